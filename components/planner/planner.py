"""The planner core: fixes in, held wheel-speed references out, in one of three modes."""

import math

from ..common.errors import InputError, ParameterError
from .curvature_mode import CurvatureMode
from .geometry import radius_of
from .limiter import limit_wheel_change
from .odometry import Odometry
from .pure_pursuit import PurePursuitMode
from .rotate_then_go import RotateThenGoMode

__all__ = ["TargetPlanner", "MODES", "IDLE", "MOVING", "STOPPING", "TURNING",
           "FIX_NONE", "FIX_ACCEPTED", "FIX_INVALID", "FIX_NEGATIVE"]

MODES = {mode.name: mode for mode in (CurvatureMode, RotateThenGoMode, PurePursuitMode)}

# Values of the ``state`` output.
IDLE, MOVING, STOPPING, TURNING = 0, 1, 2, 3

# What :meth:`TargetPlanner.update` did with the fix inputs (``fix_outcome``).
FIX_NONE = "none"
FIX_ACCEPTED = "accepted"
FIX_INVALID = "invalid"
FIX_NEGATIVE = "negative"


class TargetPlanner:
    """Wheel-speed references that drive a two-wheeled robot to the latest heard target.

    Call :meth:`update` once per planner step with the inputs at that time; it returns the
    wheel speeds to hold until the next call. A fix is new when ``measurement_id`` changes (or
    on the first call); it is used only if ``valid`` is true and the distance is not negative.
    The target is kept in the odometry frame (the start pose: (0, 0) facing +y), which the
    planner integrates from the measured wheel speeds, so it stays put while the robot moves.

    Parameters
    ----------
    track_width : float
        Distance between the wheels [m], ``L`` of Eqs. (38)-(42).
    v_cruise : float
        Cruise speed of the robot's centre [m/s], ``V`` of Eqs. (41)-(42).
    v_max : float
        Largest wheel speed [m/s] (Eq. 43).
    a_max : float
        Largest wheel acceleration [m/s^2] (Eq. 44).
    stop_distance : float
        Straight-line distance [m] from the target at which the robot stops.
    mode : str
        ``"curvature"`` (the paper), ``"rotate_then_go"`` or ``"pure_pursuit"``.
    """

    def __init__(self, track_width=0.289, v_cruise=0.3, v_max=0.4, a_max=0.4,
                 stop_distance=0.5, mode="curvature"):
        if mode not in MODES:
            raise ParameterError(f"mode = {mode!r}: not one of {sorted(MODES)}")
        for name, value in (("track_width", track_width), ("v_cruise", v_cruise),
                            ("v_max", v_max), ("a_max", a_max)):
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"{name} = {value!r}: must be a finite number > 0")
        if not (math.isfinite(stop_distance) and stop_distance >= 0.0):
            raise ParameterError(f"stop_distance = {stop_distance!r}: must be a finite number >= 0")
        self.track_width = float(track_width)
        self.v_cruise = float(v_cruise)
        self.v_max = float(v_max)
        self.a_max = float(a_max)
        self.stop_distance = float(stop_distance)
        self.mode = MODES[mode]()
        self.odometry = Odometry(track_width)
        self.has_target = False
        self.target_x = 0.0
        self.target_y = 0.0
        self.last_measurement_id = None
        self.fix_outcome = FIX_NONE
        self.started = False
        self.last_time = 0.0
        self.v_ref_left = 0.0
        self.v_ref_right = 0.0
        self.state = IDLE

    @property
    def curvature(self):
        """Signed curvature of the path being driven [1/m], left positive."""
        return self.mode.curvature

    @property
    def radius(self):
        """Radius of the path being driven [m]: 0 when turning on the spot, 1e6 when straight."""
        mode = self.mode
        return 0.0 if mode.turning else radius_of(mode.curvature)

    @property
    def arc_remaining(self):
        """Centre path length still to drive on the current plan [m]."""
        return self.mode.remaining()

    def update(self, time, step_size, wheel_speed_left, wheel_speed_right,
               measurement_id=0, valid=False, distance=0.0, bearing=0.0):
        """Take the inputs at ``time`` and return the wheel speeds to hold for ``step_size``.

        Parameters
        ----------
        time : float
            Current time [s].
        step_size : float
            Time until the next call [s], > 0.
        wheel_speed_left, wheel_speed_right : float
            Measured wheel speeds [m/s], held since the previous call.
        measurement_id : int
            Fix counter; a change marks a new fix.
        valid : bool
            Whether the fix is usable.
        distance : float
            Distance to the target [m].
        bearing : float
            Bearing of the target [rad], left positive, in [-pi, pi].

        Returns
        -------
        tuple of float
            ``(v_ref_left, v_ref_right)`` [m/s].

        Raises
        ------
        InputError
            If a wheel speed, or a valid fix's distance or bearing, is not finite, or the
            bearing is outside [-pi, pi].
        """
        measurement_id, valid = int(measurement_id), bool(valid)
        new_fix = measurement_id != self.last_measurement_id
        # Check every input before touching any state, so a refused step can be retried.
        if not (math.isfinite(wheel_speed_left) and math.isfinite(wheel_speed_right)):
            for port, value in (("wheel_speed_left", wheel_speed_left),
                                ("wheel_speed_right", wheel_speed_right)):
                if not math.isfinite(value):
                    raise InputError(f"{port} = {value!r}: must be finite")
        if new_fix and valid:
            for port, value in (("distance", distance), ("bearing", bearing)):
                if not math.isfinite(value):
                    raise InputError(f"{port} = {value!r} of fix {measurement_id}: must be finite")
            if abs(bearing) > math.pi:
                raise InputError(f"bearing = {bearing!r} of fix {measurement_id}: "
                                 "must lie in [-pi, pi] rad")
        elapsed = time - self.last_time if self.started else 0.0
        self.started = True
        self.last_time = float(time)
        self.odometry.advance(wheel_speed_left, wheel_speed_right, elapsed)
        mode = self.mode
        mode.record_progress(wheel_speed_left * elapsed, wheel_speed_right * elapsed)
        self.fix_outcome = FIX_NONE
        if new_fix:
            self._observe(measurement_id, valid, distance, bearing)

        desired_left, desired_right = mode.command(self, step_size)
        previous_left, previous_right = self.v_ref_left, self.v_ref_right
        left, right, fraction = limit_wheel_change(previous_left, previous_right,
                                                   desired_left, desired_right,
                                                   self.a_max * step_size)
        mode.after_limit(fraction)
        # The state output, classified here rather than in a helper (this runs every step).
        if left == 0.0 and right == 0.0 and previous_left == 0.0 and previous_right == 0.0:
            self.state = IDLE
        elif mode.turning:
            self.state = TURNING
        elif abs(left + right) < abs(previous_left + previous_right) - 1e-12:
            self.state = STOPPING
        else:
            self.state = MOVING
        self.v_ref_left, self.v_ref_right = left, right
        return left, right

    def _observe(self, measurement_id, valid, distance, bearing):
        self.last_measurement_id = measurement_id
        if not valid:
            self.fix_outcome = FIX_INVALID
        elif distance < 0.0:
            self.fix_outcome = FIX_NEGATIVE
        else:
            self.fix_outcome = FIX_ACCEPTED
            self.has_target = True
            self.target_x, self.target_y = self.odometry.point_at(distance, bearing)
            self.mode.on_fix(self, distance, bearing)
