"""A real cluster's processes belong to whoever started it: a sweep client killed with
``kill -9`` leaves the cluster running (the scheduler drops the client's tasks; the run a worker
is in finishes and is stored), and the cluster ends with the process that started it."""

import os
import signal
import subprocess
import sys
import time

import pytest

from orchestrator.builder.fmus import REPO_ROOT
from orchestrator.run.folder import read_summary
from orchestrator.scenario import load_scenario
from orchestrator.sweep import sweep
from tests.support.process_group import (end_command, group_members, pause_env,
                                         wait_for_stopped, wait_until_gone)
from tests.support.sweep_command import start_sweep

pytestmark = [pytest.mark.integration,
              pytest.mark.skipif(not sys.platform.startswith("linux"),
                                 reason="process groups and states from /proc (Linux)")]

_OWNER = """
import sys, time
from pathlib import Path
from orchestrator.sweep.dask_cluster import start_cluster
address, processes = start_cluster(Path(sys.argv[1]), workers=1)
print(address, flush=True)
time.sleep(600)
"""


def _scheduler_tasks(address):
    from distributed import Client

    with Client(address, timeout="30s") as client:
        return client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks))


def test_a_killed_client_leaves_the_cluster_which_ends_with_its_owner(fmu_dir, tmp_path):
    (tmp_path / "cluster").mkdir()
    # the cluster's worker stops itself as it starts its first run (its environment reaches
    # the worker process through the nanny)
    owner = subprocess.Popen(
        [sys.executable, "-c", _OWNER, str(tmp_path / "cluster")], cwd=REPO_ROOT,
        stdout=subprocess.PIPE, text=True, start_new_session=True,
        env=pause_env("open */runs/*/results.csv 1", DASK_DISTRIBUTED__WORKER__DAEMON="False"))
    client = None
    try:
        address = owner.stdout.readline().strip()
        assert address.startswith("tcp://127.0.0.1:"), address
        cluster = set(group_members(owner.pid)) - {owner.pid}
        assert len(cluster) >= 2   # a scheduler and a worker (with its nanny)
        client, scenario, out, _ = start_sweep(tmp_path, fmu_dir, runs=3,
                                               engine=("--scheduler", address), pipes=False)
        [worker] = wait_for_stopped(owner.pid, timeout=180)
        os.kill(client.pid, signal.SIGKILL)   # the client dies while its run is on a worker
        client.wait(timeout=30)
        os.kill(worker, signal.SIGCONT)
        # the scheduler forgets the dead client's tasks; the run in progress goes on to its end
        deadline = time.monotonic() + 60
        while _scheduler_tasks(address) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert _scheduler_tasks(address) == 0
        [started] = list(out.glob("runs/*"))   # the queued runs never started
        while read_summary(started)["status"] == "running" and time.monotonic() < deadline:
            time.sleep(0.2)
        assert read_summary(started)["status"] == "ok"
        assert cluster <= set(group_members(owner.pid)), "a cluster process ended with the client"

        resumed = sweep(load_scenario(scenario), {}, out, seeds=range(1, 4), fmu_dir=fmu_dir,
                        scheduler=address, progress=False)
        assert (resumed.reused, resumed.computed) == (1, 2)
        assert [row["status"] for row in resumed.rows] == ["ok"] * 3

        os.kill(owner.pid, signal.SIGKILL)
        owner.wait(timeout=30)
        elapsed, left = wait_until_gone(owner.pid, 3.0)
        assert left == [], f"cluster processes still running {elapsed:.1f} s after its owner " \
                           f"was killed: {left}"
    finally:
        for process in (client, owner):
            if process is not None:
                end_command(process)
