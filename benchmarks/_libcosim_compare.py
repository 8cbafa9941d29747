"""The libcosim comparison of benchmarks/cosim_speed.py: one single-rate system, two masters.

:func:`compare` runs fmus/SystemStructure.ssd at a single rate (:func:`single_rate_ssd`)
through libcosim (``CosimExecution.from_ssp_file``, :func:`libcosim_run`) and through our
master (Jacobi, :func:`ours_single_rate`), alternating, recording every output and only the
robot trajectory; it splits each master's stepping time into the models' own compute time
(:func:`model_compute_s`, the slaves' ``do_step`` timed in-process) and master overhead, and
puts a floor under our stepping time from our FMI calls (:func:`ours_fmi_calls`) at the cost
of the cheapest one (:func:`fmi_call_floor_us`). It returns the JSON's
``libcosim_single_rate`` section. Not a benchmark by itself (``make benchmarks`` skips files
starting with ``_``).
"""

import csv
import time
from pathlib import Path

import numpy as np

from _common import median

__all__ = ["INSTANCES", "SSD", "compare", "fmi_call_floor_us", "libcosim_run",
           "model_compute_s", "ours_fmi_calls", "ours_single_rate", "single_rate_ssd"]

ROOT = Path(__file__).resolve().parent.parent
SSD = ROOT / "fmus" / "SystemStructure.ssd"
INSTANCES = ("source", "localizer", "planner", "controller_left", "controller_right", "plant")


def single_rate_ssd(fmu_dir):
    from orchestrator.ssp import read_ssd, write_ssd

    path = Path(fmu_dir) / "SingleRate.ssd"
    write_ssd(path, read_ssd(SSD).without_step_hints())
    return path


def libcosim_run(ssd, step, stop, observer):
    from orchestrator.hosts.libcosim import run_libcosim_ssd

    timing, rows = run_libcosim_ssd(ssd, step, stop, ["plant.x", "plant.y"], observer=observer)
    return timing, np.array(rows)


def _single_rate_scenario(step, stop, outputs):
    from orchestrator.scenario import scenario_from_dict

    return scenario_from_dict({
        "name": "single_rate", "system": str(SSD), "stop_time": stop, "base_step": step,
        "steps": {name: step for name in INSTANCES}, "seed": 1, "master": "jacobi",
        "outputs": list(outputs)})


def ours_single_rate(fmu_dir, step, stop, out, outputs):
    from orchestrator.run.runner import run_scenario

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
    from orchestrator.fmu import handle as fmu
    from orchestrator.run.runner import run_scenario

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

    from orchestrator.fmu.handle import FmuInstance

    instance = FmuInstance(path, "floor")
    instance.instantiate(start_time=0.0, stop_time=1.0)
    group = instance.port_group("Real", ["voltage"])
    times = timeit.repeat(lambda: instance.read(group), number=number, repeat=repeats)
    instance.terminate()
    return median(times) / number * 1e6


def model_compute_s(fmu_dir, step, stop, out):
    """Seconds the slaves spend in ``do_step`` on the single-rate system, timed in-process."""
    from orchestrator.fmu import inprocess
    from orchestrator.run.runner import run_scenario

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


def compare(fmu_dir, floor_fmu, work, repeats, stop):
    """Run the comparison ``repeats`` times for ``stop`` simulated seconds at a 0.01 s step.

    ``fmu_dir`` holds the freshly built FMUs, ``floor_fmu`` the WheelController FMU whose
    ``fmi2GetReal`` sets the FMI call floor, ``work`` a scratch folder. Returns the JSON's
    ``libcosim_single_rate`` section.
    """
    ssd = single_rate_ssd(fmu_dir)
    step = 0.01
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
    for r in range(repeats):
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
        floors.append(fmi_call_floor_us(floor_fmu))
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
    return {
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
    }
