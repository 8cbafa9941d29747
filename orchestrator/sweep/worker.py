"""The worker side of a sweep: one run per task, on FMU instances kept warm between runs.

A worker process (a local pool process or a ``dask worker``) keeps, between tasks, the loaded
systems and one set of FMU instances per system. The next run resets those instances
(``fmi2Reset``, then the experiment set-up and parameters again) instead of loading and
instantiating the FMUs anew; a reset instance holds nothing of the last run, so a warm run
gives the same numbers, bit for bit, as a run in a fresh process.

Before a run uses an FMU, its content is checked against the digest the sweep hashed; a file
changed under a running sweep, or another machine's different copy, fails the run with a line
saying so rather than giving another build's answer under this key. An instance that failed
is freed (never reused); a pythonfmu instance that reported ``fmi2Fatal`` is dropped without
a call.

:func:`run_task` never raises: its result is the run's summary, with ``status`` ``"failed"``
and the reason in ``error`` when the run could not be done. A task with ``keep_rows`` gets a
:class:`RunOutput` instead: the summary and the run's recorded columns, which the caller would
otherwise read back from ``results.csv``.
"""

import os
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["RunOutput", "RunTask", "WarmInstances", "prepare", "run_task", "warm_instances",
           "warm_up"]


@dataclass
class RunTask:
    """What a worker needs for one run (pickled to the worker).

    Attributes
    ----------
    scenario : orchestrator.scenario.Scenario
        The scenario to run.
    run_dir : str
        Folder of the run (absolute; shared with the client on a cluster).
    key : str
        The run's key (its folder name).
    fmu_dir : str or None
        Folder of the FMUs, if not beside the ``.ssd``.
    fmu_digests : dict
        Instance name to the SHA-256 of its FMU, as the sweep hashed it.
    record_interval : float
        Simulated seconds between recorded rows.
    allow_outside : bool
        Let the ``.ssd`` name files outside its folder.
    keep_rows : bool
        Return the run's recorded columns with its summary (a :class:`RunOutput`).
    """

    scenario: object
    run_dir: str
    key: str
    fmu_dir: str | None = None
    fmu_digests: dict = field(default_factory=dict)
    record_interval: float = 0.02
    allow_outside: bool = False
    keep_rows: bool = False


@dataclass
class RunOutput:
    """What a task with ``keep_rows`` returns.

    Attributes
    ----------
    summary : dict
        The run's summary, as :func:`run_task` returns it otherwise.
    data : dict or None
        ``{column: array}``: every column of the run's ``results.csv`` with the values
        :func:`orchestrator.run.read_results` reads back, if the run ended ``ok`` and its rows
        were held in memory (:attr:`orchestrator.run.RunResult.data`); else None.
    """

    summary: dict
    data: dict | None = None


class WarmInstances:
    """FMU instances and loaded systems kept by one worker process between runs.

    Instances are kept per ``(instance name, FMU path, FMU digest)``; a run takes one of
    each it needs (or makes a new one) and gives them back when it succeeded. Safe to use from
    several threads (a ``dask worker`` with more than one thread runs tasks side by side).
    """

    def __init__(self):
        self._lock = threading.Lock()
        self._idle = {}
        self._systems = {}
        self._digests = {}
        self.created = 0
        self.reused = 0

    def file_digest(self, path):
        """SHA-256 of a file, recomputed only when its size, mtime or inode changed."""
        from orchestrator.sweep.inputs import file_digest

        path = Path(path).resolve()
        stat = path.stat()
        signature = (stat.st_size, stat.st_mtime_ns, stat.st_ino)
        cached = self._digests.get(path)
        if cached is None or cached[0] != signature:
            cached = (signature, file_digest(path))
            self._digests[path] = cached
        return cached[1]

    def system(self, ssd_path, fmu_dir, allow_outside=False):
        """The loaded system of an ``.ssd``, kept while the ``.ssd`` and its FMUs are unchanged
        (a rebuilt FMU may declare other variables: its model description is read again)."""
        from orchestrator.system import load_system

        key = (str(ssd_path), str(fmu_dir), bool(allow_outside))
        with self._lock:
            cached = self._systems.get(key)
        if cached is not None and cached[0] == self._signature(ssd_path, cached[1]):
            return cached[1]
        system = load_system(ssd_path, fmu_dir=fmu_dir, allow_outside=allow_outside)
        with self._lock:
            self._systems[key] = (self._signature(ssd_path, system), system)
        return system

    def _signature(self, ssd_path, system):
        return (self.file_digest(ssd_path),
                *(self.file_digest(component.fmu_path) for component in system.components))

    def acquire(self, instance_name, fmu_path, digest):
        """A warm instance for this run, or a new reusable one."""
        from orchestrator.fmu.handle import FmuInstance

        key = (instance_name, str(fmu_path), digest)
        with self._lock:
            idle = self._idle.get(key)
            if idle:
                self.reused += 1
                return idle.pop()
            self.created += 1
        return FmuInstance(fmu_path, instance_name, reusable=True)

    def give_back(self, instance_name, fmu_path, digest, handle):
        """Keep a terminated instance of a successful run for the next run."""
        with self._lock:
            self._idle.setdefault((instance_name, str(fmu_path), digest), []).append(handle)

    def clear(self, free=True):
        """Forget every idle instance (freeing them unless ``free`` is False)."""
        with self._lock:
            idle, self._idle = self._idle, {}
            self._systems = {}
        if free:
            for handles in idle.values():
                for handle in handles:
                    _release(handle)


def _release(handle):
    try:
        handle.release()
    except Exception:  # an instance that cannot be freed is left to the process exit
        pass


_WARM = WarmInstances()


def warm_instances():
    """The :class:`WarmInstances` of this process."""
    return _WARM


def _forget_in_child():
    # A forked child must not free (or reuse) instances that belong to its parent; the loaded
    # systems and file digests are plain data, kept (each use still checks the file's stat).
    global _WARM
    inherited, _WARM = _WARM, WarmInstances()
    _WARM._systems = dict(inherited._systems)
    _WARM._digests = dict(inherited._digests)


os.register_at_fork(after_in_child=_forget_in_child)


def _failed(error, started):
    return {"status": "failed", "error": error, "wall_time_s": time.perf_counter() - started}


def run_task(task, warm=None):
    """Do one run of a sweep on this worker; return its summary (never raises).

    Parameters
    ----------
    task : RunTask
    warm : WarmInstances, optional
        Where instances are kept between runs (default: this process's).

    Returns
    -------
    dict or RunOutput
        The run's summary; ``status`` is ``"ok"``, or ``"failed"`` with ``error``. With
        ``task.keep_rows``, a :class:`RunOutput` of the summary and the recorded columns.
    """
    summary, data = _summary_and_rows(task, warm if warm is not None else _WARM)
    return RunOutput(summary, data) if task.keep_rows else summary


def _summary_and_rows(task, warm):
    started = time.perf_counter()
    try:
        result = _run(task, warm)
        return result.summary, result.data
    except KeyboardInterrupt:
        raise
    except BaseException as exc:  # a run's failure is its row's business, not the sweep's
        from components.common.errors import SonotrackError
        from orchestrator.sweep.store import read_summary

        text = str(exc) if isinstance(exc, SonotrackError) else f"{type(exc).__name__}: {exc}"
        text = " ".join(text.split()) or type(exc).__name__
        summary = read_summary(Path(task.run_dir) / "summary.json")
        if summary is not None and summary.get("status") != "ok":
            # the run got as far as its own summary: keep its figures, say why it stopped
            summary.setdefault("error", text)
            return summary, None
        return _failed(text, started), None


def prepare(ssd_path, fmu_dir, allow_outside=False):
    """Load, in this process, what every worker's first run needs and a fork can share.

    The system of ``ssd_path`` (its ``.ssd`` and the FMUs' model descriptions) is kept in this
    process's :class:`WarmInstances`, and each FMU is unpacked (:func:`orchestrator.fmu.handle.
    extract_once`); workers forked afterwards inherit both instead of redoing them.

    Returns
    -------
    orchestrator.system.System

    Raises
    ------
    ConfigError, SystemDescriptionError
        As :func:`orchestrator.system.load_system`. An FMU that cannot be unpacked is left
        for its runs to report.
    """
    from orchestrator.fmu.handle import extract_once

    system = _WARM.system(ssd_path, fmu_dir, allow_outside)
    for component in system.components:
        try:
            extract_once(component.fmu_path)
        except Exception:  # the run that needs it fails with the reason, as a row
            pass
    return system


def warm_up(tasks, folder, warm=None):
    """Pay a worker's first-run costs before its first task: a pool worker's initializer.

    A process's first run pays more than the next ones: loading the system, loading each
    FMU's binary and importing its Python code, and the run path's own first calls. Each of
    ``tasks`` (typically the sweep's first run cut to a few steps) is run once here, in a
    scratch folder removed afterwards, leaving this process's instances terminated and kept
    for a reset, exactly as after a finished run. A local engine's workers do this while the
    sweep's process still dispatches, instead of in their first task.

    Never raises: a warm-up that fails leaves nothing kept (its instances are freed) and the
    real run then meets, and reports, the same problem itself.

    Parameters
    ----------
    tasks : sequence of RunTask
        Runs to do once (their ``run_dir`` is not used).
    folder : path-like
        Scratch folder; each run goes into ``<folder>/<process id>-<n>``, and the folder is
        removed once empty.
    warm : WarmInstances, optional
        Where instances are kept (default: this process's).
    """
    import dataclasses
    import shutil

    for number, task in enumerate(tasks):
        run_dir = Path(folder) / f"{os.getpid()}-{number}"
        task = dataclasses.replace(task, run_dir=str(run_dir))
        try:
            run_task(task, warm)
        except BaseException:  # a run's failure is the run's to report, not the warm-up's
            pass
        finally:
            shutil.rmtree(run_dir, ignore_errors=True)
    # the last worker out removes the folder; a sweep killed meanwhile takes its workers with
    # it, and the next local engine removes the folder (orchestrator.sweep.engine)
    try:
        os.rmdir(folder)
    except OSError:
        pass


def _run(task, warm):
    from components.common.errors import ConfigError
    from orchestrator.run import run_scenario

    scenario = task.scenario
    system = warm.system(scenario.system, task.fmu_dir, task.allow_outside)
    used = {}
    for component in system.components:
        expected = task.fmu_digests.get(component.name)
        actual = warm.file_digest(component.fmu_path)
        if expected is not None and actual != expected:
            raise ConfigError(
                f"{component.fmu_path}: the FMU of {component.name} on this worker is not the "
                f"one the sweep hashed (sha256 {actual[:12]} instead of {expected[:12]}); "
                "was it rebuilt during the sweep, or do the workers see other files?")
        used[component.name] = (component.fmu_path, actual)

    taken = []

    def handle(fmu_path, instance_name):
        path, digest = used[instance_name]
        instance = warm.acquire(instance_name, path, digest)
        taken.append((instance_name, path, digest, instance))
        return instance

    run_dir = Path(task.run_dir)
    try:
        result = run_scenario(scenario, run_dir, progress=False, fmu_dir=task.fmu_dir,
                              plots=False, record_interval=task.record_interval,
                              system=system, handles=handle, sync_summary=False,
                              allow_outside=task.allow_outside, keep_rows=task.keep_rows)
    except BaseException:
        for *_, instance in taken:
            _release(instance)
        raise
    for name, path, digest, instance in taken:
        warm.give_back(name, path, digest, instance)
    return result
