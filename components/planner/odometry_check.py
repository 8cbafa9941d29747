"""Do the fixes agree with the odometry? A bearing-drift check for encoder faults.

The planner integrates its pose from the measured wheel speeds only. An encoder that loses
counts makes the wheel loop hold the *measured* speed, so the wheel really turns faster than
the odometry says and the robot yaws without knowing it. The fixes are a second, independent
measurement of the robot's motion relative to the source: between two accepted fixes, the
odometry predicts where the previous fix's target should now appear; a source that moves at
most ``max_target_speed`` can only add a bounded bearing change to that prediction.

Bound on ``|bearing_measured - bearing_predicted|`` for the fix pair (t0, t1), ``dt = t1 - t0``,
``D`` the smaller of the measured and predicted distance at t1 (docs/faults.md):

- the source's own motion: ``asin(min(1, max_target_speed * (dt + h) / D))`` (a point that
  moved by ``d`` subtends at most ``asin(d / D)`` from a point ``D`` away; ``h`` the planner
  step, by which the time between the fixes may exceed the time between taking them);
- the fixes' bearing error: ``2 * bearing_noise`` (one per fix, worst case opposite signs);
- the fix's age when the planner takes it (up to one planner step, during which the odometry
  moved): the heading change plus the travel over ``D`` of the step each fix arrived in;
- the odometry's own resolution: one encoder count per wheel over the track width
  (:data:`ODOMETRY_COUNTS`), far below the rest for the paper's robot.

A discrepancy beyond the bound, in the same direction, on :data:`TRIPS_AFTER` accepted fixes in
a row declares the odometry inconsistent. One wrong fix that passes the planner's gate gives
two large discrepancies of opposite signs (into and out of it), so it cannot trip the check.
Range is not compared: the localizer's range error reaches 0.14 m near the array's edge, ten
times the 15 mm per fix that a wheel at twice its measured speed adds.
"""

import math

__all__ = ["OdometryCheck", "TRIPS_AFTER", "ODOMETRY_COUNTS", "COUNT_LENGTH"]

# Consecutive same-direction exceedances that declare the odometry inconsistent (see above).
TRIPS_AFTER = 3
# Odometry resolution allowance: this many encoder counts per wheel, of COUNT_LENGTH each
# (2 pi 0.06 m / 728 counts = 0.52 mm), over the track width.
ODOMETRY_COUNTS = 2
COUNT_LENGTH = 2.0 * math.pi * 0.06 / 728


class OdometryCheck:
    """Compare the bearing change between accepted fixes with the odometry's prediction.

    Parameters
    ----------
    max_target_speed : float
        Largest speed of the source [m/s] (the planner's gate parameter).
    bearing_noise : float
        Largest bearing error of one fix the localizer lets through [rad].
    track_width : float
        Distance between the wheels [m].

    Attributes
    ----------
    in_row : int
        Exceedances in a row, in the direction :attr:`direction`.
    last_discrepancy, last_bound : float
        Of the latest fix pair [rad] (0 before the second fix).
    """

    def __init__(self, max_target_speed, bearing_noise, track_width):
        self.max_target_speed = float(max_target_speed)
        self.bearing_noise = float(bearing_noise)
        self.resolution = ODOMETRY_COUNTS * COUNT_LENGTH / float(track_width)
        self.previous = None   # (time, target_x, target_y, age allowance [rad m, m])
        self.in_row = 0
        self.direction = 0.0
        self.last_discrepancy = 0.0
        self.last_bound = 0.0

    def reset_count(self):
        """Forget the exceedances in a row (after the planner reacted to a trip)."""
        self.in_row = 0
        self.direction = 0.0

    def observe(self, time, target_x, target_y, distance, bearing, odometry, step_turn,
                step_travel, step_size):
        """Take an accepted fix; return True when the odometry is declared inconsistent.

        Parameters
        ----------
        time : float
            Time the planner took the fix [s].
        target_x, target_y : float
            The fix's target in the odometry frame [m] (from the current pose).
        distance, bearing : float
            The fix [m, rad].
        odometry : Odometry
            The planner's pose now.
        step_turn, step_travel : float
            |Heading change| [rad] and |travel| [m] of the odometry over the step just taken
            (the fix may be up to that old).
        step_size : float
            The planner's step [s]: the time between the two fixes may exceed the time
            between taking them by up to one step.
        """
        previous = self.previous
        self.previous = (float(time), target_x, target_y, step_turn, step_travel)
        if previous is None:
            return False
        time0, x0, y0, turn0, travel0 = previous
        predicted_distance, predicted_bearing = odometry.polar_of(x0, y0)
        discrepancy = math.remainder(bearing - predicted_bearing, 2.0 * math.pi)
        near = min(distance, predicted_distance)
        if near <= 0.0:
            # at the source: any bearing is possible
            self.last_discrepancy, self.last_bound = discrepancy, math.pi
            self.reset_count()
            return False
        moved = self.max_target_speed * (time - time0 + step_size)
        bound = (math.asin(min(1.0, moved / near)) + 2.0 * self.bearing_noise
                 + turn0 + step_turn + (travel0 + step_travel) / near + self.resolution)
        self.last_discrepancy, self.last_bound = discrepancy, bound
        if abs(discrepancy) <= bound:
            self.reset_count()
            return False
        direction = math.copysign(1.0, discrepancy)
        if direction != self.direction:
            self.in_row = 0
            self.direction = direction
        self.in_row += 1
        if self.in_row >= TRIPS_AFTER:
            self.reset_count()
            return True
        return False
