"""What a killed command leaves behind, seen from outside: its process group, its pipes, its
FMU cache locks; and the environment that stops one of its processes at a chosen moment.

A test starts the command with ``start_new_session=True``, so that its process group is its
pid and holds everything it starts (forked workers, renderers, launched programs), then:

- :func:`pause_env` makes one of those processes stop itself (SIGSTOP) at a chosen audit event
  (``tests/support/pause_site/sitecustomize.py``), :func:`wait_for_stopped` finds it;
- after the kill, :func:`wait_until_gone` polls the group (zombies count as gone: they hold no
  descriptor and no lock), :func:`read_to_eof` reads a pipe to its end within a time limit, and
  :func:`held_locks` lists the cache's lock files some process still holds;
- :func:`kill_group` cleans up whatever a failed test left.
"""

import fcntl
import os
import select
import signal
import time
from pathlib import Path

__all__ = ["PAUSE_SITE", "end_command", "group_members", "held_locks", "kill_group",
           "pause_env", "read_to_eof", "wait_for_stopped", "wait_until_gone"]

PAUSE_SITE = Path(__file__).resolve().parent / "pause_site"


def pause_env(spec, **extra):
    """This process's environment plus the pause ``spec`` (``EVENT GLOB NTH``) and ``extra``."""
    env = dict(os.environ, **extra)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(PAUSE_SITE),
                                                      env.get("PYTHONPATH", "")]))
    env["SONOTRACK_TEST_PAUSE"] = spec
    return env


def _stat(pid):
    """(state, parent pid, process group) from /proc/PID/stat, or None."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text(encoding="ascii", errors="replace")
    except OSError:
        return None
    fields = text[text.rfind(")") + 2:].split()
    return fields[0], int(fields[1]), int(fields[2])


def group_members(pgid, states=None):
    """Pids of the processes in group ``pgid`` that have not ended (zombies excluded), or
    only those whose state letter is in ``states``."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        stat = _stat(entry.name)
        if stat is None or stat[2] != pgid or stat[0] in ("Z", "X"):
            continue
        if states is None or stat[0] in states:
            found.append(int(entry.name))
    return sorted(found)


def wait_for_stopped(pgid, timeout=120.0, process=None):
    """The pids of group ``pgid`` stopped by a pause, once there is one.

    Raises AssertionError if none stops in ``timeout`` s, or if ``process`` (a Popen) ends
    first (its output in the message).
    """
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        stopped = group_members(pgid, states=("T",))
        if stopped:
            return stopped
        if process is not None and process.poll() is not None:
            raise AssertionError(f"the command ended (status {process.returncode}) before "
                                 f"it reached the pause: {process.communicate()}")
        time.sleep(0.02)
    raise AssertionError(f"no process of group {pgid} stopped within {timeout} s")


def wait_until_gone(pgid, timeout):
    """Poll group ``pgid`` until no process of it runs or ``timeout`` s pass; return the
    seconds it took and the pids still running (empty if all ended)."""
    started = time.monotonic()
    while True:
        left = group_members(pgid)
        elapsed = time.monotonic() - started
        if not left or elapsed >= timeout:
            return elapsed, left
        time.sleep(0.02)


def read_to_eof(stream, timeout):
    """Read a pipe until end-of-file; return its bytes, or None if no EOF came in time
    (a process still holds the write end)."""
    fd = stream.fileno()
    chunks = []
    deadline = time.monotonic() + timeout
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return None
        readable, _, _ = select.select([fd], [], [], left)
        if not readable:
            return None
        chunk = os.read(fd, 65536)
        if not chunk:
            return b"".join(chunks)
        chunks.append(chunk)


def held_locks(cache):
    """Names of the FMU cache's lock files (``<cache>/fmu-locks/*.lock``) some process holds:
    an exclusive lock cannot be taken at once."""
    held = []
    for path in sorted(Path(cache, "fmu-locks").glob("*.lock")):
        fd = os.open(path, os.O_RDWR)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            held.append(path.name)
        finally:
            os.close(fd)
    return held


def kill_group(pgid):
    """SIGKILL whatever still runs in group ``pgid`` (clean-up after a failed test)."""
    for pid in group_members(pgid):
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def end_command(process):
    """Clean up after a test: kill what is left of ``process``'s group, then reap it."""
    kill_group(process.pid)
    if process.poll() is None:
        process.kill()
    process.wait(timeout=30)
