"""Running the study's cells through the sweep machinery and reading the runs back.

Every run of the study (each cell of each
:class:`~orchestrator.reproduce.experiments.Experiment` x the Monte Carlo draws) is one
complete scenario; all of them go to one :func:`orchestrator.sweep.run_many` call, so one
engine (Dask, local or a cluster) and one progress bar serve the whole study. Finished runs
are stored by the hash of everything they read, so a second call (or a call after an
interruption) recomputes nothing that is on disk. A run computed now sends its recorded
columns back with its summary (``run_many(keep_rows=True)``: the worker held them while
recording, the very values ``results.csv`` reads back as), so only the runs found on disk are
parsed again, by ``orchestrator.run.read_results`` (the one reader of ``results.csv``) in as
many processes as the study had workers (forked). Parsing took 15-25 ms a run (49 s for 1,960
runs in one process, 7 Dec); sending the columns adds about 3 ms to a worker's turn-around
between runs (pickling and the pipe, 0.4 MB a run).
"""

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .tolerances import monte_carlo_points

__all__ = ["RunRecord", "StudyRuns", "run_study"]


@dataclass
class RunRecord:
    """One finished (or failed) run of a cell."""

    cell: str
    index: int
    summary: dict
    data: dict
    run_dir: str
    parameters: dict = field(default_factory=dict)

    @property
    def ok(self):
        """True if the run finished and recorded at least two rows."""
        return self.summary.get("status") == "ok" and len(self.data.get("time", ())) > 1

    def xy(self):
        """True robot centre positions, ``(n, 2)``."""
        return np.column_stack([self.data["plant.x"], self.data["plant.y"]])

    def source_xy(self):
        """True source positions, ``(n, 2)``."""
        return np.column_stack([self.data["source.x"], self.data["source.y"]])


@dataclass
class StudyRuns:
    """Every run of the study by cell (lists indexed by run) and what was reused."""

    cells: dict
    computed: int = 0
    reused: int = 0
    out_dir: Path = None

    def of(self, cell):
        """The runs of a cell (an empty list if it was not run)."""
        return self.cells.get(cell, [])

    def condition(self, cells):
        """The runs of the given cells (:class:`~orchestrator.reproduce.experiments.Cell`,
        one acoustic condition), under the cells' names: what :class:`Analysis` reads."""
        return StudyRuns({cell.name: self.cells[cell.key] for cell in cells
                          if cell.key in self.cells},
                         computed=self.computed, reused=self.reused, out_dir=self.out_dir)


def _parameter_info(system, names):
    """FMU default (start) and declared valid range of each ``instance.parameter``."""
    defaults, ranges = {}, {}
    for name in names:
        instance, _, parameter = name.partition(".")
        try:
            component = system.component(instance)
        except Exception:           # the tolerance names an unknown instance: reported later
            continue
        for variable in component.model_description.modelVariables:
            if variable.name == parameter:
                if variable.start is not None:
                    defaults[name] = float(variable.start)

                def bound(value):
                    return None if value in (None, "") else float(value)
                ranges[name] = (bound(getattr(variable, "min", None)),
                                bound(getattr(variable, "max", None)))
    return defaults, ranges


def run_study(experiments, tolerances, runs, out_dir, fmu_dir=None, workers=None,
              scheduler=None, progress=True, study_seed=0, stop_time_scale=1.0):
    """Run every cell ``runs`` times (Monte Carlo draws) and read the results.

    Parameters
    ----------
    experiments : list of Experiment
    tolerances : list of Tolerance
    runs : int
        Runs per cell.
    out_dir : path-like
        Study folder; the sweeps go to ``<out_dir>/runs/<experiment>/``.
    fmu_dir : path-like, optional
        Folder of the FMUs, if not beside the ``.ssd``.
    workers : int, optional
        Worker processes of the local Dask cluster (default: the CPUs).
    scheduler : str, optional
        Address of a running Dask scheduler instead of a local cluster.
    progress : bool
        One progress bar over every run of the study on stderr.
    study_seed : int
        Seed of the draws.
    stop_time_scale : float
        Factor on every stop time (< 1 only for a quick reduced study, e.g. in tests).

    Returns
    -------
    StudyRuns

    Raises
    ------
    ConfigError
        If a tolerance names an unknown parameter or draws outside its valid range.
    """
    from orchestrator.sweep import run_many
    from orchestrator.system import load_system

    out_dir = Path(out_dir)
    scenarios, settings = [], []
    for experiment in experiments:
        base = experiment.base_scenario(stop_time_scale)
        system = load_system(base.system, fmu_dir=fmu_dir)
        defaults, ranges = _parameter_info(system, [name for t in tolerances
                                                    for name in (t.parameter, *t.linked)])
        for cell in experiment.cells:
            points = monte_carlo_points(tolerances, defaults, cell.parameters, runs,
                                        study_seed, ranges)
            for index, point in enumerate(points):
                overrides = {k: v for k, v in point.items() if k != "seed"}
                scenarios.append(base.with_overrides(name=experiment.name, seed=point["seed"],
                                                     parameters=overrides))
                settings.append({"cell": cell.key, "index": index, **point})
    result = run_many(scenarios, out_dir / "runs", settings=settings, fmu_dir=fmu_dir,
                      scheduler=scheduler, workers=workers, progress=progress, keep_rows=True)
    study = StudyRuns({}, computed=result.computed, reused=result.reused, out_dir=out_dir)
    found = {(row.get("cell"), row.get("index")): row for row in result.rows}
    jobs = [(named["cell"], named["index"], named, found.get((named["cell"], named["index"])),
             result.out_dir) for named in settings]
    records, unread = [None] * len(jobs), []
    for i, job in enumerate(jobs):
        row = job[3]
        data = result.data.get(row["hash"]) if row is not None else None
        if data is None:   # reused from disk, or not held in memory: read its file
            unread.append(i)
        else:
            records[i] = _record(*job, data=data)
    for i, record in zip(unread, _read_records([jobs[i] for i in unread], workers)):
        records[i] = record
    for record in records:
        study.cells.setdefault(record.cell, []).append(record)
    return study


def _read_records(jobs, workers):
    """:func:`_record` of every job, in order, in up to ``workers`` processes, each ending with
    this process however it dies, as the sweep's workers do. Forked where the platform can (as
    the sweep's engine does): spawned readers would run the caller's main script again, which a
    script calling :func:`~orchestrator.reproduce.reproduce` without an ``if __name__ ==
    "__main__"`` guard turns into a second study. By now the sweep's pool is closed; the
    readers only read files."""
    from orchestrator.processes import die_with_parent

    processes = min(len(jobs) // 50, workers or os.cpu_count() or 1)
    if processes < 2:
        return [_record(*job) for job in jobs]
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    with ProcessPoolExecutor(processes, mp_context=multiprocessing.get_context(method),
                             initializer=die_with_parent, initargs=(os.getpid(),)) as pool:
        return list(pool.map(_record_job, jobs, chunksize=max(1, len(jobs) // (8 * processes))))


def _record_job(job):
    return _record(*job)


def _record(cell, index, point, row, sweep_dir, data=None):
    """The run of a job; ``data``: its columns as sent back by the run (else read here)."""
    from orchestrator.run import read_results
    from orchestrator.run.folder import read_summary

    if row is None:
        return RunRecord(cell, index, {"status": "missing", "error": "no row in the sweep"}, {},
                         "", point)
    run_dir = str(Path(sweep_dir) / row["run_dir"])   # rows name it relative to the sweep
    # read as every reader reads it: a run whose process is gone is "abandoned"
    summary = read_summary(run_dir) or dict(row)
    ok = summary.get("status") == "ok" and (Path(run_dir) / "results.csv").is_file()
    if not ok:
        data = {}
    elif data is None:
        data = read_results(Path(run_dir) / "results.csv")
    return RunRecord(cell, index, summary, data, run_dir, point)
