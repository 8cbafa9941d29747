"""Path geometry and run figures of orchestrator.reproduce.geometry against analytic values."""

import math

import numpy as np
import pytest

from components.common.errors import ConfigError
from orchestrator.reproduce.geometry import (Arrival, apex_offsets, arrival_at_target,
                                             arrival_time, circle_fit_radius,
                                   distance_to_polyline, path_length, path_rmse, resample_path,
                                   tangent_arc_path)


def _arc(centre, radius, start_angle, stop_angle, count=2001):
    angles = np.linspace(start_angle, stop_angle, count)
    return np.column_stack([centre[0] + radius * np.cos(angles),
                            centre[1] + radius * np.sin(angles)])


@pytest.mark.parametrize("points, expected", [
    (np.array([[0.0, 0.0], [3.0, 4.0]]), 5.0),
    (np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [1.0, 2.0]]), 3.0),
    (np.array([[1.0, 1.0]]), 0.0),
], ids=["segment", "polyline-with-repeat", "single-point"])
def test_path_length_of_polylines(points, expected):
    assert path_length(points) == pytest.approx(expected, abs=1e-12)


def test_path_length_of_a_quarter_circle():
    quarter = _arc((1.5, 0.0), 1.5, math.pi, math.pi / 2, count=20001)
    assert path_length(quarter) == pytest.approx(math.pi / 2 * 1.5, rel=1e-8)


def test_resample_path_keeps_length_and_spacing():
    points = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    samples = resample_path(points, 0.01)
    steps = np.hypot(*np.diff(samples, axis=0).T)
    assert np.allclose(steps, 0.01, atol=1e-12)
    assert np.allclose(samples[[0, -1]], [[0.0, 0.0], [1.0, 1.0]])
    with pytest.raises(ConfigError, match="spacing = 0"):
        resample_path(points, 0)


@pytest.mark.parametrize("offset", [0.0, 0.01, 0.2], ids=["on", "1cm", "20cm"])
def test_path_rmse_of_a_parallel_line_is_its_offset(offset):
    reference = np.array([[0.0, 0.0], [1.5, 1.5]])
    normal = np.array([1.0, -1.0]) / math.sqrt(2.0)
    driven = np.linspace(reference[0], reference[1], 50) + offset * normal
    assert path_rmse(driven, reference) == pytest.approx(offset, abs=1e-12)


def test_path_rmse_of_a_concentric_arc_is_the_radius_difference():
    reference = tangent_arc_path((0.0, 0.0), math.pi / 2, [(1.5, 1.5)])
    # the ideal arc has its centre at (1.5, 0) and R = 1.5; drive one 3 cm outside it
    driven = _arc((1.5, 0.0), 1.53, math.pi, math.pi / 2, count=5000)
    assert path_rmse(driven, reference) == pytest.approx(0.03, abs=1e-6)


def test_path_rmse_of_a_lateral_step_is_analytic():
    # half the path on the line, half 2 cm off it: RMS = 0.02 / sqrt(2) (the short jump
    # between the halves adds a few samples, well under a micrometre of RMS change)
    reference = np.array([[0.0, 0.0], [2.0, 0.0]])
    driven = np.vstack([np.linspace([0.0, 0.0], [1.0, 0.0], 200),
                        np.linspace([1.0, 0.02], [2.0, 0.02], 200)])
    expected = math.sqrt(0.02 ** 2 * 1.0 / 2.02 + (0.02 ** 2 / 3.0) * 0.02 / 2.02)
    assert path_rmse(driven, reference, spacing=0.0005) == pytest.approx(expected, rel=1e-3)


def test_tangent_arc_path_matches_eq36_geometry():
    path = tangent_arc_path((0.0, 0.0), math.pi / 2, [(1.5, 1.5)])
    # Eq. (36): R = D / (2 sin 45 deg) = 1.5 m, centre on the right of the start
    assert np.allclose(np.hypot(path[:, 0] - 1.5, path[:, 1]), 1.5, atol=1e-12)
    assert np.allclose(path[[0, -1]], [[0.0, 0.0], [1.5, 1.5]], atol=1e-12)
    assert path_length(path) == pytest.approx(math.pi / 2 * 1.5, rel=1e-6)


def test_tangent_arc_path_chains_case2_arcs():
    p0 = (math.sqrt(0.5), math.sqrt(0.5))
    p1 = (2 * p0[0], 2 * p0[1])
    path = tangent_arc_path((0.0, 0.0), math.pi / 2, [p0, p1])
    assert np.min(np.hypot(*(path - p0).T)) < 1e-12
    assert np.allclose(path[-1], p1, atol=1e-12)
    # two quarter circles of R = 0.707 m (the paper's Table 7 radii)
    assert path_length(path) == pytest.approx(2 * math.pi / 2 * math.sqrt(0.5), rel=1e-6)


def test_tangent_arc_path_straight_ahead_is_a_segment():
    path = tangent_arc_path((0.0, 0.0), math.pi / 2, [(0.0, 2.0)])
    assert np.allclose(path, [[0.0, 0.0], [0.0, 2.0]])


@pytest.mark.parametrize("radius", [0.707, 1.5, 20.0])
def test_circle_fit_radius_is_exact_on_a_circle(radius):
    assert circle_fit_radius(_arc((3.0, -1.0), radius, 0.2, 1.4, 300)) == pytest.approx(
        radius, rel=1e-9)


def test_circle_fit_radius_of_a_line_is_infinite():
    assert circle_fit_radius(np.linspace([0, 0], [1, 1], 20)) == math.inf


def test_arrival_time_ignores_a_one_count_dither_but_sees_motion():
    time = np.arange(0.0, 10.0, 0.02)
    x = np.minimum(time, 5.0) * 0.3                      # drives 1.5 m, at rest from 5 s
    xy = np.column_stack([x + 0.0002 * np.sin(40 * time) * (time > 5.0), np.zeros_like(x)])
    heading = np.full_like(time, math.pi / 2)
    assert arrival_time(time, xy, heading) == pytest.approx(5.0, abs=0.03)
    # a creep of 0.02 rad/s never settles inside 0.01 rad for the last second
    creeping = heading + 0.02 * np.maximum(time - 5.0, 0.0)
    assert arrival_time(time, xy, creeping) is None
    assert arrival_time(time, np.zeros((len(time), 2)), heading) == 0.0


def test_apex_offsets_signs_inside_and_outside():
    u = np.linspace(0.0, 6.0, 601)
    lateral = 0.5 * np.sin(2 * math.pi * u / 6.0)        # apexes +0.5 at u=1.5, -0.5 at 4.5
    # source along +y from (0, 1); left of +y is -x
    source = np.column_stack([-lateral, 1.0 + u])
    inside = np.column_stack([-0.8 * lateral, 1.0 + u])
    offsets = apex_offsets(source, inside)
    assert [round(a["forward_m"], 6) for a in offsets] == [1.5, 4.5]
    assert [a["inward_offset_m"] for a in offsets] == pytest.approx([0.1, 0.1])
    outside = apex_offsets(source, np.column_stack([-1.2 * lateral, 1.0 + u]))
    assert [a["inward_offset_m"] for a in outside] == pytest.approx([-0.1, -0.1])
    straight = np.column_stack([np.zeros_like(u), 1.0 + u])
    assert apex_offsets(straight, straight) == []


def test_the_studies_use_the_one_polyline_distance():
    """The path RMSE of a study and the run summary's measure a point's distance alike: a
    point 0.3 m beside an L-shaped path, one 0.5 m past its end and one at its corner."""
    from orchestrator.run import metrics

    assert distance_to_polyline is metrics.distance_to_polyline
    corner = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0]])
    assert distance_to_polyline([[1.0, 0.3], [2.0, 1.5], [2.0, 0.0]], corner).tolist() == [
        pytest.approx(0.3, abs=1e-15), 0.5, 0.0]
    # resampled every 5 mm along the line x = 0.3, the path is 0.3 m from the corner's leg
    path = np.column_stack([np.full(201, 0.3), np.linspace(-1.0, 0.0, 201)])
    assert path_rmse(path, np.array([[0.0, -1.0], [0.0, 0.0]])) == pytest.approx(0.3, abs=1e-12)


# --- arrival at a target ---------------------------------------------------------------------

DT = 0.02
TARGET = np.array([1.0, 0.0])


def _drive(positions_x):
    """A robot on the x axis at the given positions, one per 20 ms sample."""
    x = np.asarray(positions_x, dtype=float)
    return np.arange(len(x)) * DT, np.column_stack([x, np.zeros_like(x)])


def _ramp(start, stop, speed):
    count = max(2, int(round(abs(stop - start) / (speed * DT))) + 1)
    return list(np.linspace(start, stop, count))


def test_arrives_when_at_rest_within_the_tolerance():
    # 0.4 m/s to 0.98 m, then stands 2 s: arrives at the first standing sample
    path = _ramp(0.0, 0.98, 0.4)
    time, xy = _drive(path + [0.98] * 100)
    arrival = arrival_at_target(time, xy, TARGET, tolerance=0.05)
    assert arrival.arrived and arrival.time == pytest.approx(time[len(path) - 1])
    assert arrival.error == pytest.approx(0.02) and arrival.drift == pytest.approx(0.0)
    assert arrival.figures() == {"arrived": 1.0, "arrival_s": arrival.time,
                                 "error_at_arrival_m": arrival.error,
                                 "drift_after_arrival_m": 0.0}
    # stopped 0.5 m short on purpose: measured from the stop distance
    time, xy = _drive(_ramp(0.0, 0.49, 0.4) + [0.49] * 100)
    short = arrival_at_target(time, xy, TARGET, tolerance=0.05, stop_distance=0.5)
    assert short.arrived and short.error == pytest.approx(0.01)


def test_an_overshoot_that_returns_arrives_on_its_return():
    # through the target at speed to 1.2 m, brakes (0.4 m/s^2) and comes back to 1.01 m
    out = _ramp(0.0, 1.2, 0.4)
    back = [1.2 - 0.5 * 0.4 * (k * DT) ** 2 for k in range(1, 31)]     # 0.6 s of reversal
    back += _ramp(back[-1], 1.01, 0.2)[1:]
    time, xy = _drive(out + back + [1.01] * 60)
    arrival = arrival_at_target(time, xy, TARGET, tolerance=0.05)
    passed = time[np.argmin(np.abs(np.array(out) - 1.0))]
    assert arrival.arrived and arrival.time > passed + 0.5
    # within one sample of the stop (its last 4 mm step lies inside the 5 mm rest band)
    assert arrival.time == pytest.approx(time[len(out) + len(back) - 1], abs=1.01 * DT)
    assert arrival.error == pytest.approx(0.01, abs=0.0041)
    # the turn at 1.2 m (0.2 m from the target) is not rest, even in a 0.3 m tolerance
    assert arrival_at_target(time, xy, TARGET, tolerance=0.3).time == arrival.time


def test_never_arrives_when_it_stops_outside_or_keeps_moving():
    time, xy = _drive(_ramp(0.0, 0.8, 0.4) + [0.8] * 100)         # stops 20 cm short
    assert arrival_at_target(time, xy, TARGET, tolerance=0.05) == Arrival(False)
    time, xy = _drive(_ramp(0.0, 2.0, 0.4))                       # drives straight through
    assert not arrival_at_target(time, xy, TARGET, tolerance=0.05).arrived
    time, xy = _drive(_ramp(0.0, 0.99, 0.4) + [0.99] * 10)        # record ends within the hold
    assert not arrival_at_target(time, xy, TARGET, tolerance=0.05).arrived
    # turning on the spot at the target is not rest when the heading is given
    time, xy = _drive([1.0] * 100)
    assert arrival_at_target(time, xy, TARGET, heading=np.linspace(0, 3, 100)).arrived is False
    assert arrival_at_target(time, xy, TARGET, heading=np.zeros(100)).time == 0.0


def test_creep_after_arriving_is_the_drift():
    # arrives at 1.0 m, stands 1 s, then creeps at 5 mm/s for 3 s (windup): drift 15 mm
    approach = _ramp(0.0, 1.0, 0.4)
    creep = [1.0 + 0.005 * k * DT for k in range(1, 151)]
    time, xy = _drive(approach + [1.0] * 50 + creep)
    arrival = arrival_at_target(time, xy, TARGET, tolerance=0.05)
    assert arrival.arrived and arrival.time == pytest.approx(time[len(approach) - 1])
    assert arrival.error == pytest.approx(0.0, abs=1e-12)
    assert arrival.drift == pytest.approx(0.015, rel=1e-6)
