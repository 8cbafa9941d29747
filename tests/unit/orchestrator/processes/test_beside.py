"""A function run in a forked child: its value, its failures, its end with the parent."""

import doctest
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from orchestrator.processes import beside
from orchestrator.processes.beside import Beside, BesideEach


def test_the_child_reads_the_parents_memory_and_returns_its_value():
    data = {"runs": [float(i) for i in range(200_000)]}   # not pickled: the child forks
    pending = Beside(lambda: (os.getpid(), sum(data["runs"])))
    pid, total = pending.result()
    assert pid != os.getpid() and total == sum(range(200_000))


def test_an_exception_in_the_child_is_raised_with_its_traceback():
    def fails():
        raise ValueError("figure 17 has no cells")
    with pytest.raises(RuntimeError, match="ValueError: figure 17 has no cells"):
        Beside(fails).result()


def test_a_child_that_dies_is_never_taken_for_a_result():
    with pytest.raises(RuntimeError, match=r"ended without a result \(exit code -9\)"):
        Beside(lambda: os.kill(os.getpid(), signal.SIGKILL)).result()


def test_the_child_ends_when_the_parent_is_killed(tmp_path):
    pid_file = tmp_path / "child.pid"
    script = textwrap.dedent(f"""
        import os, time
        from orchestrator.processes.beside import Beside
        def work():
            open({str(pid_file)!r}, "w").write(str(os.getpid()))
            time.sleep(60)
        Beside(work)
        time.sleep(60)
    """)
    parent = subprocess.Popen([sys.executable, "-c", script], cwd=os.getcwd())
    try:
        for _ in range(100):
            if pid_file.exists() and pid_file.read_text():
                break
            time.sleep(0.05)
        child = int(pid_file.read_text())
        parent.kill()
        parent.wait(timeout=10)
        for _ in range(100):   # the parent-death signal: well within a second
            if not _running(child):
                break
            time.sleep(0.05)
        else:
            os.kill(child, signal.SIGKILL)
            pytest.fail("the child outlived its killed parent by 5 s")
    finally:
        parent.kill()


def test_each_function_runs_once_in_a_child_and_the_values_come_back_in_order():
    # the first function is slow: the other child takes every one after it meanwhile
    def slow():
        time.sleep(1.0)
        return "slow", os.getpid()
    quick = [lambda i=i: (i, os.getpid()) for i in range(1, 9)]
    values = BesideEach([slow] + quick, processes=2).result()
    assert [v for v, _ in values] == ["slow", *range(1, 9)]
    pids = {pid for _, pid in values}
    assert len(pids) == 2 and os.getpid() not in pids
    assert all(pid != values[0][1] for _, pid in values[1:])


def test_a_failing_function_is_raised_once_every_child_has_ended(tmp_path):
    def fails():
        raise ValueError("figure 17 has no cells")

    def last():
        time.sleep(0.3)
        (tmp_path / "last").write_text("drawn")
    with pytest.raises(RuntimeError, match="ValueError: figure 17 has no cells"):
        BesideEach([fails, last], processes=2).result()
    assert (tmp_path / "last").read_text() == "drawn"


def _running(pid):
    """Whether ``pid`` runs: gone, or a zombie waiting for init to reap it, is not running
    (a dead child stays a zombie until its new parent reaps it, which may take a while)."""
    try:
        stat = open(f"/proc/{pid}/stat").read()
    except FileNotFoundError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] not in ("Z", "X")


def test_module_examples():
    assert doctest.testmod(beside).failed == 0
