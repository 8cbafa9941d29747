"""Exact geometry and the position estimators, against delays computed from mic positions."""

import math

import numpy as np
import pytest

from components.acoustics import (ESTIMATORS, ExactNearField, PaperEq4, PositionEstimator,
                                  exact_tdoas, far_field_pair_bearings, make_estimator,
                                  microphone_positions, register_estimator, robot_polar,
                                  source_in_array_frame)
from components.common.errors import InputError, ParameterError

SPACING, SOUND = 0.4, 340.0

CASES = [(2.0, 0.0), (2.0, math.radians(30)), (1.0, math.radians(-60)), (3.0, math.radians(60)),
         (0.5, math.radians(80)), (4.0, math.radians(-5))]
CASE_IDS = ["2m_broadside", "2m_left30", "1m_right60", "3m_left60", "0.5m_left80", "4m_right5"]


def delays_from_positions(distance, bearing, heading=1.234, robot=(0.7, -1.1), offset=0.15):
    """tdoa_12, tdoa_23 from world positions of the mics and the source (no formula shared)."""
    mics = microphone_positions(robot[0], robot[1], heading, SPACING, offset)
    centre = mics[1]
    direction = heading + bearing
    source = centre + distance * np.array([math.cos(direction), math.sin(direction)])
    ranges = np.hypot(*(source - mics).T)
    return (ranges[0] - ranges[1]) / SOUND, (ranges[2] - ranges[1]) / SOUND, source


@pytest.mark.parametrize("distance, bearing", CASES, ids=CASE_IDS)
def test_exact_delays_recover_distance_and_bearing(distance, bearing):
    tdoa_12, tdoa_23, _ = delays_from_positions(distance, bearing)
    location = ExactNearField(SPACING, SOUND).locate(tdoa_12, tdoa_23)
    assert bool(location.consistent)
    assert float(location.distance) == pytest.approx(distance, abs=1e-9)
    assert float(location.bearing) == pytest.approx(bearing, abs=1e-9)


@pytest.mark.parametrize("distance, bearing", CASES, ids=CASE_IDS)
def test_exact_tdoas_match_world_geometry(distance, bearing):
    tdoa_12, tdoa_23, _ = delays_from_positions(distance, bearing)
    model_12, model_23 = exact_tdoas(distance, bearing, SPACING, SOUND)
    assert float(model_12) == pytest.approx(tdoa_12, abs=1e-15)
    assert float(model_23) == pytest.approx(tdoa_23, abs=1e-15)


def test_mic_layout_left_to_right_and_array_frame():
    # Facing +y from the origin: M1 is on the left (-x), M3 on the right (+x).
    mics = microphone_positions(0.0, 0.0, math.pi / 2, 0.4, 0.1)
    np.testing.assert_allclose(mics, [[-0.4, 0.1], [0.0, 0.1], [0.4, 0.1]], atol=1e-15)
    forward, left = source_in_array_frame(-1.0, 1.1, 0.0, 0.0, math.pi / 2, 0.1)
    assert (forward, left) == pytest.approx((1.0, 1.0), abs=1e-15)


def test_robot_polar_moves_fix_to_reference_point():
    # Source 1 m straight left of an array mounted 0.3 m ahead: from the axle it is at
    # (0.3, 1.0) in the robot frame.
    distance, bearing = robot_polar(1.0, math.pi / 2, 0.3)
    assert distance == pytest.approx(math.hypot(0.3, 1.0), abs=1e-15)
    assert bearing == pytest.approx(math.atan2(1.0, 0.3), abs=1e-15)


def test_paper_eq4_errata_value():
    # docs/errata.md: the printed Eq. (4) gives 1.19 m for a source 2 m away at 45 deg.
    tdoa_12, tdoa_23 = exact_tdoas(2.0, math.radians(45), SPACING, SOUND)
    location = PaperEq4(SPACING, SOUND).locate(tdoa_12, tdoa_23)
    assert float(location.distance) == pytest.approx(1.19, abs=0.005)


def test_far_field_single_pair_bias_at_2m():
    # Broadside at 2 m: R1 - R2 = sqrt(4 + 0.16) - 2, so Eq. (5-a) alone reads
    # acos((sqrt(4.16) - 2) / 0.4) - 90 deg = -5.6 deg instead of 0.
    a = math.sqrt(4.16) - 2.0
    left, right = far_field_pair_bearings(a, a, SPACING)
    expected = math.degrees(math.acos(a / SPACING)) - 90.0
    assert math.degrees(float(left)) == pytest.approx(expected, abs=1e-12)
    assert math.degrees(float(right)) == pytest.approx(-expected, abs=1e-12)
    assert abs(expected) > 5.0


@pytest.mark.parametrize("tdoa_12, tdoa_23", [
    (0.5e-3, -0.6e-3),          # a + b < 0: wavefront curving the wrong way
    (1.3e-3, 0.1e-3),           # |a| > l: impossible for adjacent microphones
    (-1.1e-3, 1.1e-3 * 0.999),  # |sin(bearing)| > 1
], ids=["negative_sum", "beyond_spacing", "sine_above_one"])
def test_inconsistent_delays_are_flagged(tdoa_12, tdoa_23):
    location = ExactNearField(SPACING, SOUND).locate(tdoa_12, tdoa_23)
    assert not bool(location.consistent)
    assert math.isnan(float(location.distance))


def test_non_finite_delay_names_the_port():
    with pytest.raises(InputError, match=r"tdoa_23 = nan"):
        ExactNearField(SPACING, SOUND).locate(1e-5, float("nan"))


def test_registry_lists_choices_and_accepts_plugins():
    with pytest.raises(ParameterError, match="valid choices: exact, far_field, paper"):
        make_estimator("music", SPACING, SOUND)

    class Broadside(PositionEstimator):
        name = "test_broadside"

        def _compute(self, a, b):
            return np.full_like(a, 2.0), np.zeros_like(a), np.ones_like(a, dtype=bool)

    try:
        register_estimator(Broadside)
        location = make_estimator("test_broadside", SPACING, SOUND).locate(0.0, 0.0)
        assert float(location.distance) == 2.0
        # Validation is the base class's: an impossible delay is inconsistent for any plugin.
        assert not bool(make_estimator("test_broadside", SPACING, SOUND).locate(2e-3, 0.0).consistent)
    finally:
        ESTIMATORS.pop("test_broadside", None)
