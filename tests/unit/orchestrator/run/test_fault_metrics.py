"""The run summary's robustness section, on a results file with counts known by construction."""

import math

import pytest

from components.common.faults import Fault
from orchestrator.run.fault_metrics import SLIP_THRESHOLD, fault_summary_from_csv

_COLUMNS = ("time", "plant.x", "plant.y", "source.x", "source.y", "plant.speed",
            "plant.slip_left", "plant.slip_right", "localizer.fix_attempts",
            "localizer.fix_status", "planner.rejected_fixes", "localizer.faults_active",
            "planner.wheel_faults", "planner.odometry_faults")


def _write(path, rows):
    lines = [",".join(_COLUMNS)] + [",".join(repr(float(v)) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("chunk_rows", [1, 3, 1000], ids=["row by row", "chunks", "whole"])
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
    summary = fault_summary_from_csv(path, faults, stop_distance=0.4, chunk_rows=chunk_rows)
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
    summary = fault_summary_from_csv(path, (), stop_distance=0.5)
    assert summary["stopped_safely"] is False           # 0.1 m < 0.25 m
    assert "localizer.fix_status" in summary["not_recorded"]
    assert summary["invalid_fixes"] == {} and summary["fixes_rejected_by_gate"] is None
    assert summary["odometry_check_stops"] is None
    assert not math.isnan(summary["max_body_speed_m_s"])
