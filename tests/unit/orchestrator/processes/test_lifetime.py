"""Children that end with their parent: the parent-death signal, the lifeline pipe, a tied
command line; each against a real parent killed with SIGKILL, beside an untied control child
that outlives it (so the harness itself kills nothing)."""

import os
import signal
import subprocess
import sys
import threading
import time

import pytest

from orchestrator.processes import Lifeline, tied_command

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="parent-death signal and /proc (Linux)")

# A child of ours must be gone this soon after its parent is killed.
WITHIN_S = 1.0


def _running(pid):
    try:
        with open(f"/proc/{pid}/stat") as stream:
            text = stream.read()
    except FileNotFoundError:
        return False
    return text[text.rfind(")") + 2] not in "ZX"


def _seconds_until_gone(pid, limit=5.0):
    """Seconds until ``pid`` no longer runs (infinity if it still runs after ``limit``)."""
    started = time.monotonic()
    while _running(pid):
        if time.monotonic() - started > limit:
            return float("inf")
        time.sleep(0.005)
    return time.monotonic() - started


def _run_parent(code):
    """Start ``code`` as a parent process; return it and the pids it prints on one line."""
    parent = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                              start_new_session=True)
    return parent, [int(pid) for pid in parent.stdout.readline().split()]


def _kill_all(parent, pids):
    for pid in pids:
        if _running(pid):
            os.kill(pid, signal.SIGKILL)
    if parent.poll() is None:
        parent.kill()
    parent.wait()


_DEATH_SIGNAL = """
import subprocess, sys
sleeper = "import time; time.sleep(60)"
tied = subprocess.Popen([sys.executable, "-c", "import os, sys, time; "
                         "from orchestrator.processes import die_with_parent; "
                         "die_with_parent(int(sys.argv[1])); print('armed', flush=True); "
                         "time.sleep(60)", str(__import__('os').getpid())],
                        stdout=subprocess.PIPE, text=True)
untied = subprocess.Popen([sys.executable, "-c", sleeper])
assert tied.stdout.readline().strip() == "armed"
print(tied.pid, untied.pid, flush=True)
__import__('time').sleep(60)
"""


def test_a_child_with_the_death_signal_ends_with_its_killed_parent():
    parent, (tied, untied) = _run_parent(_DEATH_SIGNAL)
    try:
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait()
        assert _seconds_until_gone(tied, limit=5.0) <= WITHIN_S
        assert _running(untied)   # the control: an orphan lives on unless it is tied
    finally:
        _kill_all(parent, [tied, untied])


def test_a_child_whose_parent_died_before_it_armed_ends_at_once():
    code = ("from orchestrator.processes import die_with_parent; "
            "die_with_parent(1 if __import__('os').getppid() != 1 else 2); print('survived')")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == -signal.SIGKILL and "survived" not in done.stdout


_LIFELINE = """
import os, time
from orchestrator.processes import Lifeline, watch_lifeline
lifeline = Lifeline()
children = []
for watching in (True, True, False):
    pid = os.fork()
    if pid == 0:
        if watching:
            watch_lifeline(lifeline.read_fd)
        time.sleep(60)
        os._exit(0)
    children.append(pid)
print(*children, flush=True)
time.sleep(60)
"""


def test_forked_children_watching_the_lifeline_end_with_their_killed_parent():
    """Two watchers (each closed its copy of the write end: neither keeps the other alive)
    and a control child that does not watch."""
    parent, (first, second, control) = _run_parent(_LIFELINE)
    try:
        time.sleep(0.1)   # the watchers' threads are reading
        assert all(_running(pid) for pid in (first, second, control))
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait()
        assert _seconds_until_gone(first) <= WITHIN_S
        assert _seconds_until_gone(second) <= WITHIN_S
        assert _running(control)
    finally:
        _kill_all(parent, [first, second, control])


def test_closing_a_lifeline_ends_its_watchers_and_a_forked_copy_closes_nothing():
    lifeline = Lifeline()
    pid = os.fork()
    if pid == 0:   # the child: its copy of the object must not close the parent's pipe
        try:
            lifeline.close()
            from orchestrator.processes import watch_lifeline

            watch_lifeline(lifeline.read_fd)
            time.sleep(60)
        finally:
            os._exit(0)
    try:
        time.sleep(0.2)
        assert _running(pid)
        lifeline.close()
        assert _seconds_until_gone(pid) <= WITHIN_S
        _, status = os.waitpid(pid, 0)
        assert os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL
    finally:
        if _running(pid):
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)


_TIED = """
import subprocess, sys, time
from orchestrator.processes import tied_command
tied = subprocess.Popen(tied_command(["sleep", "60"]))
untied = subprocess.Popen(["sleep", "60"])
time.sleep(0.5)   # the launcher has armed the signal and exec'd sleep
print(tied.pid, untied.pid, flush=True)
time.sleep(60)
"""


def test_a_tied_command_ends_with_its_killed_parent():
    parent, (tied, untied) = _run_parent(_TIED)
    try:
        with open(f"/proc/{tied}/cmdline", "rb") as stream:
            assert stream.read().split(b"\0")[0] == b"sleep"   # the launcher exec'd it
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait()
        assert _seconds_until_gone(tied) <= WITHIN_S
        assert _running(untied)
    finally:
        _kill_all(parent, [tied, untied])


def test_a_command_from_another_thread_is_not_tied():
    """The signal would follow the thread that started the command, not the process."""
    commands = []
    thread = threading.Thread(target=lambda: commands.append(tied_command(["sleep", "1"])))
    thread.start()
    thread.join()
    assert commands == [["sleep", "1"]]
    assert tied_command(["sleep", "1"])[-2:] == ["sleep", "1"]
    assert tied_command(["sleep", "1"])[0] == sys.executable
