"""What ``sonotrack run`` prints: the stop distance beside the final distance, faults counted."""

from orchestrator.run.summary_text import SUMMARY_FIELDS, robustness_line, summary_lines

SUMMARY = {"stop_distance_m": 0.5, "final_distance_to_source_m": 0.5600676,
           "min_distance_to_source_m": 0.5584516, "final_position_error_m": 0.0600676,
           "path_rmse_m": 0.0213962, "sim_time_s": 30.0, "wall_time_s": 2.77,
           "realtime_factor": 10.8, "steps": 3000, "status": "ok"}


def test_the_final_distance_line_carries_the_stop_distance():
    lines = summary_lines(SUMMARY)
    assert lines[0] == "  final_distance_to_source_m   0.5601  (stop_distance_m 0.5)"
    assert [line.split()[0] for line in lines] == list(SUMMARY_FIELDS)
    assert lines[-1] == "  steps                        3000"


def test_no_robustness_line_without_faults():
    healthy = dict(SUMMARY, robustness={"faults": [], "stopped_safely": None})
    assert robustness_line(healthy["robustness"]) is None
    assert len(summary_lines(healthy)) == len(SUMMARY_FIELDS)


def test_a_fault_run_gets_one_line_of_counts():
    robustness = {"faults": [{"kind": "mic_dead", "target": "localizer"},
                             {"kind": "mic_dead", "target": "localizer"}],
                  "invalid_fixes_total": 190, "fixes_rejected_by_gate": 3,
                  "wheel_check_stops": 0, "odometry_check_stops": None, "slip_threshold": 0.2,
                  "slip_time_s": 0.04, "max_slip_ratio": 0.25, "stopped_safely": True}
    line = summary_lines(dict(SUMMARY, robustness=robustness))[-1]
    assert line == ("  robustness                   2 fault(s): mic_dead (localizer); invalid "
                    "fixes 190; rejected by the gate 3; wheel-check stops 0; slip above 0.2 for "
                    "0.04 s (max 0.25); stopped safely yes")
    assert robustness_line(dict(robustness, stopped_safely=None)).endswith("stopped safely n/a")
