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
  tests/integration/test_cosim.py). The models' own compute time on that system (the slaves'
  ``do_step`` calls, timed in-process) splits each master's stepping time into model time
  and master overhead per instance step; that time plus our FMI calls, each at the cost of
  the cheapest one (``fmi2GetReal`` of one value), is a floor under our stepping time, and
  libcosim's time over it bounds the speed-up any master making these calls could show;
* in-process: the same slave classes composed without FMI (``backend="in-process"``);
* ``run_command``: a whole default ``sonotrack run`` command in a fresh process (as a user
  types it, with its progress bar and plots; and with ``--no-plots``), split into start-up
  (interpreter, imports, argument parsing), set-up (system, FMU instances, renderers),
  stepping, summary (figures, summary.json on disk), plots (waiting for the renderer
  processes) and exit, each as a share of the command's wall time (timestamps from
  benchmarks/_run_phases.py), with the renderers' overlap; beside it the same command with one
  renderer and with the plots drawn in-process (what each piece buys), the summary's figures
  from the kept rows against re-reading results.csv, and the interpreter and import floors.

Writes benchmarks/results/cosim_speed.json.

    python benchmarks/cosim_speed.py [--repeats 3] [--single-rate-stop 10]
"""

import argparse
import csv
import json
import os
import subprocess
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


PHASES = ("start-up", "set-up", "stepping", "summary", "plots", "exit")
# How the command draws its plots (see benchmarks/_run_phases.py); "no-plots" draws none.
VARIANTS = {"plots": ("default", True), "no_plots": ("default", False),
            "plots_one_renderer": ("one-renderer", True),
            "plots_in_process": ("in-process", True)}


def run_command_phases(fmu_dir, out, variant="default", plots=True):
    """Time one whole ``sonotrack run`` (default scenario) in a fresh process, by phase.

    The phases partition the wall time of the command's own process (they add up to it):
    start-up (spawn to run_scenario entered), set-up (to the first step; includes spawning
    the renderers), stepping, summary (last step to the ok summary.json on disk), plots (to
    run_scenario's return: waiting for the renderers, or drawing in-process, and the
    summary's rewrite with the plots' names), exit. The renderers' own timestamps say how
    much of their work overlapped the parent's set-up and stepping.
    """
    times = Path(str(out) + ".times.json")
    command = [sys.executable, str(Path(__file__).resolve().parent / "_run_phases.py"),
               str(times), variant, "run", "scenarios/s_curve.toml", "--out", str(out),
               "--fmu-dir", str(fmu_dir)] + ([] if plots else ["--no-plots"])
    # as a user's shell runs it: Python caches bytecode (this session's environment turns
    # that off, which would add compiling every module to every command's start-up)
    environment = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    started = time.time()
    subprocess.run(command, cwd=ROOT, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL, env=environment)
    ended = time.time()
    marks = json.loads(times.read_text())
    summary_on_disk = min(t for t in marks["summary_writes"] if t >= marks["stepping_done"])
    phases = {
        "start-up": marks["command_started"] - started,
        "set-up": marks["stepping_started"] - marks["command_started"],
        "stepping": marks["stepping_done"] - marks["stepping_started"],
        "summary": summary_on_disk - marks["stepping_done"],
        "plots": marks["run_returned"] - summary_on_disk,
        "exit": ended - marks["run_returned"],
    }
    renderers = []
    for renderer in marks.get("renderers", []):
        if not renderer:
            continue
        # the renderer's warm-up (import, a throw-away figure) against the parent's timeline
        overlap = max(0.0, min(renderer["ready"], marks["stepping_done"])
                      - max(renderer["started"], marks["command_started"]))
        renderers.append({
            "spawn_to_started_s": renderer["started"] - marks["command_started"],
            "warm_up_s": renderer["ready"] - renderer["started"],
            "warm_up_overlapping_set_up_and_stepping_s": overlap,
            "ready_after_summary_on_disk_s": max(0.0, renderer["ready"] - summary_on_disk),
            "request_after_summary_on_disk_s": renderer["request"] - summary_on_disk,
            "drawing_s": renderer["done"] - renderer["request"],
        })
    return ended - started, phases, renderers


def summary_figures_cost(results_csv, repeats):
    """Seconds to compute the summary's figures of one default run: from the rows kept while
    recording (:class:`RowTrace`, what run_scenario does) against re-reading results.csv in
    chunks (what it did); and the cost of keeping the rows (one append per recorded row)."""
    from orchestrator.results import read_header, read_results
    from orchestrator.run_metrics import RowTrace, summary_figures, summary_figures_from_csv

    stop = json.loads((Path(results_csv).parent / "summary.json").read_text())["stop_distance_m"]
    columns = read_header(results_csv)[1:]
    data = read_results(results_csv)
    rows = [(t, list(values)) for t, *values in zip(data["time"], *(data[c] for c in columns))]
    traced, reread, appends = [], [], []
    for _ in range(repeats):
        started = time.perf_counter()
        trace = RowTrace(columns, len(rows))
        for t, values in rows:
            trace.append(t, values)
        appends.append(time.perf_counter() - started)
        started = time.perf_counter()
        ours = summary_figures(trace, (), stop)
        traced.append(time.perf_counter() - started)
        started = time.perf_counter()
        reference = summary_figures_from_csv(results_csv, (), stop)
        reread.append(time.perf_counter() - started)
    return {"rows": len(rows), "from_kept_rows_s": median(traced),
            "from_csv_reread_s": median(reread), "keeping_the_rows_s": median(appends),
            "same_figures": ours == reference}


FLOORS = {"interpreter": "pass",
          "numpy": "import numpy",
          "numpy_fmpy": "import numpy, fmpy, fmpy.fmi2",
          "numpy_matplotlib_agg": "import numpy, matplotlib.figure, "
                                  "matplotlib.backends.backend_agg"}


def start_up_floors(repeats):
    """Wall seconds of fresh interpreters that only import what a run cannot do without
    (numpy: the FMUs' models; fmpy: the FMI host) or what drawing needs (matplotlib)."""
    environment = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    walls = {name: [] for name in FLOORS}
    for _ in range(repeats + 1):   # the first round warms the bytecode and file caches
        for name, code in FLOORS.items():
            started = time.perf_counter()
            subprocess.run([sys.executable, "-c", code], check=True, env=environment)
            walls[name].append(time.perf_counter() - started)
    return {name: median(values[1:]) for name, values in walls.items()}


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


def libcosim_run(ssd, step, stop, observer):
    from orchestrator.crosscheck import run_libcosim_ssd

    timing, rows = run_libcosim_ssd(ssd, step, stop, ["plant.x", "plant.y"], observer=observer)
    return timing, np.array(rows)


def _single_rate_scenario(step, stop, outputs):
    from orchestrator.scenario import scenario_from_dict

    return scenario_from_dict({
        "name": "single_rate", "system": str(SSD), "stop_time": stop, "base_step": step,
        "steps": {name: step for name in INSTANCES}, "seed": 1, "master": "jacobi",
        "outputs": list(outputs)})


def ours_single_rate(fmu_dir, step, stop, out, outputs):
    from orchestrator.run import run_scenario

    started = time.perf_counter()
    result = run_scenario(_single_rate_scenario(step, stop, outputs), out, progress=False,
                          fmu_dir=fmu_dir, plots=False, record_interval=step)
    wall = time.perf_counter() - started
    with open(result.results_csv) as f:
        rows = list(csv.DictReader(f))[1:]
    timing = {"wall_s": wall, "stepping_s": result.summary["wall_time_s"]}
    return timing, np.array([[float(r["plant.x"]), float(r["plant.y"])] for r in rows])


def ours_fmi_calls(fmu_dir, step, stop, out, outputs):
    """Count our master's FMI calls (get, set, doStep) on the single-rate system."""
    from orchestrator import fmu
    from orchestrator.run import run_scenario

    calls = [0]

    class CountedInstance(fmu.FmuInstance):
        def read(self, group):
            calls[0] += 1
            return super().read(group)

        def write(self, group):
            calls[0] += 1
            return super().write(group)

        def do_step(self, time_, step_):
            calls[0] += 1
            return super().do_step(time_, step_)

    original = fmu.FmuInstance
    fmu.FmuInstance = CountedInstance  # run_scenario looks the class up at call time
    try:
        run_scenario(_single_rate_scenario(step, stop, outputs), out, progress=False,
                     fmu_dir=fmu_dir, plots=False, record_interval=step)
    finally:
        fmu.FmuInstance = original
    return calls[0]


def fmi_call_floor_us(path, repeats=3, number=5000):
    """Median cost of the cheapest FMI call we make: fmi2GetReal of one output of an FMU."""
    import timeit

    from orchestrator.fmu import FmuInstance

    instance = FmuInstance(path, "floor")
    instance.instantiate(start_time=0.0, stop_time=1.0)
    group = instance.port_group("Real", ["voltage"])
    times = timeit.repeat(lambda: instance.read(group), number=number, repeat=repeats)
    instance.terminate()
    return median(times) / number * 1e6


def model_compute_s(fmu_dir, step, stop, out):
    """Seconds the slaves spend in ``do_step`` on the single-rate system, timed in-process."""
    from orchestrator import inprocess
    from orchestrator.run import run_scenario

    spent = {}

    class TimedSlave(inprocess.SlaveInstance):
        def do_step(self, time_, step_):
            started = time.perf_counter()
            try:
                super().do_step(time_, step_)
            finally:
                spent[self.name] = spent.get(self.name, 0.0) + time.perf_counter() - started

    original = inprocess.SlaveInstance
    inprocess.SlaveInstance = TimedSlave  # run_scenario looks the class up at call time
    try:
        run_scenario(_single_rate_scenario(step, stop, ["plant.x", "plant.y"]), out,
                     progress=False, fmu_dir=fmu_dir, plots=False, record_interval=step,
                     backend="in-process")
    finally:
        inprocess.SlaveInstance = original
    return sum(spent.values()), spent


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="repetitions of each timing")
    parser.add_argument("--single-rate-stop", type=float, default=10.0,
                        help="simulated seconds of the libcosim comparison")
    args = parser.parse_args(argv)

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

    # Whole commands, every variant in turn, interleaved; shares are taken per command. One
    # command first, not counted, so bytecode and the FMU extraction cache exist as they do
    # for a user's second command.
    run_command_phases(fmu_dir, work / "command_warm_up")
    commands = {name: [] for name in VARIANTS}
    for r in range(args.repeats):
        for name, (variant, plots) in VARIANTS.items():
            wall, phases, renderers = run_command_phases(fmu_dir, work / f"command_{name}{r}",
                                                         variant, plots)
            commands[name].append((wall, phases, renderers))
            print(f"sonotrack run ({name.replace('_', ' ')}) {r + 1}/{args.repeats}: "
                  f"{wall:.2f} s, " + ", ".join(f"{p} {phases[p]:.2f}" for p in PHASES),
                  flush=True)

    def command_record(runs):
        walls = [wall for wall, _, _ in runs]
        shares = {p: median([phases[p] / wall for wall, phases, _ in runs]) for p in PHASES}
        # the critical path: until summary.json is on disk (plots come after it)
        to_summary = [sum(phases[p] for p in ("start-up", "set-up", "stepping", "summary"))
                      for _, phases, _ in runs]
        record = {
            "wall_s": median(walls),
            "to_summary_on_disk_s": median(to_summary),
            "not_stepping_share_to_summary": median([1 - phases["stepping"] / total for
                                                     (_, phases, _), total in zip(runs,
                                                                                  to_summary)]),
            "wall_runs_s": walls,
            "phases_s": {p: median([phases[p] for _, phases, _ in runs]) for p in PHASES},
            "phase_shares": shares,
            "not_stepping_share": median([1 - phases["stepping"] / wall
                                          for wall, phases, _ in runs]),
            # in seconds too: a renderer slowing the stepping down would flatter the share
            "not_stepping_s": median([wall - phases["stepping"] for wall, phases, _ in runs]),
        }
        renderers = [r for _, _, rs in runs for r in rs]
        if renderers:
            record["renderers"] = {key: median([r[key] for r in renderers])
                                   for key in renderers[0]}
        return record

    summary_costs = summary_figures_cost(work / "command_plots0" / "results.csv", args.repeats)
    import_floors = start_up_floors(args.repeats)

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
    single_steps = len(INSTANCES) * int(round(stop / step))
    recordings = {
        # name: (libcosim observer, our recorded outputs; [] is every output)
        "every_output": ("last_value", []),
        "trajectory": ("time_series", ["plant.x", "plant.y"]),
    }
    calls = {name: ours_fmi_calls(fmu_dir, step, stop, work / f"calls_{name}", outputs)
             for name, (_, outputs) in recordings.items()}
    timings = {name: {"libcosim": [], "ours": []} for name in recordings}
    models, model_split, floors = [], [], []
    difference = 0.0
    # One repetition runs everything once, close together in time; ratios are taken within a
    # repetition and their medians reported (this machine's speed drifts ~2x over minutes).
    for r in range(args.repeats):
        for name, (observer, outputs) in recordings.items():
            timing, theirs = libcosim_run(ssd, step, stop, observer)
            timings[name]["libcosim"].append(timing)
            timing, ours = ours_single_rate(fmu_dir, step, stop, work / f"{name}{r}", outputs)
            timings[name]["ours"].append(timing)
            difference = max(difference, float(np.max(np.hypot(*(ours - theirs).T))))
            print(f"single rate {stop:g} s, {name}: libcosim "
                  f"{timings[name]['libcosim'][-1]['wall_s']:.2f} s, ours "
                  f"{timings[name]['ours'][-1]['wall_s']:.2f} s, max trajectory difference "
                  f"{difference:.3g} m", flush=True)
        total, split = model_compute_s(fmu_dir, step, stop, work / f"model{r}")
        models.append(total)
        model_split.append(split)
        floors.append(fmi_call_floor_us(fmus["WheelController"]))
    model = median(models)

    def summarise(name):
        lib = timings[name]["libcosim"]
        ours = timings[name]["ours"]
        lib_step = [t["stepping_s"] for t in lib]
        ours_step = [t["stepping_s"] for t in ours]
        lib_overhead = [(a - m) / single_steps for a, m in zip(lib_step, models)]
        ours_overhead = [(a - m) / single_steps for a, m in zip(ours_step, models)]
        floor_s = [m + calls[name] * f * 1e-6 for m, f in zip(models, floors)]
        return {
            "libcosim_observer": recordings[name][0],
            "ours_recorded_outputs": recordings[name][1] or "every output",
            "libcosim_wall_s": median([t["wall_s"] for t in lib]),
            "ours_wall_s": median([t["wall_s"] for t in ours]),
            "speedup_ours_over_libcosim": median([a["wall_s"] / b["wall_s"]
                                                  for a, b in zip(lib, ours)]),
            "speedup_runs": [a["wall_s"] / b["wall_s"] for a, b in zip(lib, ours)],
            "libcosim_stepping_s": median(lib_step), "ours_stepping_s": median(ours_step),
            "stepping_speedup_ours_over_libcosim": median([a / b for a, b in
                                                           zip(lib_step, ours_step)]),
            "libcosim_overhead_us_per_instance_step": median(lib_overhead) * 1e6,
            "ours_overhead_us_per_instance_step": median(ours_overhead) * 1e6,
            # The stepping speed-up if the models cost nothing: the masters' overheads alone.
            "stepping_speedup_bound_without_model_time": median(
                [a / b for a, b in zip(lib_overhead, ours_overhead) if b > 0]),
            # A floor under any master that makes our calls: the models' time plus every FMI
            # call at the cost of the cheapest one. libcosim's stepping over it is the best
            # stepping speed-up such a master could show here.
            "ours_fmi_calls": calls[name],
            "ours_stepping_floor_s": median(floor_s),
            "stepping_speedup_upper_bound": median([a / b for a, b in zip(lib_step, floor_s)]),
        }

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
        "run_command": {
            "command": "sonotrack run scenarios/s_curve.toml --out DIR --fmu-dir DIR "
                       "(progress bar on; stdout and stderr to /dev/null; bytecode caching on; "
                       "after one uncounted command)",
            **{name: command_record(runs) for name, runs in commands.items()},
            "summary_figures": summary_costs,
            "floors_s": import_floors,
            "not_stepping_share_target": 0.40,
            "note": "phases from wall-clock timestamps in the command's own process, which "
                    "partition its wall time: start-up = process spawn to run_scenario entered "
                    "(interpreter, imports, parsing, the scenario's checks; the timing wrapper "
                    "imports orchestrator.run before parsing, which the CLI does after); set-up "
                    "= to the first step (system, FMU instances, spawning the renderers); "
                    "summary = last step to the ok summary.json on disk; plots = from there to "
                    "run_scenario's return (waiting for the renderers to write the PNGs, or "
                    "drawing in-process in plots_in_process; and the summary's rewrite naming "
                    "the plots); exit = to the process's end. not_stepping_share = 1 - stepping "
                    "/ wall: the share of the command's wall time during which it is not "
                    "stepping, whatever runs in parallel; the target is judged on it, with "
                    "plots (the default) and without. renderers: medians over every renderer "
                    "process of its warm-up (interpreter, numpy, matplotlib, a throw-away "
                    "figure), the part of it that overlapped the parent's set-up and stepping, "
                    "how long after the summary it was still warming up, and its drawing. "
                    "Variants: plots = as shipped (one renderer process, which forks once "
                    "the summary is on disk to draw two figures per core), plots_one_renderer "
                    "= the renderer drawing all four figures itself, plots_in_process = the "
                    "command before the renderer (matplotlib imported and every figure drawn "
                    "in its own process after the summary). Medians over repeats; shares are "
                    "medians of per-command shares; not_stepping_s = wall - stepping (a "
                    "renderer competing with the stepping for a core lengthens the stepping "
                    "and so lowers the share: compare stepping with no_plots'). floors_s: "
                    "fresh interpreters importing only what a run or a drawing cannot do "
                    "without.",
        },
        "in_process_realtime_factor": median(inprocess_rtf),
        "fmi_over_in_process_wall_ratio": median(fmi_wall) / median(inprocess_wall),
        "fmi_over_in_process_target": 3.0,
        "libcosim_single_rate": {
            "step_s": step, "stop_time_s": stop, "instance_steps": single_steps,
            "speedup_target": 3.0,
            "model_compute_s": model,
            "fmi_call_floor_us": median(floors),
            "model_compute_by_instance_s": {name: median([s[name] for s in model_split])
                                            for name in model_split[0]},
            "every_output": summarise("every_output"),
            "trajectory": summarise("trajectory"),
            "max_trajectory_difference_m": difference,
            "difference_target_m": 1e-6,
            "note": "wall: both include loading the system and instantiating the FMUs (ours "
                    "also writes results.csv and summary.json); stepping: the step loop only. "
                    "libcosim runs in a child process and is timed inside it. model_compute_s: "
                    "the slaves' do_step time on the same system run in-process (no FMI); "
                    "overhead = (stepping - model_compute) / instance_steps",
        },
    }
    out = write_result("cosim_speed", record)
    single_rate = record["libcosim_single_rate"]
    print(f"realtime factor {record['realtime_factor']:.1f} (target 20); FMI/in-process "
          f"{record['fmi_over_in_process_wall_ratio']:.2f} (target <= 3)")
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
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
