"""One run: a scenario in, a results folder out (``results.csv``, ``summary.json``, plots).

:func:`run_scenario` is the single code path of the CLI, the reports and the sweeps. It
checks the system and the scenario before t0 (every problem at once), then steps the master
with a progress bar, streaming results to disk; if an FMU fails, the rows so far and a
summary saying what failed stay on disk and :class:`SimulationError` is raised.

What the run needs is resolved once into a :class:`~orchestrator.run.plan.RunPlan`; what is
particular to the sonotrack system (the planner's stop distance, the columns always
recorded) comes from :mod:`orchestrator.system.sonotrack`, never from here.
"""

import math
import time as wallclock
from dataclasses import dataclass, field
from pathlib import Path

from components.common.errors import ConfigError, RunInterrupted, SimulationError
from orchestrator.run.plan import BACKENDS, RunPlan, plan_run

__all__ = ["BACKENDS", "RunResult", "run_scenario"]


@dataclass
class RunResult:
    """What a run leaves: its summary and the paths of its files, every path absolute.

    Attributes
    ----------
    summary : dict
        What ``summary.json`` holds.
    out_dir, results_csv, summary_json : pathlib.Path
        The run's folder and its two files (absolute, whatever folder the run was given as).
    plots : list of pathlib.Path
        The PNG files written (absolute).
    plots_error : str or None
        Why some plots could not be drawn (one line), if so.
    data : dict or None
        With ``keep_rows``: every column of ``results.csv`` (``{column: array}``, the very
        values :func:`~orchestrator.run.results.read_results` reads back), if the run ended
        ``ok`` and its rows were held in memory; else None (read the file).
    """

    summary: dict
    out_dir: Path
    results_csv: Path
    summary_json: Path
    plots: list = field(default_factory=list)
    plots_error: str | None = None
    data: dict | None = None


def run_scenario(scenario, out_dir, progress=True, fmu_dir=None, plots=True,
                 algorithm=None, record_interval=0.02, backend="fmi", fsync=False,
                 system=None, handles=None, sync_summary=True, allow_outside=False,
                 keep_rows=False):
    """Run one scenario through our master on fmpy.

    The results folder is checked before anything runs; an older run's files in it are
    cleared and ``summary.json`` says ``"running"`` before the first FMU is instantiated
    (see :mod:`orchestrator.run.folder`). The summary says ``"ok"`` only once the last step is
    done and ``results.csv`` is complete; a failure or a signal is written into it as soon as
    it is known (``"failed"`` or ``"interrupted"`` with ``error``), and a run that is killed
    leaves ``"running"``, which readers report as ``"abandoned"`` once its process is gone
    (:func:`orchestrator.run.folder.read_summary`). SIGINT and SIGTERM stop the run after the
    step in progress.

    Parameters
    ----------
    scenario : Scenario or path-like
        A loaded scenario or the path of a TOML scenario file.
    out_dir : path-like
        Folder for ``results.csv``, ``summary.json`` and the plots.
    progress : bool
        Show a progress bar on stderr.
    fmu_dir : path-like, optional
        Where the FMUs are, if not beside the ``.ssd``.
    plots : bool
        Write the PNG plots. Renderer processes get ready while the run steps and draw
        once the summary is on disk (:mod:`orchestrator.run.plot_renderer`); the call returns
        when the PNGs are written. If they cannot be, the run's results stand: the summary's
        ``plots_error`` and :attr:`RunResult.plots_error` say why (one line).
    algorithm : {"gauss-seidel", "jacobi"}, optional
        Overrides the scenario's ``master``.
    record_interval : float, optional
        Simulated time between recorded rows, rounded to a whole number of base steps
        (default 0.02 s, the speed loop's period; at most one row per base step).
    backend : {"fmi", "in-process"}
        ``"fmi"`` steps the FMUs through fmpy; ``"in-process"`` steps the same slave classes
        directly in this process (no FMI), to measure what the FMI layer costs.
    fsync : bool
        fsync ``results.csv`` at every flush (once a simulated second), not only at the end.
    system : orchestrator.system.System, optional
        The scenario's system, already loaded with the same ``fmu_dir`` (a sweep worker
        keeps it between runs); default: loaded from ``scenario.system``.
    handles : callable, optional
        ``handles(instance_name, fmu_path)`` returns the FMU handle of an instance for the
        ``"fmi"`` backend (a sweep worker passes warm, reusable ones); default a new
        :class:`~orchestrator.fmu.handle.FmuInstance` each.
    sync_summary : bool
        fsync ``summary.json`` (and its folder) at each write, so it survives a power cut. A
        sweep's worker passes False (four fsyncs, most of a warm run's overhead):
        ``results.csv`` is still fsync'ed before the summary can say ok, and a sweep runs
        again any run whose summary is missing or unreadable.
    allow_outside : bool
        Let the scenario and system files name files outside their own folders (waypoint
        CSVs, ``.ssv`` parameter files; see :mod:`orchestrator.files.paths`).
    keep_rows : bool
        Hold every recorded row in memory too (up to the summary's trace limit,
        :data:`~orchestrator.run.summary.MAX_TRACE_ROWS`) and return them as
        :attr:`RunResult.data`, for a caller that would otherwise read ``results.csv`` back.

    Returns
    -------
    RunResult

    Raises
    ------
    ConfigError
        Before anything is written, for a bad scenario, system or results folder.
    SimulationError
        If an FMU failed (the summary says ``"failed"``; rows so far are in the CSV).
    RunInterrupted
        If SIGINT or SIGTERM stopped the run (the summary says ``"interrupted"``).
    """
    from orchestrator.run.folder import RunFolder
    from orchestrator.run.plots import PLOT_FILES
    from orchestrator.scenario import load_scenario
    from orchestrator.system import load_system

    if not hasattr(scenario, "stop_time"):
        scenario = load_scenario(scenario, allow_outside=allow_outside)
    if system is None:
        system = load_system(scenario.system, fmu_dir=fmu_dir, allow_outside=allow_outside)
    plan = plan_run(scenario, system, algorithm=algorithm, record_interval=record_interval,
                    backend=backend, fsync=fsync, handles=handles)
    folder = RunFolder(out_dir, own_files=PLOT_FILES, fsync=sync_summary)
    folder.check()
    renderer = None
    if plots:
        from orchestrator.run.plot_renderer import PlotRenderer

        renderer = PlotRenderer()   # imports matplotlib on another core while we step
    try:
        return _run(plan, folder, progress, renderer, keep_rows)
    finally:
        if renderer is not None:
            renderer.close()


def _run(plan: RunPlan, folder, progress, renderer, keep_rows=False):
    """run_scenario once its plan is made and its folder is ready."""
    from orchestrator.fmu.handle import FmuInstance
    from orchestrator.run.master import InstanceSpec, Link, Master
    from orchestrator.run.summary import RowTrace
    from orchestrator.processes import process_record
    from orchestrator.run.signals import StopSignals
    from orchestrator.system.sonotrack import SONOTRACK

    scenario, system, columns = plan.scenario, plan.system, plan.columns
    if plan.backend == "fmi":
        make = plan.handles or FmuInstance
        instances = {name: make(system.component(name).fmu_path, name) for name in plan.order}
    else:
        from orchestrator.fmu.inprocess import SlaveInstance

        instances = {name: SlaveInstance(system.component(name).model_description.modelName,
                                         name) for name in plan.order}
    specs = [InstanceSpec(name, instances[name], plan.rates[name], plan.parameters[name])
             for name in plan.order]
    links = [Link(str(c.start), str(c.end)) for c in system.connections]
    master = Master(specs, links, scenario.base_step, plan.algorithm, observed=columns)

    record_every = plan.record_every
    # scenarios start at t = 0 (the schema has no start time); time is t0 + k * base_step
    start_time = 0.0
    steps_total = scenario.step_count
    summary = {
        "scenario": getattr(scenario, "name", ""),
        "status": "running",
        "sim_time_s": 0.0,
        "stop_time_s": scenario.stop_time,
        "steps": 0,
        "master": master.algorithm,
        "base_step_s": scenario.base_step,
        "seed": scenario.seed,
        "controller": SONOTRACK.controller_mode(system, plan.parameters),
        # who writes this file: a reader takes "running" from a process that is gone as
        # "abandoned" (orchestrator.run.folder)
        "process": process_record(),
    }
    folder.start(summary)

    def settle(status, error):
        """Write what is known the moment the run's fate is known."""
        summary.update(status=status, sim_time_s=master.steps_done * scenario.base_step,
                       steps=master.steps_done, error=error)
        folder.write_summary(summary)

    error = None
    recorder = trace = None
    bar = None
    started = wallclock.perf_counter()
    with StopSignals() as stop:
        try:
            master.initialize(start_time=start_time, stop_time=scenario.stop_time)
            read_row = _ColumnReader(master, system, columns)
            bar = _progress(steps_total, scenario, progress)
            recorder = _open_recorder(folder.results_csv, columns, plan.fsync)
            # with keep_rows the summary's trace holds every column: one copy per row either way
            trace = RowTrace(columns, plan.expected_rows, getattr(scenario, "faults", ()),
                             every_column=keep_rows)
            row = read_row()
            recorder.record(start_time, row)
            trace.append(start_time, row)
            bar_every = max(1, steps_total // 200)

            def on_step(k, t):
                if k % record_every == 0:
                    row = read_row()
                    recorder.record(t, row)
                    trace.append(t, row)
                if bar is not None and k % bar_every == 0:
                    bar.update(bar_every)
                if stop.received is not None:
                    raise _Stop

            if stop.received is None:
                master.run(start_time + steps_total * scenario.base_step, on_step)
            if stop.received is not None:
                raise _Stop
            recorder.close()  # fsync'ed and complete before the summary may say ok
        except SimulationError as exc:
            error = str(exc)
            settle("failed", error)
        except _Stop:
            error = (f"interrupted by {stop.name} at t = "
                     f"{master.steps_done * scenario.base_step:.6g} s")
            settle("interrupted", error)
        except BaseException as exc:
            # anything else (a full disk, a bug): say so in the summary, then let it go up
            try:
                settle("failed", f"{type(exc).__name__}: {exc}")
            finally:
                _close_quietly(recorder, master, bar)
            raise
        finally:
            wall_time = wallclock.perf_counter() - started
        _close_quietly(recorder, master, bar)

    sim_time = master.steps_done * scenario.base_step
    summary.update({
        "status": "ok" if error is None else summary["status"],
        "sim_time_s": sim_time,
        "wall_time_s": wall_time,
        "realtime_factor": sim_time / wall_time if wall_time > 0 else float("inf"),
        "steps": master.steps_done,
    })
    if error is None:
        summary.pop("error", None)
    if recorder is not None and recorder.rows > 1:
        from orchestrator.run.summary import ResultRows, has_figures, summary_figures

        if has_figures(columns):
            summary["stop_distance_m"] = plan.stop_distance
            # the file is the record of what a failed or long run kept
            kept = error is None and trace.kept and trace.rows == recorder.rows
            rows = trace if kept else ResultRows(folder.results_csv)
            summary.update(summary_figures(rows, getattr(scenario, "faults", ()),
                                           plan.stop_distance))
            error = _non_finite_metrics(summary, error)
    interrupted = summary["status"] == "interrupted"
    drawing = (renderer is not None and not interrupted and recorder is not None
               and recorder.rows > 1)
    if drawing:
        summary["plots"] = "drawing"   # until the PNGs are written (a kill leaves this)
    folder.write_summary(summary)
    written, plots_error = [], None
    if drawing:
        from orchestrator.run.plot_renderer import PlotError

        try:
            written = renderer.render(folder.results_csv, folder.path, _PLOT_ROWS,
                                      _plot_context(plan))
        except PlotError as exc:
            written, plots_error = exc.written, str(exc)
            summary["plots_error"] = plots_error
        summary["plots"] = [path.name for path in written]
        folder.write_summary(summary)
    data = None
    if (keep_rows and error is None and trace is not None and trace.kept
            and trace.rows == recorder.rows):
        data = trace.column_copies()
    result = RunResult(summary, folder.path.resolve(), folder.results_csv.resolve(),
                       folder.summary_json.resolve(), [p.resolve() for p in written],
                       plots_error, data)
    if interrupted:
        raise RunInterrupted(f"{error}; results so far in {folder.results_csv} (summary "
                             f"status: interrupted)", stop.received)
    if error is not None:
        raise SimulationError(f"{error} (results so far in {folder.results_csv})")
    return result


def _plot_context(plan):
    """The scenario, controller law and stop distance the plots are titled and drawn with."""
    from orchestrator.run.plots import PlotContext
    from orchestrator.system.sonotrack import SONOTRACK

    return PlotContext(getattr(plan.scenario, "name", ""),
                       SONOTRACK.controller_mode(plan.system, plan.parameters),
                       plan.stop_distance)


def _non_finite_metrics(summary, error):
    """A finished run whose distance metrics are NaN or inf did not give a result: say so.

    Sets the summary's status to ``failed`` with the metrics named, and returns the error
    text (``error`` unchanged if the run had already failed or the metrics are finite).
    """
    bad = sorted(k for k, v in summary.items()
                 if k.endswith("_m") and isinstance(v, float) and not math.isfinite(v))
    if not bad or error is not None:
        return error
    error = (f"metrics not finite: {', '.join(f'{k} = {summary[k]!r}' for k in bad)} "
             "(a recorded position is not finite or beyond what the metrics can measure)")
    summary.update(status="failed", error=error)
    return error


# Plots read results.csv thinned to at most this many rows (every k-th row plus the last):
# about two points per pixel of a figure, so a plot's memory no longer grows with the run
# (Agg's memory grows with the vertices of a dense line: 4,500 rows cost ~27 MB more peak
# RSS than 1,500). A default 30 s run (1,501 rows) is drawn from every row.
_PLOT_ROWS = 2000


class _Stop(Exception):
    """Raised from the step callback when a stop signal has been received."""


def _open_recorder(path, columns, fsync):
    from orchestrator.run.recorder import Recorder

    return Recorder(path, columns, fsync=fsync)


def _close_quietly(recorder, master, bar):
    """Close the CSV, free the FMUs and the progress bar; a failure here must not hide the
    run's own error (the CSV is closed first: it is what the user keeps)."""
    for close in (getattr(recorder, "close", None), master.terminate,
                  getattr(bar, "close", None)):
        if close is not None:
            try:
                close()
            except Exception:
                pass


class _ColumnReader:
    """Collects a row of the recorded columns.

    Columns the master reads every step anyway (see ``Master(observed=...)``) are copied from
    its buffers; the rest are read with one batched get per type per instance.
    """

    def __init__(self, master, system, columns):
        by_instance = {}
        self._buffered = []
        for slot, column in enumerate(columns):
            instance, port = column.split(".", 1)
            variable = system.variable(column)
            if variable.causality != "output":
                raise ConfigError(f"outputs: {column} is a {variable.causality}, not an output")
            buffered = master.observed_value(column)
            if buffered is not None:
                self._buffered.append((slot,) + buffered)
            else:
                by_instance.setdefault(instance, {}).setdefault(variable.type, []).append(port)
        self._groups = []
        position = {column: i for i, column in enumerate(columns)}
        for instance, by_type in by_instance.items():
            for type_name, ports in by_type.items():
                group = master.output_group(instance, type_name, ports)
                slots = [position[f"{instance}.{port}"] for port in ports]
                self._groups.append((instance, group, slots))
        self._master = master
        self._row = [0.0] * len(columns)

    def __call__(self):
        row = self._row
        for slot, values, index in self._buffered:
            row[slot] = values[index]
        for instance, group, slots in self._groups:
            values = self._master.read_outputs(instance, group)
            for slot, value in zip(slots, values):
                row[slot] = value
        return row


def _progress(total, scenario, enabled):
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit="step", desc=getattr(scenario, "name", "run"), leave=False)
