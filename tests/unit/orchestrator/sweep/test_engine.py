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
