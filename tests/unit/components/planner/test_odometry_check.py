"""The odometry check against an exactly simulated robot and source (own kinematics and geometry).

The "true" robot below integrates its pose from the true wheel speeds with its own arc
formula; the fixes are the exact distance and bearing from that pose to the source (plus a
given error); the check sees only the measured wheel speeds, through the planner's
:class:`Odometry`, as the planner does.
"""

import math

import pytest

from components.common.errors import ParameterError
from components.planner.odometry import Odometry
from components.planner.odometry_check import TRIPS_AFTER, OdometryCheck
from components.planner.planner import (ODOMETRY_RETRY, STOP_NONE, STOP_ODOMETRY,
                                        TargetPlanner)

TRACK = 0.289
STEP = 0.02          # planner step [s]
FIX_EVERY = 5        # a fix every 0.1 s


class TrueRobot:
    """Exact differential-drive kinematics (independent of the planner's Odometry)."""

    def __init__(self):
        self.x, self.y, self.heading = 0.0, 0.0, math.pi / 2

    def drive(self, left, right, duration):
        omega = (right - left) / TRACK
        speed = 0.5 * (left + right)
        if omega == 0.0:
            self.x += speed * duration * math.cos(self.heading)
            self.y += speed * duration * math.sin(self.heading)
        else:
            end = self.heading + omega * duration
            self.x += speed / omega * (math.sin(end) - math.sin(self.heading))
            self.y += speed / omega * (math.cos(self.heading) - math.cos(end))
            self.heading = end

    def fix(self, source_x, source_y):
        dx, dy = source_x - self.x, source_y - self.y
        bearing = math.atan2(dy, dx) - self.heading
        return math.hypot(dx, dy), math.atan2(math.sin(bearing), math.cos(bearing))


def run_check(check, steps, true_speeds, measured_speeds, source, bearing_error=lambda k: 0.0):
    """Drive ``steps`` planner steps; return the fix numbers at which the check tripped."""
    robot, odometry = TrueRobot(), Odometry(TRACK)
    trips = []
    for step in range(1, steps + 1):
        time = step * STEP
        left, right = true_speeds(time)
        robot.drive(left, right, STEP)
        m_left, m_right = measured_speeds(time)
        heading = odometry.heading
        odometry.advance(m_left, m_right, STEP)
        if step % FIX_EVERY:
            continue
        fix = step // FIX_EVERY
        distance, bearing = robot.fix(*source(time))
        bearing += bearing_error(fix)
        target = odometry.point_at(distance, bearing)
        if check.observe(time, *target, distance, bearing, odometry,
                         abs(odometry.heading - heading), abs(0.5 * (m_left + m_right)) * STEP,
                         STEP):
            trips.append(fix)
    return trips


def _straight(speed):
    return lambda time: (speed, speed)


@pytest.mark.parametrize("bearing_noise", [0.0, 0.01], ids=["exact fixes", "noisy fixes"])
def test_healthy_robot_and_a_source_at_max_speed_never_trip(bearing_noise):
    # worst case for the bearing: the source crosses the line of sight at max_target_speed
    check = OdometryCheck(0.2, bearing_noise, TRACK)
    def source(time):
        return 0.2 * time, 2.5
    # fix errors at the bound, alternating: the largest bearing change the noise can make
    trips = run_check(check, 500, _straight(0.3), _straight(0.3), source,
                      lambda fix: bearing_noise * (-1) ** fix)
    assert trips == []


def test_a_source_faster_than_the_bound_trips():
    # 2 x max_target_speed across the line of sight, 2 m away: 0.04 m per fix is 20 mrad,
    # above the bound's asin(0.2 * 0.12 / 2) = 12 mrad plus 3.6 mrad of odometry resolution
    check = OdometryCheck(0.2, 0.0, TRACK)
    trips = run_check(check, 200, _straight(0.0), _straight(0.0), lambda t: (0.4 * t, 2.0))
    assert trips and trips[0] == TRIPS_AFTER + 1   # the first pair is fix 1 -> 2


def test_encoder_losing_half_its_counts_trips_and_a_healthy_one_does_not():
    # the wheel loop holds the measured 0.3 m/s, so the true left wheel runs at 0.6 m/s
    source = lambda time: (0.0, 2.5)
    faulty = run_check(OdometryCheck(0.2, 0.01, TRACK), 20, lambda t: (0.6, 0.3),
                       _straight(0.3), source)
    assert faulty == [TRIPS_AFTER + 1]
    healthy = run_check(OdometryCheck(0.2, 0.01, TRACK), 20, _straight(0.3), _straight(0.3),
                        source)
    assert healthy == []


def test_one_wrong_fix_cannot_trip_it():
    # a fix 0.2 rad off (it passed the gate) makes two large discrepancies of opposite signs
    check = OdometryCheck(0.2, 0.01, TRACK)
    trips = run_check(check, 100, _straight(0.3), _straight(0.3), lambda t: (0.0, 2.5),
                      lambda fix: 0.2 if fix == 7 else 0.0)
    assert trips == []
    assert check.in_row == 0


def test_a_zero_bound_trips_on_fix_noise_alone():
    # broken threshold: no allowance for the source, the noise or the resolution
    check = OdometryCheck(0.0, 0.0, 1e12)
    trips = run_check(check, 100, _straight(0.0), _straight(0.0), lambda t: (0.0, 2.5),
                      lambda fix: 1e-4 * fix)
    assert trips


def _encoder_skip_loop(odometry_check, fault_from=1.0):
    """The planner driving a simulated robot whose left encoder loses half its counts."""
    planner = TargetPlanner(max_target_speed=0.2, odometry_check=odometry_check)
    robot, measured = TrueRobot(), (0.0, 0.0)
    log = []
    for step in range(200):
        time = step * STEP
        fix = robot.fix(0.0, 2.5)
        left, right = planner.update(time, STEP, *measured, step // FIX_EVERY + 1, True, *fix)
        keep = 0.5 if time >= fault_from else 1.0
        true_left = left / keep   # the loop holds the measured speed at the reference
        robot.drive(true_left, right, STEP)
        measured = (true_left * keep, right)
        log.append((time, left, right, planner.stop_reason, planner.odometry_faults))
    return log


def test_planner_stops_at_once_when_the_check_trips_and_retries_after_the_hold():
    log = _encoder_skip_loop(True)
    trip = next(i for i, row in enumerate(log) if row[4] == 1)
    assert 1.0 < log[trip][0] < 1.6
    assert all(row[3] == STOP_NONE for row in log[:trip])
    held = [row for row in log if log[trip][0] <= row[0] < log[trip][0] + ODOMETRY_RETRY - 1e-9]
    assert all(row[1] == 0.0 and row[2] == 0.0 and row[3] == STOP_ODOMETRY for row in held)
    after = log[trip + len(held)]
    assert after[3] == STOP_NONE and after[1] + after[2] > 0.0


def test_rule_off_never_stops():
    log = _encoder_skip_loop(False)
    assert all(row[3] == STOP_NONE and row[4] == 0 for row in log)


def test_check_needs_a_source_speed_bound():
    with pytest.raises(ParameterError, match="max_target_speed"):
        TargetPlanner(odometry_check=True)
