"""Speed of the co-simulation: our master on fmpy against fmpy, libcosim and plain Python.

Measured side by side in one run (alternating repetitions, medians reported):

* ``realtime_factor``: the default scenario (scenarios/s_curve.toml) at its default rates;
* ``us_per_instance_step``: our master stepping one FMU alone against fmpy's own
  ``simulate_fmu`` on the same FMU, step and stop time (RobotPlant and WheelController);
* libcosim: ``CosimExecution.from_ssp_file`` on fmus/SystemStructure.ssd at a single rate
  against our master (Jacobi) on the same single-rate system, recording the same things:
  every output after every step (libcosim's last-value observer, which reads every variable,
  against our recorder writing every output to results.csv), and only the robot trajectory
  (libcosim's time-series observer on plant.x, plant.y against our recorder with those
  columns); also the largest difference of the robot trajectories (the cross-check of
  tests/integration/orchestrator/run/test_runner.py). The models' own compute time on that system (the slaves'
  ``do_step`` calls, timed in-process) splits each master's stepping time into model time
  and master overhead per instance step; that time plus our FMI calls, each at the cost of
  the cheapest one (``fmi2GetReal`` of one value), is a floor under our stepping time, and
  libcosim's time over it bounds the speed-up any master making these calls could show;
* in-process: the same slave classes composed without FMI (``backend="in-process"``);
* ``room``: scenarios/room.toml (the default S-curve in the paper's 7 x 7 m room, the localizer
  hearing image sources) against the same scenario with ``localizer.room = false`` (free
  field), alternating, each run's wall time from its summary (set-up and stepping); target:
  the room within 3x (issue 22). ``--room-only`` measures this alone;
* ``run_command``: a whole default ``sonotrack run`` command in a fresh process (as a user
  types it, with its progress bar and plots; and with ``--no-plots``), split into start-up
  (interpreter, imports, argument parsing), set-up (system, FMU instances, renderers),
  stepping, summary (figures, summary.json on disk), plots (waiting for the renderer
  processes) and exit, each as a share of the command's wall time (timestamps from
  benchmarks/_run_phases.py), with the renderers' overlap; beside it the same command with one
  renderer and with the plots drawn in-process (what each piece buys), the summary's figures
  from the kept rows against re-reading results.csv, and the interpreter and import floors.

* ``system_fmu``: the whole-system FMU (``sonotrack build --system``) against ``sonotrack run
  --no-plots`` of the same scenario, cost per simulated second and their ratio, as whole
  commands and as stepping alone (benchmarks/_system_fmu.py).

The run-command part is benchmarks/_run_command.py, the libcosim comparison
benchmarks/_libcosim_compare.py, the system FMU benchmarks/_system_fmu.py; this script is the
one entry point.

Writes benchmarks/results/cosim_speed.json.

    python benchmarks/cosim_speed.py [--repeats 3] [--single-rate-stop 10] [--room-only]
                                     [--system-fmu-only]
"""

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _libcosim_compare  # noqa: E402
import _run_command  # noqa: E402
import _system_fmu  # noqa: E402
from _common import build_fresh, median, write_result  # noqa: E402
from _libcosim_compare import INSTANCES  # noqa: E402
from _run_command import PHASES, VARIANTS  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def run_default(fmu_dir, backend, out):
    from orchestrator.run.runner import run_scenario

    result = run_scenario(ROOT / "scenarios" / "s_curve.toml", out, progress=False,
                          fmu_dir=fmu_dir, plots=False, backend=backend)
    return result.summary


def run_room(fmu_dir, room, out):
    """scenarios/room.toml, in its room or (``room`` false) in free field; the summary."""
    from orchestrator.run.runner import run_scenario
    from orchestrator.scenario import load_scenario

    scenario = load_scenario(ROOT / "scenarios" / "room.toml")
    if not room:
        scenario = scenario.with_overrides(parameters={"localizer.room": False})
    return run_scenario(scenario, out, progress=False, fmu_dir=fmu_dir, plots=False).summary


def room_against_free_field(fmu_dir, work, repeats):
    """Wall times of the room scenario in its room and in free field, alternating."""
    walls = {"room": [], "free_field": []}
    for r in range(repeats):
        for name in walls:
            summary = run_room(fmu_dir, name == "room", work / f"{name}{r}")
            walls[name].append(summary["wall_time_s"])
        print(f"room scenario run {r + 1}/{repeats}: {walls['room'][-1]:.2f} s in the room, "
              f"{walls['free_field'][-1]:.2f} s in free field", flush=True)
    return {"scenario": "scenarios/room.toml (free field: localizer.room = false)",
            "room_wall_s": median(walls["room"]), "free_field_wall_s": median(walls["free_field"]),
            "room_runs_s": walls["room"], "free_field_runs_s": walls["free_field"],
            "room_over_free_field": median(walls["room"]) / median(walls["free_field"]),
            "room_over_free_field_target": 3.0}


def instance_steps(scenario_path):
    from orchestrator.scenario import load_scenario

    scenario = load_scenario(scenario_path)
    return sum(int(round(scenario.stop_time / scenario.step(name))) for name in INSTANCES)


def single_fmu_ours(path, name, inputs, step, stop):
    from orchestrator.fmu.handle import FmuInstance
    from orchestrator.run.master import InstanceSpec, Master

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


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="repetitions of each timing")
    parser.add_argument("--single-rate-stop", type=float, default=10.0,
                        help="simulated seconds of the libcosim comparison")
    parser.add_argument("--room-only", action="store_true",
                        help="only the room against free field (writes cosim_speed_room.json)")
    parser.add_argument("--system-fmu-only", action="store_true",
                        help="only the system FMU against sonotrack run (writes "
                             "cosim_speed_system_fmu.json)")
    args = parser.parse_args(argv)
    if args.system_fmu_only:
        fmus = build_fresh(["RobotPlant", "SoundSource", "AcousticLocalizer", "CurvaturePlanner",
                            "WheelController"])
        work = Path(tempfile.mkdtemp(prefix="sonotrack_cosim_speed_"))
        record = _system_fmu.measure(next(iter(fmus.values())).parent, work, args.repeats)
        print(_system_fmu.summary_line(record))
        print(f"wrote {write_result('cosim_speed_system_fmu', record)}")
        return 0
    if args.room_only:
        load_at_start = os.getloadavg()[0]
        fmus = build_fresh(["RobotPlant", "SoundSource", "AcousticLocalizer", "CurvaturePlanner",
                            "WheelController"])
        work = Path(tempfile.mkdtemp(prefix="sonotrack_cosim_speed_"))
        room = room_against_free_field(next(iter(fmus.values())).parent, work, args.repeats)
        room["load_average"] = [load_at_start, os.getloadavg()[0]]
        out = write_result("cosim_speed_room", room)
        print(f"room / free field {room['room_over_free_field']:.2f} (target <= 3); wrote {out}")
        return 0

    load_at_start = os.getloadavg()[0]
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

    room = room_against_free_field(fmu_dir, work, args.repeats)

    commands = _run_command.measure(fmu_dir, work, args.repeats)

    summary_costs = _run_command.summary_figures_cost(work / "command_plots0" / "results.csv",
                                                      args.repeats)
    import_floors = _run_command.start_up_floors(args.repeats)

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

    single_rate = _libcosim_compare.compare(fmu_dir, fmus["WheelController"], work,
                                            args.repeats, args.single_rate_stop)
    system_fmu = _system_fmu.measure(fmu_dir, work / "system_fmu", args.repeats)

    record = {
        "scenario": "scenarios/s_curve.toml",
        # 1-minute load averages when the script started and ended (2 cores: above ~2 means
        # other processes shared them, and every figure here is slower than on an idle machine)
        "load_average": [load_at_start, os.getloadavg()[0]],
        "repeats": args.repeats,
        "realtime_factor": median(fmi_rtf),
        "realtime_factor_target": 20.0,
        "realtime_factor_runs": fmi_rtf,
        "wall_time_s": median(fmi_wall),
        "instance_steps": scenario_steps,
        "us_per_instance_step": median(fmi_wall) / scenario_steps * 1e6,
        "single_fmu": single,
        "run_command": _run_command.section(commands, summary_costs, import_floors),
        "in_process_realtime_factor": median(inprocess_rtf),
        "fmi_over_in_process_wall_ratio": median(fmi_wall) / median(inprocess_wall),
        "fmi_over_in_process_target": 3.0,
        "libcosim_single_rate": single_rate,
        "system_fmu": system_fmu,
    }
    out = write_result("cosim_speed", record)
    print(f"realtime factor {record['realtime_factor']:.1f} (target 20); FMI/in-process "
          f"{record['fmi_over_in_process_wall_ratio']:.2f} (target <= 3); room / free field "
          f"{room['room_over_free_field']:.2f} (target <= 3)")
    for name in ("every_output", "trajectory"):
        row = single_rate[name]
        print(f"ours vs libcosim, {name}: {row['speedup_ours_over_libcosim']:.2f}x wall, "
              f"{row['stepping_speedup_ours_over_libcosim']:.2f}x stepping (target >= 3); "
              f"overhead per instance step {row['ours_overhead_us_per_instance_step']:.0f} us "
              f"vs {row['libcosim_overhead_us_per_instance_step']:.0f} us; model time "
              f"{single_rate['model_compute_s']:.3f} s; {row['ours_fmi_calls']} FMI calls at "
              f">= {single_rate['fmi_call_floor_us']:.1f} us: stepping speed-up at most "
              f"{row['stepping_speedup_upper_bound']:.2f}x")
    for name in VARIANTS:
        command = record["run_command"][name]
        print(f"sonotrack run ({name.replace('_', ' ')}): {command['wall_s']:.2f} s; not "
              f"stepping {command['not_stepping_share']:.0%} (target <= 40 %): " +
              ", ".join(f"{p} {command['phase_shares'][p]:.0%}" for p in PHASES))
    print(_system_fmu.summary_line(system_fmu))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
