"""The planner drives an ideal kinematic robot, integrated here, to the target.

The robot in these tests is independent of the planner's odometry: unicycle kinematics
integrated with RK4 at a fine step from the held reference wheel speeds; its wheel speeds
(equal to the references, as for a perfect speed loop) are fed back as the measurement.
"""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from components.planner import IDLE, MODES, MOVING, STOPPING, TURNING, TargetPlanner

STEP = 0.02
SUBSTEPS = 4


class IdealRobot:
    """Unicycle in the world frame, starting at (0, 0) facing +y."""

    def __init__(self, track_width):
        self.track_width = track_width
        self.x, self.y, self.heading = 0.0, 0.0, math.pi / 2

    def _rates(self, heading, speed, turn_rate):
        return speed * math.cos(heading), speed * math.sin(heading), turn_rate

    def drive(self, left, right, duration):
        speed, turn_rate = 0.5 * (left + right), (right - left) / self.track_width
        dt = duration / SUBSTEPS
        for _ in range(SUBSTEPS):
            k1 = self._rates(self.heading, speed, turn_rate)
            k2 = self._rates(self.heading + 0.5 * dt * k1[2], speed, turn_rate)
            k3 = self._rates(self.heading + 0.5 * dt * k2[2], speed, turn_rate)
            k4 = self._rates(self.heading + dt * k3[2], speed, turn_rate)
            self.x += dt / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            self.y += dt / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
            self.heading += dt * turn_rate


def world_point(distance, bearing, x=0.0, y=0.0, heading=math.pi / 2):
    return x + distance * math.cos(heading + bearing), y + distance * math.sin(heading + bearing)


def run(planner, fixes, duration, track_width, step=STEP, stop_when_idle=True):
    """Close the loop; ``fixes(k, robot)`` returns (measurement_id, valid, distance, bearing)."""
    robot = IdealRobot(track_width)
    left = right = 0.0
    trace = []
    for k in range(int(round(duration / step))):
        fix = fixes(k, robot)
        left, right = planner.update(k * step, step, left, right, *fix)
        trace.append((left, right, planner.radius, planner.state))
        robot.drive(left, right, step)
        settled = k > 10 and all(row[3] == IDLE for row in trace[-10:])
        if stop_when_idle and settled and planner.has_target:
            break
    return robot, trace


@pytest.mark.parametrize("mode", sorted(MODES), ids=sorted(MODES))
@pytest.mark.parametrize("bearing_deg", [-80, -45, 0, 30, 80], ids=lambda b: f"{b}deg")
def test_ideal_robot_ends_within_1mm_of_a_static_target(mode, bearing_deg):
    track, distance, bearing = 0.289, 2.0, math.radians(bearing_deg)
    planner = TargetPlanner(track_width=track, v_cruise=0.3, stop_distance=0.0, mode=mode)
    robot, trace = run(planner, lambda k, r: (1, True, distance, bearing), 30.0, track)
    target = world_point(distance, bearing)
    assert math.hypot(robot.x - target[0], robot.y - target[1]) < 1e-3
    assert trace[-1][3] == IDLE and trace[-1][:2] == (0.0, 0.0)


@pytest.mark.parametrize("mode", sorted(MODES), ids=sorted(MODES))
def test_robot_stops_at_stop_distance_from_the_target(mode):
    track, distance, bearing, stop = 0.289, 2.5, math.radians(-30), 0.5
    planner = TargetPlanner(track_width=track, stop_distance=stop, mode=mode)
    robot, _ = run(planner, lambda k, r: (7, True, distance, bearing), 30.0, track)
    target = world_point(distance, bearing)
    assert math.hypot(robot.x - target[0], robot.y - target[1]) == pytest.approx(stop, abs=1e-3)


def test_curvature_mode_holds_the_wheel_ratio_while_accelerating_and_braking():
    track, distance, bearing = 0.40, 2.0, -math.pi / 4
    planner = TargetPlanner(track_width=track, v_cruise=0.3, stop_distance=0.0)
    _, trace = run(planner, lambda k, r: (1, True, distance, bearing), 15.0, track)
    expected = (1 + track / 2 / math.sqrt(2)) / (1 - track / 2 / math.sqrt(2))  # Eqs. (41)/(42)
    ratios = [left / right for left, right, _, _ in trace if right > 0.0]
    assert len(ratios) > 100
    assert max(abs(r - expected) for r in ratios) < 1e-12
    # One trapezoid: every moving step (accelerate, cruise) comes before every braking step.
    states = [row[3] for row in trace]
    last_moving = max(k for k, state in enumerate(states) if state == MOVING)
    assert last_moving < states.index(STOPPING)


def test_table6_accelerations_with_the_papers_one_second_ramp():
    # Sec. 4.2.2: each speed change takes 1 s, so Table 6 prints accelerations equal to the
    # speeds. A 1 s ramp of the outer wheel to 0.342 m/s is a_max = 0.342 m/s^2.
    track, speed = 0.40, 0.3
    outer = speed * (1 + track / 2 / math.sqrt(2))
    planner = TargetPlanner(track_width=track, v_cruise=speed, a_max=outer, stop_distance=0.0)
    _, trace = run(planner, lambda k, r: (1, True, 2.0, -math.pi / 4), 12.0, track, step=0.01)
    left = [0.0] + [row[0] for row in trace]
    right = [0.0] + [row[1] for row in trace]
    assert max(b - a for a, b in zip(left, left[1:])) / 0.01 == pytest.approx(0.342, rel=0.01)
    assert max(b - a for a, b in zip(right, right[1:])) / 0.01 == pytest.approx(0.258, rel=0.01)
    assert left.index(max(left)) * 0.01 == pytest.approx(1.0, abs=0.011)


def test_case2_replan_keeps_radius_0707_per_segment_and_continuous_speeds():
    # Table 7: 1 m at 45 deg right, then (while moving) 1 m at 45 deg left, V = 0.3 m/s.
    track, a_max, switch = 0.40, 0.4, 100
    planner = TargetPlanner(track_width=track, v_cruise=0.3, a_max=a_max, stop_distance=0.0)

    def fixes(k, robot):
        return (1, True, 1.0, -math.pi / 4) if k < switch else (2, True, 1.0, math.pi / 4)

    robot, trace = run(planner, fixes, 20.0, track)
    assert trace[0][2] == pytest.approx(0.707, rel=1e-3)
    assert trace[switch][2] == pytest.approx(0.707, rel=1e-3)
    assert trace[switch - 1][0] == pytest.approx(0.384, rel=0.01)   # segment 1 cruise, left
    assert trace[switch - 1][1] == pytest.approx(0.216, rel=0.01)
    previous = (0.0, 0.0)
    for left, right, _, _ in trace:
        assert abs(left - previous[0]) <= a_max * STEP * (1 + 1e-9)
        assert abs(right - previous[1]) <= a_max * STEP * (1 + 1e-9)
        previous = (left, right)
    # After the blend the arc is re-planned from odometry, so the robot still reaches the
    # second target (seen from its pose at the switch).
    robot_at_switch, _ = run(TargetPlanner(track_width=track, v_cruise=0.3, a_max=a_max,
                                           stop_distance=0.0),
                             lambda k, r: (1, True, 1.0, -math.pi / 4), switch * STEP, track)
    target = world_point(1.0, math.pi / 4, robot_at_switch.x, robot_at_switch.y,
                         robot_at_switch.heading)
    assert math.hypot(robot.x - target[0], robot.y - target[1]) < 1e-3


def test_rotate_then_go_turns_in_place_before_driving():
    track = 0.289
    planner = TargetPlanner(track_width=track, stop_distance=0.0, mode="rotate_then_go")
    _, trace = run(planner, lambda k, r: (1, True, 1.5, math.radians(60)), 20.0, track)
    turning = [row for row in trace if row[3] == TURNING]
    assert all(left == -right and right >= 0.0 for left, right, *_ in turning)
    # 60 deg on the spot: each wheel rolls |beta| L / 2, too short to reach 0.3 m/s, so the
    # peak is the triangle's sqrt(a_max * length), to within one sampled acceleration step.
    peak = math.sqrt(0.4 * math.radians(60) * track / 2)
    assert max(right for _, right, *_ in turning) == pytest.approx(peak, abs=0.4 * STEP)
    assert all(row[2] == 0.0 for row in turning)


def test_invalid_and_negative_fixes_are_ignored():
    planner = TargetPlanner(stop_distance=0.0)
    planner.update(0.0, STEP, 0.0, 0.0, 1, False, 2.0, 0.3)
    assert planner.fix_outcome == "invalid" and not planner.has_target
    planner.update(STEP, STEP, 0.0, 0.0, 2, True, -1.0, 0.3)
    assert planner.fix_outcome == "negative" and not planner.has_target
    assert planner.state == IDLE and (planner.v_ref_left, planner.v_ref_right) == (0.0, 0.0)


@pytest.mark.parametrize("port, fix, speeds", [
    ("distance", (1, True, math.nan, 0.1), (0.0, 0.0)),
    ("bearing", (1, True, 1.0, math.inf), (0.0, 0.0)),
    ("wheel_speed_left", (1, True, 1.0, 0.1), (math.nan, 0.0)),
    ("bearing", (1, True, 1.0, 4.0), (0.0, 0.0))],
    ids=["nan-distance", "inf-bearing", "nan-wheel", "bearing-out-of-range"])
def test_non_finite_inputs_raise_an_error_naming_the_port(port, fix, speeds):
    from components.common.errors import InputError
    with pytest.raises(InputError, match=port):
        TargetPlanner().update(0.0, STEP, *speeds, *fix)


def test_unknown_mode_lists_the_valid_ones():
    from components.common.errors import ParameterError
    with pytest.raises(ParameterError, match="pure_pursuit"):
        TargetPlanner(mode="spiral")


@settings(max_examples=60, deadline=None)
@given(mode=st.sampled_from(sorted(MODES)),
       fixes=st.lists(st.tuples(st.integers(0, 150), st.floats(0.0, 4.0),
                                st.floats(-1.55, 1.55)), min_size=1, max_size=4),
       stop=st.sampled_from([0.0, 0.5]), track=st.sampled_from([0.289, 0.40]),
       step=st.sampled_from([0.02, 0.05]))
def test_speed_and_acceleration_limits_hold_at_every_step(mode, fixes, stop, track, step):
    v_max, a_max = 0.4, 0.4
    planner = TargetPlanner(track_width=track, v_cruise=0.3, v_max=v_max, a_max=a_max,
                            stop_distance=stop, mode=mode)
    schedule = sorted(fixes)

    def fix_at(k, robot):
        current = (0, False, 0.0, 0.0)
        for number, (start, distance, bearing) in enumerate(schedule, start=1):
            if k >= start:
                current = (number, True, distance, bearing)
        return current

    _, trace = run(planner, fix_at, 8.0, track, step, stop_when_idle=False)
    previous = (0.0, 0.0)
    for left, right, *_ in trace:
        assert abs(left) <= v_max * (1 + 1e-12) and abs(right) <= v_max * (1 + 1e-12)
        assert abs(left - previous[0]) <= a_max * step * (1 + 1e-9)
        assert abs(right - previous[1]) <= a_max * step * (1 + 1e-9)
        previous = (left, right)


@pytest.mark.parametrize("mode", sorted(MODES), ids=sorted(MODES))
@pytest.mark.parametrize("distance", [5e-324, 2.2e-309, 1e-12], ids=["min-subnormal", "subnormal", "1e-12"])
def test_a_fix_nearer_than_anything_measurable_stops_with_finite_speeds(mode, distance):
    # Found by hypothesis: in curvature mode 2 sin(theta) / D overflowed to inf and the wheel
    # speeds became NaN for a subnormal distance.
    planner = TargetPlanner(track_width=0.289, v_cruise=0.3, v_max=0.4, a_max=0.4,
                            stop_distance=0.0, mode=mode)
    _, trace = run(planner, lambda k, robot: (1, True, distance, 0.5), 2.0, 0.289, 0.02,
                   stop_when_idle=False)
    assert all(math.isfinite(value) for row in trace for value in row[:2])
    assert trace[-1][0] == 0.0 and trace[-1][1] == 0.0
