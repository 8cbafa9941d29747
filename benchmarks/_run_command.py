"""The ``run_command`` part of benchmarks/cosim_speed.py: a whole ``sonotrack run`` by phase.

:func:`measure` times the default ``sonotrack run`` command in fresh processes, every variant
of :data:`VARIANTS` in turn and interleaved, each split into :data:`PHASES` by
:func:`run_command_phases` (timestamps from benchmarks/_run_phases.py);
:func:`summary_figures_cost` times the summary's figures from the kept rows against
re-reading results.csv; :func:`start_up_floors` times fresh interpreters that import only what
a run or a drawing cannot do without; :func:`section` makes the JSON's ``run_command``
section of them. Not a benchmark by itself (``make benchmarks`` skips files starting with
``_``).
"""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

from _common import median

__all__ = ["FLOORS", "PHASES", "VARIANTS", "command_record", "measure", "run_command_phases",
           "section", "start_up_floors", "summary_figures_cost"]

ROOT = Path(__file__).resolve().parent.parent

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
    from orchestrator.run.results import read_header, read_results
    from orchestrator.run.summary import ResultRows, RowTrace, summary_figures

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
        reference = summary_figures(ResultRows(results_csv), (), stop)
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


def measure(fmu_dir, work, repeats):
    """Run every variant's command ``repeats`` times, interleaved; return {variant: runs}.

    Each run is ``(wall_s, phases, renderers)`` of :func:`run_command_phases`.
    """
    # Whole commands, every variant in turn, interleaved; shares are taken per command. One
    # command first, not counted, so bytecode and the FMU extraction cache exist as they do
    # for a user's second command.
    run_command_phases(fmu_dir, work / "command_warm_up")
    commands = {name: [] for name in VARIANTS}
    for r in range(repeats):
        for name, (variant, plots) in VARIANTS.items():
            wall, phases, renderers = run_command_phases(fmu_dir, work / f"command_{name}{r}",
                                                         variant, plots)
            commands[name].append((wall, phases, renderers))
            print(f"sonotrack run ({name.replace('_', ' ')}) {r + 1}/{repeats}: "
                  f"{wall:.2f} s, " + ", ".join(f"{p} {phases[p]:.2f}" for p in PHASES),
                  flush=True)
    return commands


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


def section(commands, summary_costs, import_floors):
    """The JSON's ``run_command`` section: one :func:`command_record` per variant of
    :func:`measure`'s ``commands``, the summary's figures' cost and the start-up floors."""
    return {
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
                "imports orchestrator.run.runner before parsing, which the CLI does after); set-up "
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
    }
