"""The sampled trapezoid the planner uses lands on the end point, within its limits."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from components.common.trapezoid import braking_speed, next_speed


def drive(length, cruise, a_max, step):
    """Hold each speed for ``step``; the distance is summed independently of the profile code."""
    speeds, covered, speed = [], 0.0, 0.0
    for _ in range(100000):
        speed = next_speed(speed, cruise, length - covered, a_max, step)
        if speed == 0.0 and covered > 0.0:
            break
        speeds.append(speed)
        covered += speed * step
    return speeds, covered


@pytest.mark.parametrize("length, cruise, a_max, step", [
    (2.0, 0.3, 0.4, 0.02), (0.05, 0.3, 0.4, 0.02), (7.0, 0.2, 0.2, 0.1), (1e-4, 0.3, 0.4, 0.05),
    (3.3, 0.4, 0.4, 0.033)],
    ids=["table6-like", "triangle", "source-like", "tiny", "odd-step"])
def test_lands_on_the_end_within_limits(length, cruise, a_max, step):
    speeds, covered = drive(length, cruise, a_max, step)
    assert covered == pytest.approx(length, abs=1e-12)
    previous = 0.0
    for speed in speeds + [0.0]:
        assert 0.0 <= speed <= cruise + 1e-15
        assert abs(speed - previous) <= a_max * step * (1 + 1e-9)
        previous = speed


def test_duration_matches_continuous_trapezoid():
    # Continuous rest-to-rest trapezoid: T = L / v + v / a; sampling adds at most two steps.
    length, cruise, a_max, step = 2.0, 0.3, 0.4, 0.01
    speeds, _ = drive(length, cruise, a_max, step)
    assert len(speeds) * step == pytest.approx(length / cruise + cruise / a_max, abs=2 * step)


@settings(max_examples=200, deadline=None)
@given(remaining=st.floats(1e-9, 20.0), a_max=st.floats(0.05, 2.0), step=st.floats(0.001, 0.2))
def test_braking_staircase_covers_exactly_the_remaining_distance(remaining, a_max, step):
    speed = braking_speed(remaining, a_max, step)
    covered, v = 0.0, speed
    while v > 0.0:
        covered += v * step
        v = max(v - a_max * step, 0.0)
    assert covered == pytest.approx(remaining, rel=1e-9, abs=1e-15)


def test_overshoot_brakes_at_the_limit_instead_of_stopping_at_once():
    assert next_speed(0.3, 0.3, -0.1, 0.4, 0.1) == pytest.approx(0.26)
    assert next_speed(0.02, 0.3, -0.1, 0.4, 0.1) == 0.0
    assert math.isclose(braking_speed(0.0, 0.4, 0.1), 0.0)


@settings(max_examples=500, deadline=None)
@given(current=st.floats(-0.5, 1.0), cruise=st.floats(0.0, 1.0), a_max=st.floats(0.05, 2.0),
       step=st.floats(0.001, 0.2), scale=st.floats(0.0, 3.0), nudge=st.integers(-3, 3))
def test_next_speed_is_the_documented_min_max_exactly(current, cruise, a_max, step, scale,
                                                      nudge):
    # next_speed skips braking_speed far from the end; it must still equal, bit for bit,
    # V = max(min(cruise, V + a h, v(r)), V - a h, 0) (docs/planner.md). The remaining
    # distance is drawn around the braking distance of min(cruise, V + a h), where the
    # shortcut switches, down to a few ulps from it.
    held = min(cruise, current + a_max * step)
    remaining = scale * (held + 0.5 * a_max * step) ** 2 / (2.0 * a_max)
    for _ in range(abs(nudge)):
        remaining = math.nextafter(remaining, math.copysign(math.inf, nudge))
    expected = max(min(cruise, current + a_max * step, braking_speed(remaining, a_max, step)),
                   current - a_max * step, 0.0)
    assert next_speed(current, cruise, remaining, a_max, step) == expected
