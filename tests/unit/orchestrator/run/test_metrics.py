"""Tracking figures over row chunks, and the one point-to-polyline distance, against geometry.

The references: the distance from a point to a segment one scalar at a time, figures of
hand-made runs whose distances are known exactly, and the figures' definition written out on
whole arrays (which the two-pass chunked computation must reproduce bit for bit).
"""

import math

import numpy as np
import pytest

from orchestrator.run.metrics import distance_to_polyline, source_distance, tracking_summary
from orchestrator.run.recorder import Recorder
from orchestrator.run.summary import ResultRows, RowTrace

POSITIONS = ["plant.x", "plant.y", "source.x", "source.y"]


# ----- the polyline distance ----------------------------------------------------------------

def _segment_distance(px, py, ax, ay, bx, by):
    """Distance from a point to a segment, one scalar at a time (the reference)."""
    ux, uy = bx - ax, by - ay
    length2 = ux * ux + uy * uy
    s = 0.0 if length2 == 0 else min(1.0, max(0.0, ((px - ax) * ux + (py - ay) * uy) / length2))
    return math.hypot(px - (ax + s * ux), py - (ay + s * uy))


def test_distance_to_polyline_against_scalar_geometry():
    rng = np.random.default_rng(3)
    polyline = np.cumsum(rng.normal(size=(60, 2)), axis=0)
    polyline[20] = polyline[19]   # a repeated vertex: a segment of length zero
    points = rng.normal(size=(1100, 2)) * 5   # more than two blocks of 512 points
    ours = distance_to_polyline(points, polyline)
    reference = [min(_segment_distance(*p, *a, *b) for a, b in zip(polyline[:-1], polyline[1:]))
                 for p in points]
    assert np.allclose(ours, reference, rtol=1e-12, atol=1e-12)
    # exact cases: beside a segment, past its end, on a vertex
    line = np.array([[-1.0, 0.0], [1.0, 0.0], [1.0, 2.0]])
    assert distance_to_polyline([[0.0, 1.5], [4.0, 6.0], [1.0, 2.0]], line).tolist() == [
        1.0, 5.0, 0.0]


def test_distance_to_a_single_vertex_and_of_no_points():
    assert distance_to_polyline([[3.0, 4.0], [0.0, -2.0]], [[0.0, 0.0]]).tolist() == [5.0, 2.0]
    assert distance_to_polyline([1.0, 1.0], [[4.0, 5.0]]).tolist() == [5.0]   # one flat point
    assert distance_to_polyline([[1.0, 2.0]], [0.0, 0.0, 3.0, 0.0]).tolist() == [2.0]  # flat
    assert distance_to_polyline(np.zeros((0, 2)), [[0.0, 0.0], [1.0, 0.0]]).shape == (0,)


def test_source_distance_is_the_euclidean_distance():
    chunk = {"plant.x": np.array([0.0, 1.0]), "plant.y": np.array([0.0, 1.0]),
             "source.x": np.array([3.0, 1.0]), "source.y": np.array([4.0, -1.0])}
    assert source_distance(chunk).tolist() == [5.0, 2.0]


# ----- tracking figures --------------------------------------------------------------------

def _record(path, robot, source):
    """The rows to results.csv (as a run writes them) and into a RowTrace (as it keeps them)."""
    trace = RowTrace(POSITIONS, len(robot))
    with Recorder(path, POSITIONS) as recorder:
        for k, (r, s) in enumerate(zip(robot, source)):
            row = [float(r[0]), float(r[1]), float(s[0]), float(s[1])]
            recorder.record(k * 0.02, row)
            trace.append(k * 0.02, row)
    return trace


def _definition(robot, source, stop_distance):
    """The tracking figures as defined, on whole arrays (thinned as tracking_summary does)."""
    distance = np.hypot(*(robot - source).T)
    moved = np.hypot(*(robot - robot[0]).T) > 1e-3
    on_path = robot[moved] if moved.any() else robot[-1:]
    on_path = on_path[::max(1, len(on_path) // 3000)]
    path = source[::max(1, len(source) // 500)]
    if not np.array_equal(path[-1], source[-1]):
        path = np.vstack([path, source[-1:]])
    path = np.vstack([robot[:1], path])
    deviation = distance_to_polyline(on_path, path)
    return {"final_distance_to_source_m": float(distance[-1]),
            "final_position_error_m": float(abs(distance[-1] - stop_distance)),
            "min_distance_to_source_m": float(distance.min()),
            "path_rmse_m": float(np.sqrt(np.mean(deviation ** 2)))}


def test_figures_are_their_definition_whatever_the_chunks(tmp_path):
    """Two passes over chunks give the whole-array figures bit for bit, from the kept rows
    (one chunk) and from the file at any chunk size, on a run long enough to be thinned
    (12,000 rows: 3,000 robot points and 500 path vertices are kept)."""
    rng = np.random.default_rng(7)
    n = 12_000
    t = np.arange(n) * 0.02
    source = np.column_stack([0.5 * np.sin(t / 20.0), 2.0 + 0.05 * t])
    robot = source - np.column_stack([np.zeros(n), np.full(n, 0.5)])
    robot += rng.normal(scale=0.01, size=robot.shape)
    robot[:40] = 0.0  # standing still at first
    trace = _record(tmp_path / "r.csv", robot, source)
    expected = _definition(robot, source, 0.5)
    assert tracking_summary(trace, 0.5) == expected
    for chunk_rows in (1, 333, 4096, 100_000):
        assert tracking_summary(ResultRows(tmp_path / "r.csv", chunk_rows), 0.5) == expected


def test_figures_against_geometry(tmp_path):
    """A robot 0.1 m beside a straight source path, 1 m behind the source: path RMS 0.1 m."""
    n = 5001
    y = np.linspace(0.0, 10.0, n)
    source = np.column_stack([np.zeros(n), y + 2.0])
    robot = np.column_stack([np.full(n, 0.1), y + 1.0])
    # the start lies on the source's line, so the reference path (start, then the source's
    # path) is the line x = 0 and every later robot point is 0.1 m from it
    robot[0] = (0.0, -5.0)
    trace = _record(tmp_path / "r.csv", robot, source)
    figures = tracking_summary(ResultRows(tmp_path / "r.csv", chunk_rows=512), 0.5)
    assert figures["path_rmse_m"] == pytest.approx(0.1, abs=1e-12)
    assert figures == tracking_summary(trace, 0.5)
    assert figures["final_distance_to_source_m"] == pytest.approx(np.hypot(0.1, 1.0), 1e-12)
    assert figures["min_distance_to_source_m"] == pytest.approx(np.hypot(0.1, 1.0), 1e-12)
    assert figures["final_position_error_m"] == pytest.approx(np.hypot(0.1, 1.0) - 0.5, 1e-12)


def test_a_robot_that_never_moves(tmp_path):
    """Its path deviation is that of its start, which begins the reference path: zero; the
    source walks from 3 m to 5 m away along y, so the closest is 3 m and the last 5 m."""
    n = 300
    source = np.column_stack([np.zeros(n), np.linspace(3.0, 5.0, n)])
    robot = np.zeros((n, 2))
    trace = _record(tmp_path / "r.csv", robot, source)
    for rows in (trace, ResultRows(tmp_path / "r.csv", chunk_rows=64)):
        assert tracking_summary(rows, 0.5) == {
            "final_distance_to_source_m": 5.0, "final_position_error_m": 4.5,
            "min_distance_to_source_m": 3.0, "path_rmse_m": 0.0}


def test_a_position_that_is_not_finite_is_not_hidden(tmp_path):
    """A NaN position in a later chunk makes the closest distance NaN from either source (a
    running min() would skip it), so the run is then reported as not finite."""
    n = 100
    source = np.column_stack([np.zeros(n), np.full(n, 2.0)])
    robot = np.column_stack([np.zeros(n), np.linspace(0.0, 1.0, n)])
    robot[70] = np.nan
    trace = _record(tmp_path / "r.csv", robot, source)
    for rows in (trace, ResultRows(tmp_path / "r.csv", chunk_rows=16)):
        assert math.isnan(tracking_summary(rows, 0.5)["min_distance_to_source_m"])


def test_no_rows_no_figures(tmp_path):
    _record(tmp_path / "r.csv", np.zeros((0, 2)), np.zeros((0, 2)))
    assert tracking_summary(ResultRows(tmp_path / "r.csv"), 0.5) == {}
    assert tracking_summary(RowTrace(POSITIONS, 10), 0.5) == {}
