"""A run's summary as the lines ``sonotrack run`` prints: the answer first, then the run.

The distance figures come first, the final distance with the planner's stop distance beside
it (the distance the robot is meant to end at), then the path deviation and the run's own
figures; when the scenario injected faults, one more line counts what the robustness section
found. Every field is defined in ``docs/metrics.md``.

Examples
--------
>>> for line in summary_lines({"stop_distance_m": 0.5, "final_distance_to_source_m": 0.5601,
...                            "min_distance_to_source_m": 0.5585, "steps": 3000}):
...     print(line)
  final_distance_to_source_m   0.5601  (stop_distance_m 0.5)
  min_distance_to_source_m     0.5585
  steps                        3000
"""

__all__ = ["SUMMARY_FIELDS", "robustness_line", "summary_lines"]

# The printed fields, in order (each defined in docs/metrics.md).
SUMMARY_FIELDS = ("final_distance_to_source_m", "min_distance_to_source_m",
                  "final_position_error_m", "path_rmse_m", "sim_time_s", "wall_time_s",
                  "realtime_factor", "steps")
_WIDTH = 28


def _value(value):
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def _yes_no(value):
    return "n/a" if value is None else "yes" if value else "no"


def robustness_line(robustness):
    """One line counting what the ``robustness`` section found, or None without faults."""
    faults = robustness.get("faults") or []
    if not faults:
        return None
    kinds = ", ".join(dict.fromkeys(f"{f['kind']} ({f['target']})" for f in faults))
    parts = [f"{len(faults)} fault(s): {kinds}",
             f"invalid fixes {robustness.get('invalid_fixes_total', 0)}"]
    for key, text in (("fixes_rejected_by_gate", "rejected by the gate"),
                      ("wheel_check_stops", "wheel-check stops"),
                      ("odometry_check_stops", "odometry-check stops")):
        if robustness.get(key) is not None:
            parts.append(f"{text} {robustness[key]}")
    if "max_slip_ratio" in robustness:
        parts.append(f"slip above {robustness.get('slip_threshold', 0):g} for "
                     f"{robustness.get('slip_time_s', 0.0):.3g} s "
                     f"(max {robustness['max_slip_ratio']:.3g})")
    if "stopped_safely" in robustness:
        parts.append(f"stopped safely {_yes_no(robustness['stopped_safely'])}")
    return f"  {'robustness':{_WIDTH}s} " + "; ".join(parts)


def summary_lines(summary):
    """The lines ``sonotrack run`` prints for a summary (see the module docstring).

    Parameters
    ----------
    summary : dict
        A run's summary (``summary.json``).

    Returns
    -------
    list of str
    """
    lines = []
    for key in SUMMARY_FIELDS:
        if key not in summary:
            continue
        line = f"  {key:{_WIDTH}s} {_value(summary[key])}"
        if key == "final_distance_to_source_m" and "stop_distance_m" in summary:
            line += f"  (stop_distance_m {_value(summary['stop_distance_m'])})"
        lines.append(line)
    robustness = robustness_line(summary.get("robustness") or {})
    if robustness:
        lines.append(robustness)
    return lines
