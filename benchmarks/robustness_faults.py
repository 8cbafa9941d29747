"""Does the loop survive each fault kind? One closed-loop run per ``scenarios/faults/*.toml``.

For each scenario: injected (the target reported the fault active), survived (every check of
:func:`orchestrator.run.fault_metrics.survival`), final distance, max slip ratio, invalid fixes,
fixes the planner's gate rejected, stops by the planner's wheel check and odometry check, and
odometry-check stops outside an encoder fault (false positives; target 0). Target: all
survived. Writes the ``faults`` section of
``benchmarks/results/robustness.json`` (the file's other sections, written by
``benchmarks/robustness.py``, are kept); with ``--plots DIR`` also one PNG per kind
(``docs/faults/`` holds the committed ones)::

    .venv/bin/python benchmarks/robustness_faults.py --plots docs/faults
"""

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks._common import RESULTS, build_fresh  # noqa: E402

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios" / "faults"


def fault_rows(fmu_dir, plot_dir=None, names=None):
    """Run every fault scenario; return one row per scenario (a dict of figures)."""
    import numpy as np

    from components.planner.odometry_check import TRIPS_AFTER
    from orchestrator.run.fault_metrics import survival
    from orchestrator.run.results import read_results
    from orchestrator.run.runner import run_scenario
    from orchestrator.scenario import load_scenario

    rows = []
    for path in sorted(SCENARIOS.glob("*.toml")):
        if names and path.stem not in names:
            continue
        scenario = load_scenario(path)
        started = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="sonotrack_fault_") as out:
            result = run_scenario(scenario, Path(out) / "run", progress=False, fmu_dir=fmu_dir,
                                  plots=False)
            data = read_results(result.results_csv)
            checks = survival(data, scenario)
            trips = data["time"][np.flatnonzero(np.diff(data["planner.odometry_faults"]) > 0)
                                 + 1]
            if plot_dir is not None:
                from orchestrator.run.fault_plots import plot_fault_run

                plot_fault_run(data, scenario, Path(plot_dir) / f"{path.stem}.png")
        robustness = result.summary["robustness"]
        # an encoder fault's trips may come up to TRIPS_AFTER + 1 fixes (0.1 s) after its end
        windows = [(f.start, f.end + (TRIPS_AFTER + 1) * 0.1) for _, f in scenario.faults
                   if f.kind in ("encoder_skip", "encoder_freeze")]
        outside = [float(t) for t in trips if not any(a <= t <= b for a, b in windows)]
        # largest |discrepancy| / bound of the check, away from the encoder faults
        time_s = data["time"]
        away = ~np.any([(time_s >= a) & (time_s <= b) for a, b in windows], axis=0) \
            if windows else np.ones(time_s.shape, bool)
        bound = data["planner.bearing_bound"]
        ratio = np.abs(data["planner.bearing_discrepancy"])[away & (bound > 0)] \
            / bound[away & (bound > 0)]
        rows.append({
            "scenario": path.stem,
            "kinds": sorted({fault.kind for _, fault in scenario.faults}),
            "injected": bool(robustness["faults_active_s"])
                        and all(v > 0 for v in robustness["faults_active_s"].values()),
            "faults_active_s": robustness["faults_active_s"],
            "survived": all(checks.values()),
            "checks": checks,
            "final_distance_m": result.summary["final_distance_to_source_m"],
            "min_distance_m": result.summary["min_distance_to_source_m"],
            "max_body_speed_m_s": robustness["max_body_speed_m_s"],
            "max_slip_ratio": robustness["max_slip_ratio"],
            "slip_time_s": robustness["slip_time_s"],
            "invalid_fixes": robustness["invalid_fixes"],
            "fixes_rejected_by_gate": robustness["fixes_rejected_by_gate"],
            "wheel_check_stops": robustness["wheel_check_stops"],
            "odometry_check_stops": robustness["odometry_check_stops"],
            "odometry_check_stop_times_s": [float(t) for t in trips],
            "odometry_check_stops_outside_encoder_faults": len(outside),
            "max_discrepancy_over_bound_outside_encoder_faults":
                float(ratio.max()) if ratio.size else None,
            "stopped_safely": robustness.get("stopped_safely"),
            "wall_time_s": time.perf_counter() - started,
        })
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plots", help="folder for one PNG per fault scenario")
    parser.add_argument("names", nargs="*", help="scenario names (default: all)")
    args = parser.parse_args(argv)
    from orchestrator.builder.fmus import FMU_PACKAGES

    paths = build_fresh(list(FMU_PACKAGES))
    fmu_dir = next(iter(paths.values())).parent
    rows = fault_rows(fmu_dir, args.plots, args.names)
    for row in rows:
        print(f"{row['scenario']:20s} injected {row['injected']!s:5s} survived "
              f"{row['survived']!s:5s} final {row['final_distance_m']:.3f} m  max slip "
              f"{row['max_slip_ratio']:.2f}  max speed {row['max_body_speed_m_s']:.3f} m/s  "
              f"invalid {sum(row['invalid_fixes'].values())}  rejected "
              f"{row['fixes_rejected_by_gate']}  stops: wheel {row['wheel_check_stops']} "
              f"odometry {row['odometry_check_stops']} (outside encoder faults "
              f"{row['odometry_check_stops_outside_encoder_faults']}, largest discrepancy "
              f"{row['max_discrepancy_over_bound_outside_encoder_faults']:.3f} of the bound)")
    survived = sum(row["survived"] for row in rows)
    false_stops = sum(row["odometry_check_stops_outside_encoder_faults"] for row in rows)
    print(f"survived {survived} of {len(rows)} (target: all); odometry-check stops outside "
          f"encoder faults: {false_stops} (target: 0)")
    if not args.names:
        path = write_section("faults", {
            "target": "every fault scenario survived",
            "survived": survived, "scenarios": len(rows), "met": survived == len(rows),
            "odometry_check_stops_outside_encoder_faults": false_stops,
            "runs": rows})
        print(f"wrote the faults section of {path}")


def write_section(name, section):
    """Set one top-level section of ``robustness.json``, keeping the others; return the path."""
    import json

    from orchestrator.run.folder import atomic_write_json

    path = RESULTS / "robustness.json"
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        record = {}
    record[name] = dict(section, machine=machine_info(),
                        generated_utc=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
    RESULTS.mkdir(parents=True, exist_ok=True)
    atomic_write_json(path, record)
    return path


def machine_info():
    import os
    import platform

    return {"python": platform.python_version(), "cpus": os.cpu_count(),
            "load_average_1min": os.getloadavg()[0]}


if __name__ == "__main__":
    main()
