"""Many runs at once, resumable: :func:`sweep` (a grid and seeds) and :func:`run_many`.

Each planned run (:mod:`orchestrator.sweep.plan`) is looked up in the store first: a run whose
folder holds a finished summary is reused, every other run goes to the engine
(:mod:`orchestrator.sweep.engine`). As results arrive the table is rewritten atomically
(:mod:`orchestrator.sweep.store`), so a sweep that is killed keeps, in its table and its
store, every run it finished; started again, it computes only the rest. A run that fails is a
row with its ``status`` and ``error``; the sweep goes on.
"""

import os
import time
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["SweepResult", "run_many", "sweep"]

# The table is rewritten after a result unless writing it has taken more than this share of
# the time since the last write (many thousands of rows); it is always written at the end.
_TABLE_TIME_SHARE = 0.05


@dataclass
class SweepResult:
    """What a sweep leaves.

    Attributes
    ----------
    rows : list of dict
        One per run, in plan order: its settings, ``status`` (and ``error``), ``hash`` (its
        key), ``run_dir`` (relative to ``out_dir``: ``runs/<hash>``, so the sweep folder can
        be moved) and the summary's scalar figures.
    out_dir : pathlib.Path
        The sweep's folder.
    table_csv, table_json : pathlib.Path
        ``sweep.csv`` and ``sweep.json`` in it.
    computed, reused, failed : int
        Runs computed now, found finished in the store, and failed (now).
    engine : str
        ``"local"`` or ``"cluster"`` (``""`` if nothing had to run).
    data : dict
        With ``keep_rows``: run key to the run's recorded columns (``{column: array}``, as
        ``orchestrator.run.read_results`` reads its ``results.csv``), for each run computed
        now that ended ``ok`` with its rows in memory; the others are read from their folder.
    """

    rows: list = field(default_factory=list)
    out_dir: Path = None
    table_csv: Path = None
    table_json: Path = None
    computed: int = 0
    reused: int = 0
    failed: int = 0
    engine: str = ""
    data: dict = field(default_factory=dict)


def _row(run, summary, out_dir):
    row = dict(run.settings)
    row["status"] = summary.get("status", "failed")
    if row["status"] != "ok":
        row["error"] = summary.get("error", "no reason recorded")
    row["hash"] = run.key
    row["run_dir"] = Path(os.path.relpath(run.run_dir, Path(out_dir).resolve())).as_posix()
    for name, value in summary.items():
        if name not in row and not isinstance(value, (dict, list)):
            row[name] = value
    return row


class _Table:
    """The rows found or computed so far, written atomically and not too often."""

    def __init__(self, planned, out_dir, settings):
        from orchestrator.sweep.store import write_table

        self._write = write_table
        self._order = [run.key for run in planned]
        self._rows = {}
        self._out_dir = out_dir
        self._settings = settings
        self._last = time.perf_counter()
        self._spent = 0.0
        self.paths = (out_dir / "sweep.csv", out_dir / "sweep.json")

    def add(self, key, row):
        self._rows[key] = row
        now = time.perf_counter()
        if self._spent <= _TABLE_TIME_SHARE * (now - self._last):
            self.write()

    def rows(self):
        return [self._rows[key] for key in self._order if key in self._rows]

    def write(self):
        started = time.perf_counter()
        self.paths = self._write(self.rows(), self._out_dir, self._settings)
        self._last = time.perf_counter()
        self._spent = self._last - started


def _execute(plan, first, out_dir, settings, fmu_dir, engine, scheduler, workers, progress,
             record_interval, label, allow_outside, keep_rows=False):
    """Plan (``plan(system)``), reuse finished runs, run the rest on the engine, write the
    table.

    A local engine not yet started is started before planning: once this process has loaded
    ``first``'s system and unpacked its FMUs (``system``, passed on to ``plan``), its workers
    are forked and warm up on ``first`` cut to a few steps, while this process plans and
    hashes the runs.
    """
    from orchestrator.sweep.engine import LocalEngine, open_engine
    from orchestrator.sweep.worker import prepare

    own = engine is None
    if own and not scheduler:
        engine = open_engine(None, workers)
    fmu_dir = str(Path(fmu_dir).resolve()) if fmu_dir is not None else None
    try:
        system = None
        if isinstance(engine, LocalEngine) and first is not None and not engine.started:
            # the system loaded and the FMUs unpacked once, here, for the workers to inherit;
            # then the workers: a local pool forks fastest from a process with one thread,
            # and the progress bar starts a monitor thread
            system = prepare(first.system, fmu_dir, allow_outside)
            engine.start(warm_up=_warm_up_tasks(first, fmu_dir, record_interval,
                                                allow_outside))
        planned = plan(system)
        if settings is None:
            settings = list(dict.fromkeys(k for run in planned for k in run.settings))
        return _run_planned(planned, out_dir, settings, fmu_dir, engine, scheduler, workers,
                            progress, record_interval, label, allow_outside, keep_rows)
    finally:
        if own and engine is not None:
            engine.close()


def _run_planned(planned, out_dir, settings, fmu_dir, engine, scheduler, workers, progress,
                 record_interval, label, allow_outside, keep_rows=False):
    from orchestrator.sweep.store import finished_summary
    from orchestrator.sweep.worker import RunOutput, RunTask, run_task

    out_dir = Path(out_dir)
    result = SweepResult(out_dir=out_dir)
    table = _Table(planned, out_dir, settings)
    pending = []
    for run in planned:
        summary = finished_summary(run.run_dir)
        if summary is None:
            pending.append(run)
        else:
            table.add(run.key, _row(run, summary, out_dir))
            result.reused += 1
    table.write()
    if pending:
        from orchestrator.sweep.engine import open_engine

        own = engine is None
        if own:
            engine = open_engine(scheduler, workers)
        result.engine = engine.name
        by_key = {run.key: run for run in pending}
        bar = _bar(len(planned), result.reused, label) if progress else None

        def on_result(key, summary):
            if isinstance(summary, RunOutput):
                if summary.data is not None:
                    result.data[key] = summary.data
                summary = summary.summary
            row = _row(by_key[key], summary if isinstance(summary, dict) else
                       {"status": "failed", "error": f"worker returned {summary!r}"},
                       out_dir)
            result.computed += 1
            result.failed += row["status"] != "ok"
            table.add(key, row)
            if bar is not None:
                bar.update(1)
                if result.failed:
                    bar.set_postfix(failed=result.failed, refresh=False)

        tasks = [(run.key, RunTask(run.scenario, str(run.run_dir), run.key, fmu_dir,
                                   {k[4:]: v for k, v in run.digests.items()
                                    if k.startswith("fmu:")}, record_interval,
                                   allow_outside, keep_rows))
                 for run in pending]
        try:
            engine.run(run_task, tasks, on_result)
        finally:
            table.write()
            if bar is not None:
                bar.close()
            if own:
                engine.close()
    result.rows = table.rows()
    result.table_csv, result.table_json = table.paths
    return result


# A warm-up run lasts this many of the scenario's longest communication steps.
_WARM_UP_STEPS = 5


def _warm_up_tasks(scenario, fmu_dir, record_interval, allow_outside):
    """The run a worker does once before its first task: ``scenario`` cut to a few steps."""
    from components.common.errors import ConfigError
    from orchestrator.sweep.worker import RunTask

    if scenario is None:
        return ()
    longest = max([scenario.base_step, *scenario.steps.values()])
    try:
        short = scenario.with_overrides(stop_time=_WARM_UP_STEPS * longest)
    except ConfigError:  # e.g. a step that does not divide the short stop time: no warm-up
        return ()
    # no digests: the worker keys its instances by the FMUs it finds, and each real run checks
    # those against the digests the sweep hashed
    return (RunTask(short, "", "warm-up", fmu_dir, {}, record_interval, allow_outside),)


def _bar(total, initial, label):
    from tqdm import tqdm

    # tqdm's default line shows runs per second (over recent runs) and the time left
    return tqdm(total=total, initial=initial, unit="run", desc=label, smoothing=0.1)


def sweep(base, grid, out_dir, seeds=None, fmu_dir=None, scheduler=None, workers=None,
          progress=True, engine=None, record_interval=0.02, allow_outside=False):
    """Run ``base`` over a parameter grid and seeds, resuming from finished runs.

    Parameters
    ----------
    base : orchestrator.scenario.Scenario
        The scenario every run starts from.
    grid : dict of str to list
        ``"instance.parameter"`` to the values to try; every combination runs.
    out_dir : path-like
        Folder of the sweep (``runs/<key>/`` per run, ``sweep.csv``, ``sweep.json``).
    seeds : list of int, optional
        Seeds to run each combination with (default: the scenario's seed).
    fmu_dir : path-like, optional
        Folder of the FMUs, if not beside the ``.ssd``.
    scheduler : str or distributed.Client, optional
        A Dask scheduler's address (``tcp://host:8786``) or client; default this machine.
    workers : int, optional
        Worker processes on this machine (default: the number of CPUs).
    progress : bool
        Show a progress bar (runs per second, time left) on stderr.
    engine : LocalEngine or ClusterEngine, optional
        An engine kept open by the caller across sweeps (its workers stay warm); overrides
        ``scheduler`` and ``workers``.
    record_interval : float
        Simulated seconds between recorded rows of each run.
    allow_outside : bool
        Let the ``.ssd`` name files outside its folder (see :mod:`orchestrator.files.paths`).

    Returns
    -------
    SweepResult

    Raises
    ------
    ConfigError
        Before anything runs, listing every bad grid key, value or seed (with the valid
        choices), or if the engine cannot start. A run that fails does not raise: its row
        says ``status: failed`` and why.

    Examples
    --------
    >>> from orchestrator.scenario import load_scenario                 # doctest: +SKIP
    >>> result = sweep(load_scenario("scenarios/s_curve.toml"),        # doctest: +SKIP
    ...                {"planner.v_cruise": [0.2, 0.3]}, "runs/v_cruise", seeds=[1, 2])
    >>> [(r["planner.v_cruise"], r["seed"], r["path_rmse_m"]) for r in result.rows]  # doctest: +SKIP
    """
    from orchestrator.sweep.plan import plan_runs

    def plan(system):
        return plan_runs(base, grid, out_dir, seeds=seeds, fmu_dir=fmu_dir, system=system,
                         allow_outside=allow_outside)

    return _execute(plan, base, out_dir, sorted(grid), fmu_dir, engine, scheduler, workers,
                    progress, record_interval, "sweep", allow_outside)


def run_many(scenarios, out_dir, settings=None, fmu_dir=None, scheduler=None, workers=None,
             progress=True, engine=None, record_interval=0.02, allow_outside=False,
             keep_rows=False):
    """Run a list of scenarios (e.g. Monte Carlo draws) as one resumable sweep.

    Parameters
    ----------
    scenarios : list of orchestrator.scenario.Scenario
        Complete scenarios (parameters and seed set), e.g. from ``base.with_overrides``.
    out_dir : path-like
        Folder of the sweep (``runs/<key>/`` per run, ``sweep.csv``, ``sweep.json``).
    settings : list of dict, optional
        What names each run in the table, one dict per scenario (default: its name and seed).
    fmu_dir, scheduler, workers, progress, engine, record_interval, allow_outside
        As for :func:`sweep`.
    keep_rows : bool
        Send each run's recorded columns back with its summary (:attr:`SweepResult.data`),
        for a caller that reads every run's results: the worker holds them already, so they
        need not be parsed again from ``results.csv``.

    Returns
    -------
    SweepResult
        Rows in the order of ``scenarios`` (a scenario equal to an earlier one appears once).

    Examples
    --------
    >>> draws = [base.with_overrides(seed=s, parameters={"plant.mass": m})   # doctest: +SKIP
    ...          for s, m in zip(range(100), masses)]
    >>> rows = run_many(draws, "runs/mc", workers=2).rows                    # doctest: +SKIP
    """
    from orchestrator.sweep.plan import plan_scenarios

    scenarios = list(scenarios)

    def plan(system):
        return plan_scenarios(scenarios, out_dir, settings=settings, fmu_dir=fmu_dir,
                              allow_outside=allow_outside,
                              systems={scenarios[0].system: system} if system else None)

    return _execute(plan, scenarios[0] if scenarios else None, out_dir, None, fmu_dir, engine,
                    scheduler, workers, progress, record_interval, "runs", allow_outside,
                    keep_rows)
