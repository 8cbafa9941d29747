"""Where a sweep's runs execute: Dask, on this machine or on a cluster.

Both engines hand the same task function (:func:`orchestrator.sweep.worker.run_task`) to
Dask and report each result as it arrives, so the sweep writes one store and one table
whichever runs it:

- :class:`LocalEngine` (the default): Dask's local scheduler (:func:`dask.local.get_async`,
  the core of :func:`dask.multiprocessing.get`) over a pool of worker processes that this
  engine keeps for its whole life. The pool starts in milliseconds (its processes are forked
  from this one once Dask is imported; the sweep starts them before it plans, and before its
  progress bar starts a thread). Each worker first warms up on a few steps of the sweep's
  first scenario, while the sweep's process plans and hashes the runs, then keeps FMUs
  loaded and instances warm from one run, and one sweep, to the next.
- :class:`ClusterEngine`: a ``dask.distributed`` scheduler given by address (``dask
  scheduler`` / ``dask worker`` on any machines that see the same files) or an existing
  ``Client``; the workers keep their instances warm the same way.

:func:`open_engine` picks one from the CLI's ``--scheduler`` / ``--workers``.

A local engine's workers end when the sweep's process dies, however it dies (SIGKILL, the
out-of-memory killer, a CI time-out): each worker arms Linux's parent-death signal (when the
pool was started from the main thread, whose end is the process's) and watches a lifeline
pipe that only the sweep's process holds open (:mod:`orchestrator.processes.lifetime`), so
none is left holding the FMU cache's shared locks or the sweep's output. A worker's stdin is
``/dev/null`` and its stdout goes to its stderr: the sweep's stdout carries the sweep's own
report, and a caller reading it to the end waits for the sweep alone. A cluster's workers
belong to the cluster: a killed client's tasks are the scheduler's to drop (see
``docs/process_lifetime.md``).
"""

import os
import signal
import socket
import threading
from pathlib import Path
from urllib.parse import urlsplit

from components.common.errors import ConfigError

__all__ = ["ClusterEngine", "LocalEngine", "open_engine"]


def _check_workers(workers):
    if workers is None:
        return max(1, os.cpu_count() or 1)
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ConfigError(f"--workers {workers!r}: expected a whole number of worker "
                          f"processes >= 1 (this machine has {os.cpu_count()} CPUs)")
    return workers


def _leave_the_callers_streams():
    """stdin from /dev/null, stdout into stderr: the sweep's stdout is the sweep's alone."""
    try:
        devnull = os.open(os.devnull, os.O_RDONLY)
        try:
            os.dup2(devnull, 0)
        finally:
            os.close(devnull)
        os.dup2(2, 1)
    except OSError:   # no stderr to write to (a daemon's closed descriptors): leave them
        pass


def _start_worker(warm_up_tasks, scratch, parent_pid=None, lifeline_fd=None,
                  death_signal=False):
    """A pool worker's initializer: tie the worker to the sweep's process, then warm up."""
    from orchestrator.processes import die_with_parent, end_this_process, watch_lifeline

    if death_signal:
        die_with_parent(parent_pid)
    elif parent_pid is not None and os.getppid() != parent_pid:
        end_this_process()
    if lifeline_fd is not None:
        watch_lifeline(lifeline_fd)
    if parent_pid is not None:
        _leave_the_callers_streams()
    # Ctrl-C belongs to the sweep's process, which stops the pool; a worker interrupted in the
    # middle of an FMU call would only turn it into an fmi2Fatal.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if warm_up_tasks:
        from orchestrator.sweep.worker import warm_up

        warm_up(warm_up_tasks, scratch)


def _process_id():
    return os.getpid()


# A warm-up folder is named after the sweep's process: sonotrack-warm-up-<pid>-<random>.
_SCRATCH_PREFIX = "sonotrack-warm-up-"


def _remove_abandoned_scratch(folder):
    """Remove the warm-up folders in ``folder`` of sweeps whose process is gone (killed while
    its workers warmed up: they died with it, leaving their half-done warm-up run)."""
    import shutil

    from orchestrator.processes import GONE, process_state

    host = socket.gethostname()
    for path in Path(folder).glob(f"{_SCRATCH_PREFIX}*-*"):
        owner = path.name[len(_SCRATCH_PREFIX):].split("-", 1)[0]
        if owner.isdigit() and path.is_dir() and process_state(
                {"pid": int(owner), "host": host}) == GONE:
            shutil.rmtree(path, ignore_errors=True)


def _pool_context():
    """Fork where the platform has it: workers start in milliseconds with this process's
    imports, and (unlike spawn or a fork server) never re-run the caller's main script, which
    a script without an ``if __name__ == "__main__"`` guard would turn into a second sweep."""
    import multiprocessing

    if "fork" in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("fork")
    return multiprocessing.get_context("spawn")


def _queue_depth(workers, alone):
    """Tasks to keep submitted to the pool: two per worker, or one to run a suspect alone.

    :func:`dask.local.get_async` submits the next task only after it has taken a result and
    run the callbacks (the sweep's table write, with its fsyncs). With one task queued per
    worker beyond the one it runs, a worker that finishes takes the next task at once instead
    of waiting for that round trip; workers still take queued tasks in order as they become
    free, so the load stays balanced. (One slot: one task at a time, to find which task kills
    its worker.)
    """
    return 1 if alone else 2 * workers


def _kill_workers(pool):
    """SIGKILL the worker processes of a :class:`~concurrent.futures.ProcessPoolExecutor`.

    The one private access of this module: ``pool._processes``. Python 3.11 gives no public
    way to reach or stop a pool's processes (``shutdown`` waits for the running tasks, and
    ``cancel_futures`` cancels only queued ones); ``ProcessPoolExecutor.kill_workers()``
    arrives in Python 3.14, which this project does not run on yet.
    """
    for process in list((getattr(pool, "_processes", None) or {}).values()):
        if process.is_alive():
            process.kill()


class LocalEngine:
    """Runs tasks on Dask's local process scheduler over a kept pool of worker processes.

    Parameters
    ----------
    workers : int, optional
        Worker processes (default: the number of CPUs).

    Examples
    --------
    >>> with LocalEngine(workers=2) as engine:                      # doctest: +SKIP
    ...     first = sweep(base, grid_a, "out/a", engine=engine)
    ...     second = sweep(base, grid_b, "out/b", engine=engine)    # warm workers
    """

    name = "local"

    def __init__(self, workers=None):
        self.workers = _check_workers(workers)
        self._pool = None
        self._lifeline = None  # its end-of-file tells forked workers that we died
        self._scratch = None  # the workers' warm-up folder, removed on close
        self._ran = False

    def start(self, warm_up=()):
        """Start the worker processes now (otherwise at the first run); return self.

        Returns once the processes are forked, without waiting for them: each one first runs
        ``warm_up`` (a few :class:`~orchestrator.sweep.worker.RunTask`, see
        :func:`~orchestrator.sweep.worker.warm_up`) in a scratch folder and then takes tasks,
        so its first-run costs overlap whatever this process does meanwhile (planning,
        hashing, dispatching). Dask is imported before the fork, so that the workers inherit
        it. Ignored if already started.

        The workers end when this process dies, however it dies (see the module docstring);
        Linux's parent-death signal is armed only when this is the main thread, since the
        kernel sends it when the forking thread ends.
        """
        if self._pool is None:
            import tempfile
            from concurrent.futures import ProcessPoolExecutor

            import dask.multiprocessing  # noqa: F401  (for run(), and inherited by the workers)

            from orchestrator.processes import Lifeline

            warm_up = tuple(warm_up)
            if warm_up:
                _remove_abandoned_scratch(tempfile.gettempdir())
                self._scratch = tempfile.mkdtemp(prefix=f"{_SCRATCH_PREFIX}{os.getpid()}-")
            self._ran = False
            context = _pool_context()
            forked = context.get_start_method() == "fork"
            self._cut_lifeline()   # a former pool's, if it ended without a close
            self._lifeline = Lifeline() if forked else None
            tie = (os.getpid(), self._lifeline.read_fd if forked else None,
                   forked and threading.current_thread() is threading.main_thread())
            self._pool = ProcessPoolExecutor(self.workers, mp_context=context,
                                             initializer=_start_worker,
                                             initargs=(warm_up, self._scratch, *tie))
            # with fork, the first submission forks every worker (before any thread starts)
            self._pool.submit(_process_id)
        return self

    @property
    def started(self):
        """Whether the worker processes are running."""
        return self._pool is not None

    def run(self, function, tasks, on_result):
        """Run ``function(task)`` for each ``(key, task)``; ``on_result(key, result)`` as each ends.

        A worker process that dies (a crash in native code) breaks the pool, and the tasks
        sent out but unfinished then (running, or queued behind a running one) are suspects:
        a new pool runs each suspect alone, then the other tasks as before. A task whose
        worker died while it ran alone, twice, is reported as failed instead of being tried
        again; the tasks that merely shared the pool with it are computed.
        """
        import pickle
        from concurrent.futures.process import BrokenProcessPool
        from functools import partial

        import cloudpickle
        from dask.local import get_async
        from dask.multiprocessing import pack_exception, reraise

        # what dask.multiprocessing.get passes get_async for a process pool
        dumps = partial(cloudpickle.dumps, protocol=pickle.HIGHEST_PROTOCOL)

        remaining = dict(tasks)
        breaks = {key: 0 for key in remaining}
        suspects, idle_breaks = [], 0

        def pretask(key, dsk, state):
            sent.add(key)

        def posttask(key, result, dsk, state, worker_id):
            remaining.pop(key, None)
            on_result(key, result)

        while remaining:
            self.start()
            self._ran = True
            suspects = [key for key in suspects if key in remaining]
            alone = suspects[:1]
            batch = {key: remaining[key] for key in alone or remaining}
            graph = {key: (function, task) for key, task in batch.items()}
            sent = set()
            try:
                get_async(self._pool.submit, _queue_depth(self.workers, alone), graph,
                          list(graph), dumps=dumps, loads=cloudpickle.loads,
                          pack_exception=pack_exception, raise_exception=reraise,
                          chunksize=1, callbacks=[(None, None, pretask, posttask, None)])
            except BrokenProcessPool:
                self._drop_pool()
                idle_breaks = idle_breaks + 1 if not sent else 0
                if idle_breaks >= 2:  # workers that die before any task: nothing can run
                    for key in list(remaining):
                        remaining.pop(key)
                        on_result(key, {"status": "failed", "error": "the worker processes "
                                        "died before running a task (twice)"})
                    break
                if not alone:
                    suspects = [key for key in batch if key in sent and key in remaining]
                    continue
                key = alone[0]
                breaks[key] += 1
                if breaks[key] >= 2:
                    remaining.pop(key)
                    on_result(key, {"status": "failed", "error": "the worker process "
                                    "running it died (twice, running alone); see the run's "
                                    "folder"})
            except BaseException:
                self._drop_pool()
                raise

    def _drop_pool(self):
        """Stop the workers now (after Ctrl-C or a broken pool).

        SIGKILL, not SIGTERM: a run stopped half-way is not finished whatever its summary
        says (the sweep runs it again), and a kill cannot race the run's own signal handlers
        into a traceback on the terminal.
        """
        pool, self._pool = self._pool, None
        if pool is None:
            return
        _kill_workers(pool)
        pool.shutdown(wait=True, cancel_futures=True)
        self._cut_lifeline()
        self._remove_scratch()

    def close(self):
        """Stop the worker processes (at once if they never ran a task: they were only
        warming up)."""
        if not self._ran:
            self._drop_pool()
            return
        pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
        self._cut_lifeline()
        self._remove_scratch()

    def _cut_lifeline(self):
        # after the workers have exited: a worker still watching would end at once
        lifeline, self._lifeline = self._lifeline, None
        if lifeline is not None:
            lifeline.close()

    def _remove_scratch(self):
        scratch, self._scratch = self._scratch, None
        if scratch is not None:
            import shutil

            shutil.rmtree(scratch, ignore_errors=True)

    def __enter__(self):
        # started by the first sweep, so that the workers warm up on its first run
        return self

    def __exit__(self, *exc):
        self.close()


def _check_reachable(address, timeout):
    """Fail fast, with one line, when nothing listens at a ``tcp://host:port`` address."""
    text = address if "://" in address else f"tcp://{address}"
    parts = urlsplit(text)
    if parts.scheme != "tcp":
        return
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
    if not host or not port:
        raise ConfigError(f"--scheduler {address!r}: expected tcp://HOST:PORT, e.g. "
                          "tcp://127.0.0.1:8786")
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as error:
        reason = error.strerror or type(error).__name__
        raise ConfigError(f"--scheduler {address}: no Dask scheduler answers there ({reason});"
                          " start one with `dask scheduler` and give its tcp://HOST:8786 "
                          "address, or leave --scheduler out to run on this machine") from None


class ClusterEngine:
    """Runs tasks on a ``dask.distributed`` scheduler.

    Parameters
    ----------
    scheduler : str or distributed.Client
        Scheduler address (``tcp://host:8786``) or a connected client (kept open on close).
    timeout : float
        Seconds to wait for the scheduler to answer.
    """

    name = "cluster"

    def __init__(self, scheduler, timeout=10.0):
        from distributed import Client

        if isinstance(scheduler, Client):
            self.client, self._own = scheduler, False
            return
        address = str(getattr(scheduler, "scheduler_address", scheduler))
        _check_reachable(address, timeout)
        try:
            self.client = Client(address, timeout=f"{timeout}s", set_as_default=False)
        except (OSError, TimeoutError) as error:
            raise ConfigError(f"--scheduler {address}: cannot connect to a Dask scheduler "
                              f"there within {timeout:g} s ({' '.join(str(error).split())})") \
                from None
        self._own = True

    def start(self, warm_up=()):
        """Nothing to start (the cluster runs already; its workers warm up in their first
        task); return self."""
        return self

    def run(self, function, tasks, on_result):
        """Run ``function(task)`` for each ``(key, task)``; ``on_result(key, result)`` as each ends.

        A task lost with its worker (``KilledWorker``) or failing to unpickle on a worker is
        reported as failed with the reason.
        """
        import uuid

        from distributed import as_completed

        token = uuid.uuid4().hex[:8]
        futures = {self.client.submit(function, task, key=f"sonotrack-run-{key}-{token}",
                                      pure=False): key for key, task in tasks}
        try:
            for future in as_completed(futures, loop=self.client.loop):
                key = futures[future]
                try:
                    result = future.result()
                except Exception as error:
                    result = {"status": "failed",
                              "error": f"{type(error).__name__}: {' '.join(str(error).split())}"}
                on_result(key, result)
                future.release()
        except BaseException:
            self.client.cancel(list(futures))
            raise

    def close(self):
        """Disconnect (only a client this engine opened)."""
        if self._own:
            self.client.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def open_engine(scheduler=None, workers=None, timeout=10.0):
    """The engine for ``--scheduler`` / ``--workers``: a cluster if given, else local.

    Raises
    ------
    ConfigError
        If ``workers`` is not a whole number >= 1, both are given, or the scheduler cannot be
        reached (each in one line naming the option and what is valid).
    """
    if scheduler is not None and not isinstance(scheduler, str):
        return ClusterEngine(scheduler, timeout=timeout)
    if scheduler:
        if workers is not None:
            raise ConfigError("--workers applies to this machine's engine; with --scheduler "
                              "the workers are the `dask worker` processes of the cluster")
        return ClusterEngine(scheduler, timeout=timeout)
    return LocalEngine(workers)
