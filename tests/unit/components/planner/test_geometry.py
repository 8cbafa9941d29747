"""Arc geometry of Eqs. (36)-(42) against independent geometry and the paper's Table 6."""

import math

import numpy as np
import pytest

from components.planner import (RADIUS_STRAIGHT, arc_curvature, arc_length, radius_of,
                                stop_arc_length, wheel_arc_lengths, wheel_factors)

# Table 6 of the paper (2 m at 45 deg right, V = 0.3 m/s), as printed.
TABLE6 = {"radius": 1.414, "v_left": 0.342, "v_right": 0.258, "s_left": 2.528, "s_right": 1.9}


def circle_through(distance, bearing):
    """Centre and radius of the circle tangent to +y at the origin through the target.

    Independent construction: the centre lies on the x axis at (c, 0); equal distances to the
    origin and to the target fix c.
    """
    tx = distance * math.cos(math.pi / 2 + bearing)
    ty = distance * math.sin(math.pi / 2 + bearing)
    c = (tx * tx + ty * ty) / (2.0 * tx)
    return c, abs(c)


@pytest.mark.parametrize("distance, bearing_deg", [(2.0, -45.0), (1.0, 45.0), (3.0, 10.0),
                                                   (0.7, -80.0), (1.5, 89.0)],
                         ids=["2m-right45", "1m-left45", "3m-left10", "0.7m-right80",
                              "1.5m-left89"])
def test_curvature_and_arc_length_match_circle_construction(distance, bearing_deg):
    bearing = math.radians(bearing_deg)
    centre, radius = circle_through(distance, bearing)
    kappa = arc_curvature(distance, bearing)
    assert 1.0 / abs(kappa) == pytest.approx(radius, rel=1e-12)
    # Left turns have their centre on the left (negative x for a robot facing +y).
    assert math.copysign(1.0, kappa) == -math.copysign(1.0, centre)
    # Swept angle from the start point to the target, measured about the centre.
    tx, ty = distance * math.cos(math.pi / 2 + bearing), distance * math.sin(math.pi / 2 + bearing)
    start_angle = math.atan2(0.0, -centre)
    end_angle = math.atan2(ty, tx - centre)
    swept = abs(math.atan2(math.sin(end_angle - start_angle), math.cos(end_angle - start_angle)))
    assert arc_length(distance, bearing) == pytest.approx(radius * swept, rel=1e-12)


def test_straight_ahead_has_zero_curvature_and_the_sentinel_radius():
    assert arc_curvature(2.0, 0.0) == 0.0
    assert arc_length(2.0, 0.0) == 2.0
    assert radius_of(0.0) == RADIUS_STRAIGHT
    assert arc_length(2.0, 1e-8) == pytest.approx(2.0, abs=1e-15)


@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["left", "right"])
def test_target_at_the_side_gives_the_semicircle(sign):
    distance = 1.2
    assert radius_of(arc_curvature(distance, sign * math.pi / 2)) == pytest.approx(distance / 2)
    assert arc_length(distance, sign * math.pi / 2) == pytest.approx(math.pi * distance / 2)


@pytest.mark.parametrize("distance, bearing_deg, stop", [(2.0, -45.0, 0.5), (2.0, 0.0, 0.5),
                                                          (1.0, 80.0, 0.3), (2.0, 30.0, 0.0)],
                         ids=["right45", "straight", "left80", "no-stop"])
def test_stop_arc_ends_at_the_stop_distance(distance, bearing_deg, stop):
    bearing = math.radians(bearing_deg)
    kappa = arc_curvature(distance, bearing)
    driven = arc_length(distance, bearing) - stop_arc_length(kappa, stop)
    # Walk the arc numerically (independent of the closed form) and measure the gap.
    n = 200000
    ds = driven / n
    headings = math.pi / 2 + kappa * (np.arange(n) + 0.5) * ds
    x = float(np.sum(np.cos(headings)) * ds)
    y = float(np.sum(np.sin(headings)) * ds)
    tx, ty = distance * math.cos(math.pi / 2 + bearing), distance * math.sin(math.pi / 2 + bearing)
    assert math.hypot(tx - x, ty - y) == pytest.approx(stop, abs=1e-6)


def test_table6_radius_speeds_and_wheel_distances_with_track_width_040():
    distance, bearing, speed, track = 2.0, -math.pi / 4, 0.3, 0.40
    kappa = arc_curvature(distance, bearing)
    factor_left, factor_right = wheel_factors(kappa, track)
    s_left, s_right = wheel_arc_lengths(kappa, arc_length(distance, bearing), track)
    assert radius_of(kappa) == pytest.approx(TABLE6["radius"], rel=0.01)
    assert factor_left * speed == pytest.approx(TABLE6["v_left"], rel=0.01)
    assert factor_right * speed == pytest.approx(TABLE6["v_right"], rel=0.01)
    assert s_left == pytest.approx(TABLE6["s_left"], rel=0.01)
    assert s_right == pytest.approx(TABLE6["s_right"], rel=0.01)


def test_wheel_factors_reproduce_eq40_radius():
    # Eq. (40): R = (L/2) (v_R + v_L) / (v_R - v_L), an independent statement of the same ratio.
    track = 0.289
    for kappa in (-2.0, -0.5, 0.3, 1.7):
        factor_left, factor_right = wheel_factors(kappa, track)
        radius = track / 2 * (factor_right + factor_left) / (factor_right - factor_left)
        assert radius == pytest.approx(1.0 / kappa, rel=1e-12)
