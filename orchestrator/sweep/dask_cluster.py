"""A real Dask cluster of separate processes on this machine, started with the ``dask`` CLI.

What ``sonotrack sweep --scheduler`` talks to on a cluster, made locally: one ``dask
scheduler`` and ``workers`` single-threaded ``dask worker`` processes on 127.0.0.1, each its own
process as on separate machines. The cluster test (``tests/integration/orchestrator/sweep/test_runs.py``) and the
sweep benchmark (``benchmarks/sweep_scaling.py``) start theirs here.

The cluster belongs to the process that starts it: its scheduler and workers end when that
process dies, however it dies (each command is wrapped by
:func:`orchestrator.processes.tied_command`, which arms Linux's parent-death signal before it
runs ``dask``; a worker's nanny takes its worker process with it). Start it from the main
thread: from another thread the commands are not tied (the signal would follow that thread).

Examples
--------
>>> address, processes = start_cluster(Path("/tmp/work"))      # doctest: +SKIP
>>> sweep(scenario, grid, "runs/sweep", scheduler=address)      # doctest: +SKIP
>>> stop_cluster(processes)                                     # doctest: +SKIP
"""

import json
import subprocess
import sys
import time
from pathlib import Path

from components.common.errors import SimulationError
from orchestrator.processes import tied_command

__all__ = ["dask_command", "scheduler_address", "start_cluster", "stop_cluster"]


def dask_command():
    """The ``dask`` console script of this Python environment."""
    return str(Path(sys.executable).with_name("dask"))


def scheduler_address(scheduler_file, process, timeout=60.0):
    """The address a starting ``dask scheduler`` writes to its ``--scheduler-file``.

    The scheduler does not write that file atomically, so it is read until it holds whole JSON.

    Raises
    ------
    SimulationError
        If the scheduler exits, or writes no address within ``timeout`` seconds.
    """
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise SimulationError(f"dask scheduler exited with status {process.returncode} "
                                  f"before writing {scheduler_file}")
        try:
            return json.loads(Path(scheduler_file).read_text())["address"]
        except (OSError, ValueError, KeyError):
            time.sleep(0.1)
    raise SimulationError(f"dask scheduler wrote no address to {scheduler_file} in {timeout} s")


def start_cluster(work, workers=2, env=None, timeout=60.0):
    """Start a scheduler and ``workers`` workers on 127.0.0.1; return once all are connected.

    Parameters
    ----------
    work : pathlib.Path
        Folder for the scheduler file and the workers' local directories (and their cwd).
    workers : int
        Number of ``dask worker`` processes, one thread each.
    env : dict, optional
        Environment of the processes (default: this process's).
    timeout : float
        Seconds to wait for the scheduler's address; the workers get 90 s to connect.

    Returns
    -------
    (str, list of subprocess.Popen)
        The scheduler's ``tcp://127.0.0.1:PORT`` address and the processes, scheduler first;
        pass them to :func:`stop_cluster`. On any failure they are stopped before raising.
    """
    from distributed import Client

    work = Path(work)
    scheduler_file = work / "scheduler.json"
    common = {"cwd": work, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL,
              "env": env}
    processes = [subprocess.Popen(tied_command([dask_command(), "scheduler", "--host",
                                                "127.0.0.1", "--port", "0", "--no-dashboard",
                                                "--scheduler-file", str(scheduler_file)]),
                                  **common)]
    try:
        address = scheduler_address(scheduler_file, processes[0], timeout)
        for _ in range(workers):
            processes.append(subprocess.Popen(tied_command(
                [dask_command(), "worker", address, "--nthreads", "1", "--no-dashboard",
                 "--host", "127.0.0.1", "--local-directory", str(work / "dask")]), **common))
        with Client(address, timeout="30s") as client:
            client.wait_for_workers(workers, timeout=90)
    except BaseException:
        stop_cluster(processes)
        raise
    return address, processes


def stop_cluster(processes, timeout=20.0):
    """Terminate the processes, wait up to ``timeout`` s in all, then kill what is left."""
    for process in processes:
        if process.poll() is None:
            process.terminate()
    deadline = time.monotonic() + timeout
    for process in processes:
        try:
            process.wait(timeout=max(0.1, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=10)
