"""A killed sweep leaves nothing running: ``kill -9`` of ``sonotrack sweep`` at three moments.

The sweep runs as a real child process in a session of its own (its process group holds its
forked workers). One of its processes stops itself at the chosen moment
(``tests/support/pause_site``): a worker in its warm-up run, a worker starting its second run,
or the sweep's process between writing ``sweep.json`` and renaming ``sweep.csv`` into place.
Then the sweep's process gets SIGKILL (and the group SIGCONT, so a stopped worker goes on as a
running one would). Within 3 s no process of the group may run, both of its pipes must read
to end-of-file, and no FMU cache lock may be held; a new sweep then reuses exactly the runs
whose summary says ok and computes the rest.
"""

import json
import os
import signal
import subprocess
import sys

import pytest

from orchestrator.builder.fmus import REPO_ROOT
from orchestrator.run.folder import read_summary
from orchestrator.scenario import load_scenario
from orchestrator.sweep import sweep
from tests.support.process_group import (end_command, group_members, held_locks, read_to_eof,
                                         wait_for_stopped, wait_until_gone)
from tests.support.sweep_command import start_sweep

pytestmark = [pytest.mark.integration,
              pytest.mark.skipif(not sys.platform.startswith("linux"),
                                 reason="reads process groups and states from /proc (Linux)")]

RUNS = 4
# Everything a killed sweep started must end within this many seconds (the bound).
GONE_WITHIN_S = 3.0


def _statuses_on_disk(out):
    """run key -> the status its summary.json says, read as plain JSON (no liveness check)."""
    found = {}
    for path in sorted(out.glob("runs/*/summary.json")):
        try:
            found[path.parent.name] = json.loads(path.read_text())["status"]
        except (OSError, ValueError, KeyError):
            found[path.parent.name] = None
    return found


def _table_rows(path):
    if path.suffix == ".json":
        return len(json.loads(path.read_text()))
    return len(path.read_text().splitlines()) - 1


@pytest.mark.parametrize("moment, pause", [
    ("warm-up", "open */sonotrack-warm-up-*/results.csv 1"),
    ("mid-run", "open */runs/*/results.csv 2"),
    ("table", "os.rename */.sweep.csv.*.partial 2"),
], ids=["during-warm-up", "mid-run", "while-writing-the-table"])
def test_a_killed_sweep_leaves_nothing_running_and_resumes(fmu_dir, tmp_path, moment, pause):
    process, scenario, out, cache = start_sweep(tmp_path, fmu_dir, pause, runs=RUNS)
    try:
        stopped = wait_for_stopped(process.pid, process=process)
        workers = [pid for pid in group_members(process.pid) if pid != process.pid]
        # the moment is the one named: a worker stopped, or the sweep's own process
        assert stopped == ([process.pid] if moment == "table" else workers), stopped
        os.kill(process.pid, signal.SIGKILL)
        process.wait(timeout=30)
        # a stopped worker goes on only once the sweep's death is complete (reaped), as it
        # would have been running then
        try:
            os.killpg(process.pid, signal.SIGCONT)
        except ProcessLookupError:   # every process of the group already ended
            pass
        elapsed, left = wait_until_gone(process.pid, GONE_WITHIN_S)
        assert left == [], f"still running {elapsed:.1f} s after the kill: {left}"
        # no process holds the sweep's pipes: a caller reading its output gets end-of-file
        assert read_to_eof(process.stdout, 1.0) is not None, "stdout still held open"
        assert read_to_eof(process.stderr, 1.0) is not None, "stderr still held open"
        assert list((cache / "fmu-locks").glob("*.lock")), "the sweep took no cache lock"
        assert held_locks(cache) == []
    finally:
        end_command(process)

    statuses = _statuses_on_disk(out)
    finished = [key for key, status in statuses.items() if status == "ok"]
    if moment == "warm-up":
        assert finished == []
    if moment == "mid-run":
        # run 1 finished, run 2 was in the killed worker's hands: it reads as abandoned
        [cut] = [key for key, status in statuses.items() if status == "running"]
        assert len(finished) == 1
        summary = read_summary(out / "runs" / cut)
        assert summary["status"] == "abandoned"
        assert summary["process"]["pid"] in workers
        assert f"pid {summary['process']['pid']} on " in summary["error"]
    if moment == "table":
        # killed between the two files of one table write: sweep.json new, sweep.csv old and
        # the new one left as a temporary file
        assert _table_rows(out / "sweep.json") >= 1
        assert _table_rows(out / "sweep.csv") < _table_rows(out / "sweep.json")
        assert list(out.glob(".sweep.csv.*.partial"))
        assert finished

    resumed = sweep(load_scenario(scenario), {}, out, seeds=range(1, RUNS + 1), fmu_dir=fmu_dir,
                    workers=1, progress=False)
    assert (resumed.reused, resumed.computed) == (len(finished), RUNS - len(finished))
    assert [row["status"] for row in resumed.rows] == ["ok"] * RUNS
    assert _table_rows(out / "sweep.csv") == _table_rows(out / "sweep.json") == RUNS
    assert not list(out.glob(".*.partial")), "a killed writer's temporary table is left"
    assert set(_statuses_on_disk(out).values()) == {"ok"}


_THREAD_STARTED = """
import os, threading, time
from orchestrator.sweep.engine import LocalEngine

def pid_after(seconds):
    time.sleep(seconds)
    return os.getpid()

engine = LocalEngine(workers=2)
# started from another thread: Linux's parent-death signal would follow that thread, so the
# workers rely on the lifeline alone
starter = threading.Thread(target=engine.start)
starter.start()
starter.join()
results = []
engine.run(pid_after, [("a", 0.5), ("b", 0.5)], lambda key, pid: results.append(pid))
print(*sorted(set(results)), flush=True)   # each worker has run its initializer and a task
time.sleep(120)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc")
def test_workers_of_an_engine_started_off_the_main_thread_die_by_the_lifeline(tmp_path):
    process = subprocess.Popen([sys.executable, "-c", _THREAD_STARTED], cwd=REPO_ROOT,
                               stdout=subprocess.PIPE, start_new_session=True)
    try:
        workers = [int(pid) for pid in process.stdout.readline().split()]
        assert len(workers) == 2 and set(workers) <= set(group_members(process.pid))
        os.kill(process.pid, signal.SIGKILL)
        process.wait(timeout=30)
        elapsed, left = wait_until_gone(process.pid, GONE_WITHIN_S)
        assert left == [], f"workers still running {elapsed:.1f} s after the kill: {left}"
    finally:
        end_command(process)
