"""The local engine's worker pool: the one private access it keeps, pinned to this Python."""

import os
import time
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool

import pytest

from components.common.errors import ConfigError
from orchestrator.sweep.engine import _kill_workers, _pool_context, open_engine


def _sleep(seconds):
    time.sleep(seconds)
    return os.getpid()


def test_killing_the_workers_stops_a_running_task_at_once():
    pool = ProcessPoolExecutor(1, mp_context=_pool_context())
    try:
        pool.submit(os.getpid).result(timeout=30)
        running = pool.submit(_sleep, 60)
        time.sleep(0.2)  # let the worker take it
        started = time.monotonic()
        _kill_workers(pool)
        assert isinstance(running.exception(timeout=30), BrokenProcessPool)
        assert time.monotonic() - started < 10
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def test_killing_the_workers_of_a_pool_already_shut_down_does_nothing():
    pool = ProcessPoolExecutor(1, mp_context=_pool_context())
    pool.submit(os.getpid).result(timeout=30)
    pool.shutdown(wait=True)
    _kill_workers(pool)


@pytest.mark.parametrize("workers", [0, -1, 1.5, True, "2"], ids=repr)
def test_a_bad_worker_count_is_refused_naming_the_option(workers):
    with pytest.raises(ConfigError, match=r"--workers .*whole number of worker processes >= 1"):
        open_engine(workers=workers)


_PRINTING_SWEEP = """
import os, sys
from orchestrator.sweep.engine import LocalEngine

def say(text):
    print(text, flush=True)
    return os.getpid()

print("the sweep's own line", flush=True)
with LocalEngine(workers=1) as engine:
    engine.run(say, [("a", "a worker's line")], lambda key, pid: None)
"""


def test_a_workers_output_goes_to_stderr_and_never_holds_the_sweeps_stdout():
    """The sweep's stdout carries the sweep's report alone: a worker writes to stderr."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", _PRINTING_SWEEP], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "the sweep's own line\n"
    assert "a worker's line" in done.stderr


def test_warm_up_folders_of_sweeps_that_died_are_removed_and_live_ones_kept(tmp_path):
    import subprocess
    import sys

    from orchestrator.sweep.engine import _remove_abandoned_scratch

    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()   # a sweep's process that has ended
    dead = tmp_path / f"sonotrack-warm-up-{child.pid}-a1b2"
    (dead / f"{child.pid + 1}-0").mkdir(parents=True)
    (dead / f"{child.pid + 1}-0" / "results.csv").write_text("time\n0.0\n")
    live = tmp_path / f"sonotrack-warm-up-{os.getpid()}-c3d4"
    live.mkdir()
    unrelated = tmp_path / "sonotrack-warm-up-notes"
    unrelated.mkdir()
    _remove_abandoned_scratch(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([live.name, unrelated.name])
