"""The summary's figures kept row by row (RowTrace) against the chunked re-read of results.csv.

The reference is :func:`summary_figures_from_csv`, which parses the file the
:class:`~orchestrator.run.recorder.Recorder` wrote, in blocks of 2,048 rows; the traces below are
longer than one block so the chunk boundaries are crossed.
"""

import math

import numpy as np
import pytest

from components.common.faults import Fault
from orchestrator.run.recorder import Recorder
from orchestrator.run.summary import (MAX_TRACE_ROWS, RowTrace, summary_figures,
                                      summary_figures_from_csv)
from tests.support.json_leaves import leaves

COLUMNS = ["source.x", "source.y", "plant.x", "plant.y", "plant.heading", "plant.speed",
           "plant.slip_left", "plant.slip_right", "localizer.fix_attempts",
           "localizer.fix_status", "planner.rejected_fixes", "localizer.faults_active",
           "plant.faults_active", "controller_left.kp"]


def _rows(count, seed):
    """A robot chasing a wandering source, with slips, fix attempts and fault flags."""
    rng = np.random.default_rng(seed)
    source = np.cumsum(rng.normal(0.0, 0.004, (count, 2)), axis=0) + [0.3, 2.0]
    robot = np.zeros((count, 2))
    for k in range(1, count):
        robot[k] = robot[k - 1] + 0.01 * (source[k - 1] - robot[k - 1])
    attempts = np.cumsum(rng.random(count) < 0.2)
    status = np.where(rng.random(count) < 0.3, rng.integers(1, 13, count), 0)
    for k in range(count):
        yield (k * 0.02, [float(source[k, 0]), float(source[k, 1]), float(robot[k, 0]),
                          float(robot[k, 1]), float(rng.normal()), float(rng.normal(0.2, 0.1)),
                          float(rng.normal(0, 0.15)), float(rng.normal(0, 0.15)),
                          int(attempts[k]), int(status[k]), int(k // 500),
                          bool(1000 < k < 1800), bool(k > 4000), float(rng.normal())])


def _assert_equal(ours, reference, tolerance=1e-12):
    left, right = dict(leaves(ours)), dict(leaves(reference))
    assert left.keys() == right.keys()
    for key, value in right.items():
        if isinstance(value, float):
            assert math.isclose(left[key], value, rel_tol=tolerance, abs_tol=tolerance), key
        else:
            assert left[key] == value, key


def _record(tmp_path, count, seed, faults=(), expected=None):
    trace = RowTrace(COLUMNS, count if expected is None else expected, faults)
    with Recorder(tmp_path / "results.csv", COLUMNS) as recorder:
        for time, row in _rows(count, seed):
            recorder.record(time, row)
            trace.append(time, row)
    return trace


FAULTS = [("localizer", Fault(kind="lost_fixes", start=20.0, end=36.0)),
          ("plant", Fault(kind="low_friction", start=80.0, magnitude=0.3))]


@pytest.mark.parametrize("count, seed, faults", [(5000, 1, ()), (4500, 2, FAULTS),
                                                 (2, 3, FAULTS), (2049, 4, ())],
                         ids=["5000-rows", "4500-rows-faults", "2-rows", "one-past-a-chunk"])
def test_trace_gives_the_figures_of_the_chunked_reread(tmp_path, count, seed, faults):
    trace = _record(tmp_path, count, seed, faults)
    assert trace.kept and trace.rows == count
    ours = summary_figures(trace, faults, 0.5)
    reference = summary_figures_from_csv(tmp_path / "results.csv", faults, 0.5)
    _assert_equal(ours, reference)
    # the figures are not trivially equal: the run has slips, invalid fixes and fault time
    robustness = reference["robustness"]
    assert robustness["invalid_fixes_total"] > 0 and robustness["slip_time_s"] > 0 or count < 10
    if faults and count > 2000:
        assert robustness["faults_active_s"]["localizer"] == pytest.approx(799 * 0.02)


def test_a_lost_row_is_caught_by_the_comparison(tmp_path):
    """The comparison above can fail: a trace that misses one row differs from the file."""
    trace = RowTrace(COLUMNS, 5000)
    with Recorder(tmp_path / "results.csv", COLUMNS) as recorder:
        for time, row in _rows(5000, 1):
            recorder.record(time, row)
            if time != 40.0:
                trace.append(time, row)
    with pytest.raises(AssertionError):
        _assert_equal(summary_figures(trace, (), 0.5),
                      summary_figures_from_csv(tmp_path / "results.csv", (), 0.5))


def test_trace_is_not_kept_past_its_bound_or_its_expected_rows(tmp_path):
    assert not RowTrace(COLUMNS, MAX_TRACE_ROWS + 1).kept
    assert RowTrace(COLUMNS, MAX_TRACE_ROWS + 1)._values.size == 0   # nothing allocated
    trace = _record(tmp_path, 30, 5, expected=20)
    assert not trace.kept and trace.rows == 30


def test_trace_keeps_only_recorded_columns():
    trace = RowTrace(["plant.x", "plant.y", "source.x", "source.y", "plant.speed"], 3)
    assert trace.names == ["time", "plant.x", "plant.y", "source.x", "source.y", "plant.speed"]
    trace.append(0.0, [1.0, 2.0, 3.0, 4.0, 5.0])
    assert trace.columns()["plant.speed"].tolist() == [5.0]


def _segment_distance(px, py, ax, ay, bx, by):
    """Distance from a point to a segment, one scalar at a time (the reference)."""
    ux, uy = bx - ax, by - ay
    length2 = ux * ux + uy * uy
    s = 0.0 if length2 == 0 else min(1.0, max(0.0, ((px - ax) * ux + (py - ay) * uy) / length2))
    return math.hypot(px - (ax + s * ux), py - (ay + s * uy))


def test_distance_to_polyline_against_scalar_geometry():
    from orchestrator.run.metrics import distance_to_polyline

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
