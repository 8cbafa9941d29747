"""The whole-system FMU's cost per simulated second against ``sonotrack run --no-plots``.

Part of benchmarks/cosim_speed.py (its ``system_fmu`` section; ``--system-fmu-only`` measures
this alone into results/cosim_speed_system_fmu.json); also runnable alone, printing only:

    python benchmarks/_system_fmu.py [--repeats 3]

Both sides run the default scenario (scenarios/s_curve.toml, 30 s) with the same settings, in
alternation, ``repeats`` times each (medians reported):

* ``command``: a fresh process each, as a user types it: ``sonotrack run --no-plots --quiet``
  (start-up, set-up, stepping, results.csv, summary.json) against a Python process that runs
  ``TrackingSystem.fmu`` with ``fmpy.simulate_fmu`` at 20 ms and writes every output to a CSV
  with ``fmpy.util.write_csv`` (start-up, unpacking, stepping, the CSV);
* ``stepping``: in this process, the run's stepping (its master's ``run``: every step, every
  output recorded to results.csv) against fmi2DoStep plus one fmi2Get per type of every output
  per 20 ms step of the system FMU through fmpy.

Each is given in wall time and in CPU time (user + system of the child processes for the
commands, of this process for the stepping): on a machine others share, the CPU time is the
steadier figure. The ratio is system FMU over ``sonotrack run``: below 1, the one FMU is
cheaper.
"""

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "scenarios" / "s_curve.toml"
STEP = 0.02

_FMPY_COMMAND = """
import sys
import fmpy
from fmpy.util import write_csv
result = fmpy.simulate_fmu(sys.argv[1], stop_time=float(sys.argv[2]), step_size={step},
                           output_interval={step})
write_csv(sys.argv[3], result)
""".format(step=STEP)


def _children_cpu():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _command(argv):
    """(wall, CPU) seconds of a command in a fresh process."""
    started, cpu = time.perf_counter(), _children_cpu()
    subprocess.run(argv, check=True, capture_output=True, text=True)
    return time.perf_counter() - started, _children_cpu() - cpu


def _run_stepping(scenario, out, fmu_dir):
    """(wall, CPU) seconds of the master's stepping in ``sonotrack run`` (run_scenario)."""
    import orchestrator.run.master as master
    from orchestrator.run.runner import run_scenario

    timed = []
    original = master.Master.run

    def run(self, *args, **kwargs):
        started, cpu = time.perf_counter(), time.process_time()
        try:
            return original(self, *args, **kwargs)
        finally:
            timed.append((time.perf_counter() - started, time.process_time() - cpu))

    master.Master.run = run
    try:
        run_scenario(scenario, out, progress=False, fmu_dir=fmu_dir, plots=False)
    finally:
        master.Master.run = original
    return timed[0]


def _fmu_stepping(fmu_path, stop_time):
    """(wall, CPU) seconds of doStep and the outputs' gets over the run, through fmpy."""
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    folder = tempfile.mkdtemp(prefix="sonotrack_system_fmu_")
    fmpy.extract(str(fmu_path), folder)
    description = fmpy.read_model_description(folder)
    slave = FMU2Slave(guid=description.guid, unzipDirectory=folder,
                      modelIdentifier=description.coSimulation.modelIdentifier,
                      instanceName="bench")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    groups = {}
    for variable in description.modelVariables:
        if variable.causality == "output":
            groups.setdefault(variable.type, []).append(variable.valueReference)
    getters = [(slave.getReal, groups["Real"]), (slave.getInteger, groups["Integer"]),
               (slave.getBoolean, groups["Boolean"])]
    steps = int(round(stop_time / STEP))
    started, cpu = time.perf_counter(), time.process_time()
    for k in range(steps):
        slave.doStep(currentCommunicationPoint=k * STEP, communicationStepSize=STEP)
        for get, references in getters:
            get(references)
    timing = time.perf_counter() - started, time.process_time() - cpu
    slave.terminate()
    slave.freeInstance()
    return timing


def measure(fmu_dir, work, repeats):
    """Both sides ``repeats`` times, alternating; return the ``system_fmu`` record."""
    from orchestrator.run.as_fmu import build_scenario_fmu
    from orchestrator.scenario import load_scenario

    from _common import median

    work = Path(work)
    scenario = load_scenario(SCENARIO)
    fmu = build_scenario_fmu(scenario, work / "system_fmu", fmu_dir=fmu_dir)
    sonotrack = Path(sys.executable).with_name("sonotrack")
    run_argv = [str(sonotrack), "run", str(SCENARIO), "--no-plots", "--quiet",
                "--fmu-dir", str(fmu_dir)]
    fmpy_argv = [sys.executable, "-c", _FMPY_COMMAND, str(fmu), repr(scenario.stop_time)]
    # one of each first, not counted: bytecode and the FMU unpacking cache exist as they do
    # for a user's second command
    _command(run_argv + ["--out", str(work / "warm_run")])
    _command(fmpy_argv + [str(work / "warm_fmu.csv")])
    runs = {"run_command": [], "fmu_command": [], "run_stepping": [], "fmu_stepping": []}
    for r in range(repeats):
        runs["run_command"].append(_command(run_argv + ["--out", str(work / f"run{r}")]))
        runs["fmu_command"].append(_command(fmpy_argv + [str(work / f"fmu{r}.csv")]))
        runs["run_stepping"].append(_run_stepping(scenario, work / f"stepping{r}", fmu_dir))
        runs["fmu_stepping"].append(_fmu_stepping(fmu, scenario.stop_time))
        print(f"system FMU {r + 1}/{repeats} (wall, CPU s): command "
              f"{runs['fmu_command'][-1]} vs sonotrack run {runs['run_command'][-1]}; stepping "
              f"{runs['fmu_stepping'][-1]} vs {runs['run_stepping'][-1]}", flush=True)
    stop = scenario.stop_time
    record = {"scenario": "scenarios/s_curve.toml", "simulated_s": stop,
              "fmu_step_s": STEP, "repeats": repeats, "runs_s": runs,
              # 1-minute load average at the end (2 cores: above ~2, others shared them)
              "load_average_1min": os.getloadavg()[0]}
    for part in ("command", "stepping"):
        record[part] = {}
        for index, clock in enumerate(("wall", "cpu")):
            ours = median([timing[index] for timing in runs[f"fmu_{part}"]])
            theirs = median([timing[index] for timing in runs[f"run_{part}"]])
            record[part][clock] = {"system_fmu_s_per_simulated_s": ours / stop,
                                   "sonotrack_run_s_per_simulated_s": theirs / stop,
                                   "ratio_system_fmu_to_run": ours / theirs}
    return record


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="repetitions of each side")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from _common import build_fresh

    fmus = build_fresh(["RobotPlant", "SoundSource", "AcousticLocalizer", "CurvaturePlanner",
                        "WheelController"])
    fmu_dir = next(iter(fmus.values())).parent
    record = measure(fmu_dir, tempfile.mkdtemp(prefix="sonotrack_system_fmu_"), args.repeats)
    print(summary_line(record))   # the figure of record is cosim_speed.json's system_fmu
    return 0


def summary_line(record):
    """One line per part with the cost per simulated second and the ratio, wall and CPU."""
    lines = []
    for part, label in (("command", "command (vs sonotrack run --no-plots)"),
                        ("stepping", "stepping")):
        cells = []
        for clock in ("wall", "cpu"):
            row = record[part][clock]
            cells.append(f"{clock} {row['system_fmu_s_per_simulated_s'] * 1e3:.1f} vs "
                         f"{row['sonotrack_run_s_per_simulated_s'] * 1e3:.1f} ms "
                         f"(ratio {row['ratio_system_fmu_to_run']:.2f})")
        lines.append(f"system FMU per simulated second, {label}: " + "; ".join(cells))
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
