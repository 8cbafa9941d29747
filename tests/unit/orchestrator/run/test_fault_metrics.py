"""The run summary's robustness section, on a results file with counts known by construction."""

import math

import numpy as np
import pytest

from components.common.faults import Fault
from orchestrator.run.fault_metrics import SLIP_THRESHOLD, fault_summary
from orchestrator.run.summary import ResultRows, RowTrace

_COLUMNS = ("time", "plant.x", "plant.y", "source.x", "source.y", "plant.speed",
            "plant.slip_left", "plant.slip_right", "localizer.fix_attempts",
            "localizer.fix_status", "planner.rejected_fixes", "localizer.faults_active",
            "planner.wheel_faults", "planner.odometry_faults")


def _write(path, rows):
    lines = [",".join(_COLUMNS)] + [",".join(repr(float(v)) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("chunk_rows", [1, 3, 1000, None],
                         ids=["row by row", "chunks", "whole", "kept rows"])
def test_counts_and_extremes(tmp_path, chunk_rows):
    rows = []
    # 20 rows, 0.05 s apart; attempts every other row; the robot drives to 0.5 m and stops
    for k in range(20):
        t = 0.05 * k
        attempts = k // 2 + 1
        status = {2: 10, 3: 10, 4: 10, 6: 5, 7: 12}.get(attempts, 0)  # by attempt number
        slip = 0.5 if 8 <= k < 12 else 0.01                   # 4 rows above the threshold
        speed = 0.0 if k >= 18 else 0.3 - 0.01 * k
        active = 1 if 0.2 <= t < 0.5 else 0
        rows.append((t, 0.0, 0.1 * min(k, 15), 0.0, 2.0, speed, -slip, 0.0, attempts,
                     status, k // 5, active, k // 10, k // 7))
    # the last row holds two new attempts (10 -> 12): the one shown and one never recorded
    rows[-1] = rows[-1][:8] + (rows[-1][8] + 2,) + rows[-1][9:]
    path = tmp_path / "results.csv"
    _write(path, rows)
    faults = [("localizer", Fault("mic_dead", 0.2, 0.5, channel="M1"))]
    if chunk_rows is None:   # the rows as a run keeps them while recording
        rows_source = RowTrace(_COLUMNS[1:], len(rows), faults)
        for row in rows:
            rows_source.append(row[0], row[1:])
    else:
        rows_source = ResultRows(path, chunk_rows)
    summary = fault_summary(rows_source, faults, stop_distance=0.4)
    assert summary["invalid_fixes"] == {"a microphone record is dead": 3,
                                        "fix lost (dropped before it was taken)": 1,
                                        "no burst onset detected": 1, "unrecorded": 1}
    assert summary["invalid_fixes_total"] == 6
    assert summary["fixes_rejected_by_gate"] == 3
    assert summary["wheel_check_stops"] == 1 and summary["odometry_check_stops"] == 2
    assert summary["slip_time_s"] == pytest.approx(4 * 0.05)
    assert summary["max_slip_ratio"] == pytest.approx(0.5) and SLIP_THRESHOLD < 0.5
    assert summary["max_body_speed_m_s"] == pytest.approx(0.3)
    assert summary["faults_active_s"] == {"localizer": pytest.approx(6 * 0.05)}
    assert summary["faults"][0]["kind"] == "mic_dead" and summary["faults"][0]["end_s"] == 0.5
    # closest 0.5 m > stop_distance / 2 = 0.2 m, final speed 0: stopped safely
    assert summary["stopped_safely"] is True
    assert summary["not_recorded"] == []


def test_too_close_is_not_safe_and_missing_columns_are_named(tmp_path):
    path = tmp_path / "results.csv"
    path.write_text("time,plant.x,plant.y,source.x,source.y,plant.speed\n"
                    "0.0,0.0,0.0,0.0,1.0,0.0\n0.1,0.0,0.9,0.0,1.0,0.0\n")
    summary = fault_summary(ResultRows(path), (), stop_distance=0.5)
    assert summary["stopped_safely"] is False           # 0.1 m < 0.25 m
    assert "localizer.fix_status" in summary["not_recorded"]
    assert summary["invalid_fixes"] == {} and summary["fixes_rejected_by_gate"] is None
    assert summary["odometry_check_stops"] is None
    assert not math.isnan(summary["max_body_speed_m_s"])


def test_survival_checks_against_the_planner_limits():
    """v_max 0.3 m/s allows 0.315 m/s; stop_distance 0.5 m forbids 0.25 m and asks for a
    final distance within 0.3 m of it (recovered) or, after a permanent fault, a stop."""
    from types import SimpleNamespace

    from orchestrator.run.fault_metrics import survival

    data = {"plant.speed": np.array([0.0, 0.31, -0.2, 0.01]),
            "plant.x": np.zeros(4), "plant.y": np.array([0.0, 1.0, 1.6, 1.8]),
            "source.x": np.zeros(4), "source.y": np.full(4, 2.6)}
    passing = SimpleNamespace(parameters={"planner.v_max": 0.3}, faults=[])
    assert survival(data, passing) == {"finite": True, "speed": True, "no_collision": True,
                                       "recovered": False}     # 0.8 m from 0.5 m: too far
    data["plant.y"][-1] = 2.1                                   # 0.5 m away at the end
    assert survival(data, passing)["recovered"] is True
    data["plant.y"][-2] = 2.4                                   # 0.2 m < 0.25 m
    permanent = SimpleNamespace(parameters={"planner.v_max": 0.29},
                                faults=[("localizer", Fault("mic_dead", 1.0, channel="M1"))])
    assert survival(data, permanent) == {"finite": True, "speed": False,
                                         "no_collision": False, "stopped": True}


@pytest.mark.parametrize("chunk_rows", [1, 1000], ids=["row by row", "whole"])
def test_stopping_is_not_asked_of_a_robot_whose_source_still_moves(tmp_path, chunk_rows):
    """A healthy tracking run ends with the source driving at 0.2 m/s and the robot following
    it: not having stopped is right there, so the figure is None, not False."""
    path = tmp_path / "results.csv"
    # the source drives +y at 0.2 m/s; the robot follows 0.6 m behind at the same speed
    path.write_text("time,plant.x,plant.y,source.x,source.y,plant.speed\n" + "".join(
        f"{t:.2f},0.0,{0.2 * t:.4f},0.0,{0.6 + 0.2 * t:.4f},0.2\n"
        for t in np.arange(0, 1.0001, 0.1)))
    summary = fault_summary(ResultRows(path, chunk_rows), (), stop_distance=0.5)
    assert summary["source_speed_at_end_m_s"] == pytest.approx(0.2)
    assert summary["stopped_safely"] is None
    # the same robot standing still beside a source that has stopped: asked, and answered
    path.write_text("time,plant.x,plant.y,source.x,source.y,plant.speed\n"
                    "0.0,0.0,0.0,0.0,0.6,0.0\n0.1,0.0,0.0,0.0,0.6,0.0\n")
    summary = fault_summary(ResultRows(path, chunk_rows), (), stop_distance=0.5)
    assert summary["source_speed_at_end_m_s"] == 0.0 and summary["stopped_safely"] is True
