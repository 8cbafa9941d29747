"""Speed of the co-simulation: our master on fmpy against fmpy, libcosim and plain Python.

Measured side by side in one run (alternating repetitions, medians reported):

* ``realtime_factor``: the default scenario (scenarios/s_curve.toml) at its default rates;
* ``us_per_instance_step``: our master stepping one FMU alone against fmpy's own
  ``simulate_fmu`` on the same FMU, step and stop time (RobotPlant and WheelController);
* libcosim: ``CosimExecution.from_ssp_file`` on fmus/SystemStructure.ssd at a single rate
  against our master (Jacobi) on the same single-rate system; also the largest difference of
  the robot trajectories (the cross-check of tests/integration/test_cosim.py);
* in-process: the same slave classes composed without FMI (``backend="in-process"``).

Writes benchmarks/results/cosim_speed.json.

    python benchmarks/cosim_speed.py [--repeats 3] [--single-rate-stop 10]
"""

import argparse
import csv
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import build_fresh, median, write_result  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SSD = ROOT / "fmus" / "SystemStructure.ssd"
INSTANCES = ("source", "localizer", "planner", "controller_left", "controller_right", "plant")


def run_default(fmu_dir, backend, out):
    from orchestrator.run import run_scenario

    result = run_scenario(ROOT / "scenarios" / "s_curve.toml", out, progress=False,
                          fmu_dir=fmu_dir, plots=False, backend=backend)
    return result.summary


def instance_steps(scenario_path):
    from orchestrator.scenario import load_scenario

    scenario = load_scenario(scenario_path)
    return sum(int(round(scenario.stop_time / scenario.step(name))) for name in INSTANCES)


def single_fmu_ours(path, name, inputs, step, stop):
    from orchestrator.fmu import FmuInstance
    from orchestrator.master import InstanceSpec, Master

    instance = FmuInstance(path, name)
    master = Master([InstanceSpec(name, instance, 1, {})], [], step)
    master.initialize(0.0, stop)
    instance.set_values(inputs)
    # record every output every step, as simulate_fmu does
    groups = {}
    for variable in instance.variables.values():
        if variable.causality == "output":
            groups.setdefault(variable.type, []).append(variable.name)
    groups = [instance.port_group(t, names) for t, names in groups.items()]
    steps = int(round(stop / step))
    started = time.perf_counter()
    for k in range(steps):
        master.step(k)
        for group in groups:
            instance.read(group)
    wall = time.perf_counter() - started
    master.terminate()
    return wall / steps


def single_fmu_fmpy(path, inputs, step, stop):
    import fmpy

    started = time.perf_counter()
    fmpy.simulate_fmu(str(path), stop_time=stop, step_size=step, output_interval=step,
                      start_values=inputs)
    return (time.perf_counter() - started) / int(round(stop / step))


def single_rate_ssd(fmu_dir):
    from orchestrator.ssp import read_ssd, write_ssd

    path = Path(fmu_dir) / "SingleRate.ssd"
    write_ssd(path, read_ssd(SSD).without_step_hints())
    return path


def libcosim_run(ssd, step, stop):
    from orchestrator.crosscheck import run_libcosim_ssd

    timing, rows = run_libcosim_ssd(ssd, step, stop, ["plant.x", "plant.y"])
    return timing, np.array(rows)


def ours_single_rate(fmu_dir, step, stop, out):
    from orchestrator.run import run_scenario
    from orchestrator.scenario import scenario_from_dict

    scenario = scenario_from_dict({
        "name": "single_rate", "system": str(SSD), "stop_time": stop, "base_step": step,
        "steps": {name: step for name in INSTANCES}, "seed": 1, "master": "jacobi"})
    started = time.perf_counter()
    result = run_scenario(scenario, out, progress=False, fmu_dir=fmu_dir, plots=False,
                          record_interval=step)
    wall = time.perf_counter() - started
    with open(result.results_csv) as f:
        rows = list(csv.DictReader(f))[1:]
    timing = {"wall_s": wall, "stepping_s": result.summary["wall_time_s"]}
    return timing, np.array([[float(r["plant.x"]), float(r["plant.y"])] for r in rows])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="repetitions of each timing")
    parser.add_argument("--single-rate-stop", type=float, default=10.0,
                        help="simulated seconds of the libcosim comparison")
    args = parser.parse_args(argv)

    fmus = build_fresh(["RobotPlant", "SoundSource", "AcousticLocalizer", "CurvaturePlanner",
                        "WheelController"])
    fmu_dir = next(iter(fmus.values())).parent
    work = Path(tempfile.mkdtemp(prefix="sonotrack_cosim_speed_"))
    scenario_steps = instance_steps(ROOT / "scenarios" / "s_curve.toml")

    fmi_rtf, inprocess_rtf, fmi_wall, inprocess_wall = [], [], [], []
    for r in range(args.repeats):
        summary = run_default(fmu_dir, "fmi", work / f"fmi{r}")
        fmi_rtf.append(summary["realtime_factor"])
        fmi_wall.append(summary["wall_time_s"])
        summary_in = run_default(fmu_dir, "in-process", work / f"inprocess{r}")
        inprocess_rtf.append(summary_in["realtime_factor"])
        inprocess_wall.append(summary_in["wall_time_s"])
        print(f"default scenario run {r + 1}/{args.repeats}: RTF {fmi_rtf[-1]:.1f} (FMI), "
              f"{inprocess_rtf[-1]:.1f} (in-process)", flush=True)

    single = {}
    cases = {"RobotPlant": ({"voltage_left": 6.0, "voltage_right": 5.0}, 0.02),
             "WheelController": ({"v_ref": 0.3, "v_meas": 0.25}, 0.02)}
    for name, (inputs, step) in cases.items():
        ours, theirs = [], []
        for _ in range(args.repeats):
            ours.append(single_fmu_ours(fmus[name], name, inputs, step, 20.0))
            theirs.append(single_fmu_fmpy(fmus[name], inputs, step, 20.0))
        single[name] = {"step_s": step, "ours_us_per_step": median(ours) * 1e6,
                        "fmpy_simulate_fmu_us_per_step": median(theirs) * 1e6,
                        "ratio_ours_to_fmpy": median(ours) / median(theirs)}
        print(f"{name} alone: ours {single[name]['ours_us_per_step']:.1f} us/step, "
              f"fmpy.simulate_fmu {single[name]['fmpy_simulate_fmu_us_per_step']:.1f} us/step",
              flush=True)

    ssd = single_rate_ssd(fmu_dir)
    step, stop = 0.01, args.single_rate_stop
    libcosim_walls, ours_walls, libcosim_steps, ours_steps = [], [], [], []
    difference = None
    for r in range(args.repeats):
        timing, theirs = libcosim_run(ssd, step, stop)
        libcosim_walls.append(timing["wall_s"])
        libcosim_steps.append(timing["stepping_s"])
        timing, ours = ours_single_rate(fmu_dir, step, stop, work / f"single{r}")
        ours_walls.append(timing["wall_s"])
        ours_steps.append(timing["stepping_s"])
        difference = float(np.max(np.hypot(*(ours - theirs).T)))
        print(f"single rate {stop:g} s: libcosim {libcosim_walls[-1]:.2f} s, ours "
              f"{ours_walls[-1]:.2f} s, max trajectory difference {difference:.3g} m", flush=True)

    record = {
        "scenario": "scenarios/s_curve.toml",
        "repeats": args.repeats,
        "realtime_factor": median(fmi_rtf),
        "realtime_factor_target": 20.0,
        "realtime_factor_runs": fmi_rtf,
        "wall_time_s": median(fmi_wall),
        "instance_steps": scenario_steps,
        "us_per_instance_step": median(fmi_wall) / scenario_steps * 1e6,
        "single_fmu": single,
        "in_process_realtime_factor": median(inprocess_rtf),
        "fmi_over_in_process_wall_ratio": median(fmi_wall) / median(inprocess_wall),
        "fmi_over_in_process_target": 3.0,
        "libcosim_single_rate": {
            "step_s": step, "stop_time_s": stop,
            "libcosim_wall_s": median(libcosim_walls), "ours_wall_s": median(ours_walls),
            "speedup_ours_over_libcosim": median(libcosim_walls) / median(ours_walls),
            "libcosim_stepping_s": median(libcosim_steps), "ours_stepping_s": median(ours_steps),
            "stepping_speedup_ours_over_libcosim": median(libcosim_steps) / median(ours_steps),
            "speedup_target": 3.0,
            "max_trajectory_difference_m": difference,
            "difference_target_m": 1e-6,
            "note": "wall: both include loading the system and instantiating the FMUs (ours "
                    "also writes results.csv and summary.json); stepping: the step loop only. "
                    "libcosim runs in a child process and is timed inside it",
        },
    }
    out = write_result("cosim_speed", record)
    single_rate = record["libcosim_single_rate"]
    print(f"realtime factor {record['realtime_factor']:.1f} (target 20); FMI/in-process "
          f"{record['fmi_over_in_process_wall_ratio']:.2f} (target <= 3); ours vs libcosim "
          f"{single_rate['speedup_ours_over_libcosim']:.1f}x wall, "
          f"{single_rate['stepping_speedup_ours_over_libcosim']:.1f}x stepping (target >= 3)")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
