"""The summary's figures from the rows kept while recording (RowTrace) and from results.csv.

The reference is :func:`summary_figures` over :class:`ResultRows`, which parses the file the
:class:`~orchestrator.run.recorder.Recorder` wrote, in blocks of 2,048 rows; the traces below are
longer than one block so the chunk boundaries are crossed.
"""

import math

import numpy as np
import pytest

from components.common.faults import Fault
from orchestrator.run.recorder import Recorder
from orchestrator.run.summary import (MAX_TRACE_ROWS, TRACE_COLUMNS, ResultRows, RowTrace,
                                      has_figures, summary_columns, summary_figures)
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
    reference = summary_figures(ResultRows(tmp_path / "results.csv"), faults, 0.5)
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
                      summary_figures(ResultRows(tmp_path / "results.csv"), (), 0.5))


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


def test_both_sources_hold_the_same_rows(tmp_path):
    """The kept rows come as one chunk, the file's in blocks of chunk_rows; joined, the same
    numbers (the CSV's shortest round-tripping text parses back to the very floats)."""
    trace = _record(tmp_path, 300, 6)
    file = ResultRows(tmp_path / "results.csv", chunk_rows=64)
    assert file.names == ["time"] + COLUMNS
    assert set(trace.names) == set(summary_columns()) - {"planner.wheel_faults",
                                                         "planner.odometry_faults"}
    wanted = ["time", "plant.x", "localizer.fix_status"]
    kept, read = list(trace.chunks(wanted)), list(file.chunks(wanted))
    assert [len(c["time"]) for c in kept] == [300]
    assert [len(c["time"]) for c in read] == [64, 64, 64, 64, 44]
    for name in wanted:
        assert np.array_equal(kept[0][name], np.concatenate([c[name] for c in read])), name
    assert list(kept[0]) == list(read[0]) == wanted


def test_the_summary_columns_are_the_figures_columns():
    assert TRACE_COLUMNS == ("plant.x", "plant.y", "source.x", "source.y")
    assert summary_columns(FAULTS) == [
        "time", "plant.x", "plant.y", "source.x", "source.y", "plant.speed", "plant.slip_left",
        "plant.slip_right", "localizer.fix_attempts", "localizer.fix_status",
        "planner.rejected_fixes", "planner.wheel_faults", "planner.odometry_faults",
        "localizer.faults_active", "plant.faults_active"]
    assert has_figures(["plant.speed", "source.y", "plant.x", "source.x", "plant.y"])
    assert not has_figures(["plant.x", "plant.y", "source.x", "plant.speed"])


def test_figures_of_a_run_known_by_construction(tmp_path):
    """Five rows 0.1 s apart: the robot drives from (0, 0) towards a source at rest at (0, 2)
    and stops 0.3 m beside the path with 1.5 m to go; its left wheel slips in rows 1 and 2."""
    columns = ["plant.x", "plant.y", "source.x", "source.y", "plant.speed", "plant.slip_left",
               "plant.slip_right"]
    rows = [(0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0), (0.3, 0.5, 0.0, 2.0, 0.2, 0.3, 0.0),
            (0.3, 1.0, 0.0, 2.0, 0.25, -0.4, 0.1), (0.3, 1.5, 0.0, 2.0, 0.1, 0.0, 0.0),
            (0.3, 1.5, 0.0, 2.0, 0.0, 0.0, 0.0)]
    trace = RowTrace(columns, len(rows))
    with Recorder(tmp_path / "results.csv", columns) as recorder:
        for k, row in enumerate(rows):
            recorder.record(0.1 * k, row)
            trace.append(0.1 * k, row)
    for source in (trace, ResultRows(tmp_path / "results.csv", chunk_rows=2)):
        figures = summary_figures(source, (), 0.5)
        last = math.hypot(0.3, 0.5)
        assert figures["final_distance_to_source_m"] == pytest.approx(last, abs=1e-15)
        assert figures["min_distance_to_source_m"] == pytest.approx(last, abs=1e-15)
        assert figures["final_position_error_m"] == pytest.approx(last - 0.5, abs=1e-15)
        # the reference path is (0, 0) -> (0, 2); every moved point is 0.3 m beside it
        assert figures["path_rmse_m"] == pytest.approx(0.3, abs=1e-15)
        robustness = figures["robustness"]
        assert robustness["slip_time_s"] == pytest.approx(0.2, abs=1e-15)
        assert (robustness["max_slip_ratio"], robustness["max_body_speed_m_s"]) == (0.4, 0.25)
        assert robustness["stopped_safely"] is True     # at rest, never closer than 0.25 m
        assert robustness["not_recorded"] == [
            "localizer.fix_attempts", "localizer.fix_status", "planner.rejected_fixes",
            "planner.wheel_faults", "planner.odometry_faults"]
        assert robustness["invalid_fixes"] == {} and robustness["fixes_rejected_by_gate"] is None
