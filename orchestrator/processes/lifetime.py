"""A child process ends when its parent dies, however the parent dies (SIGKILL included).

A process killed with SIGKILL runs no clean-up, so whatever it started must notice by itself.
Three means, each where it applies:

- :func:`die_with_parent`, called first thing in the child: Linux's parent-death signal
  (``prctl(PR_SET_PDEATHSIG, SIGKILL)`` through ctypes), then a check that the parent did not
  die before the signal was armed. The kernel sends it when the *thread* that forked the child
  ends, so it suits children forked by a thread that outlives them: the main thread, or a
  thread that waits for its child (``subprocess.run``, the plot renderer).
- :class:`Lifeline`: a pipe whose write end only the parent holds (every process forked from
  the parent closes its copy at once, through :func:`os.register_at_fork`). A forked child hands
  the read end to :func:`watch_lifeline`, whose thread reads it: end-of-file comes when the
  parent's descriptor closes, which the kernel does when the parent dies. Works on any POSIX
  system, whichever thread forked.
- :func:`tied_command`: a command line for a program we do not write (the ``dask`` CLI) that
  arms the parent-death signal in a small launcher and then ``exec``'s the program; the signal
  survives ``exec``.

A child ended by any of them is killed with SIGKILL, as if the signal came from outside: it may
be inside an FMU call, and a clean-up could report to nobody.
"""

import ctypes
import os
import signal
import sys
import threading
from pathlib import Path

__all__ = ["Lifeline", "arm_parent_death_signal", "die_with_parent", "end_this_process",
           "tied_command", "watch_lifeline"]

_PR_SET_PDEATHSIG = 1   # <linux/prctl.h>
# The source tree this module is imported from: a launcher imports the same code.
_SOURCE_ROOT = str(Path(__file__).resolve().parents[2])
_LAUNCHER = (f"import sys; sys.path.insert(0, {_SOURCE_ROOT!r}); "
             "from orchestrator.processes.lifetime import _exec_tied; _exec_tied()")
# Write ends of the lifelines this process made; a forked child closes its copies at once.
_WRITE_ENDS = set()


def end_this_process():
    """Kill this process with SIGKILL now (no clean-up, no exit handlers)."""
    os.kill(os.getpid(), getattr(signal, "SIGKILL", signal.SIGTERM))
    os._exit(1)   # where the signal is not fatal at once


def arm_parent_death_signal():
    """Ask Linux to SIGKILL this process when the thread that forked it ends.

    Returns
    -------
    bool
        Whether it is armed (False on other systems or if ``prctl`` refused).
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        status = libc.prctl(_PR_SET_PDEATHSIG, ctypes.c_ulong(int(signal.SIGKILL)),
                            ctypes.c_ulong(0), ctypes.c_ulong(0), ctypes.c_ulong(0))
    except (OSError, AttributeError):
        return False
    return status == 0


def die_with_parent(parent_pid):
    """In a child: end with the parent ``parent_pid`` (Linux parent-death signal).

    The signal is armed, then the parent is checked: one that died before the signal was armed
    has left this process to another parent already, and this process ends now.

    Returns
    -------
    bool
        Whether the signal is armed (False off Linux: use a :class:`Lifeline` there).
    """
    armed = arm_parent_death_signal()
    if os.getppid() != parent_pid:
        end_this_process()
    return armed


def _close_write_ends_in_child():
    for fd in _WRITE_ENDS:
        try:
            os.close(fd)
        except OSError:
            pass
    _WRITE_ENDS.clear()


os.register_at_fork(after_in_child=_close_write_ends_in_child)


class Lifeline:
    """A pipe that tells the processes forked from this one that it has died.

    Make it before forking; pass :attr:`read_fd` to each forked child, which calls
    :func:`watch_lifeline` with it. Nobody writes into the pipe: a child's read returns only
    at end-of-file, once the write end is closed in this process, by :meth:`close` or by the
    kernel when this process dies. Every forked child closes its inherited copy of the write
    end before any of its own code runs, so the children never keep each other alive.

    Attributes
    ----------
    read_fd : int or None
        The end the children watch (None once closed).
    """

    def __init__(self):
        self.read_fd, self._write_fd = os.pipe()
        self._owner = os.getpid()
        _WRITE_ENDS.add(self._write_fd)

    def close(self):
        """Close both ends, which ends any child still watching; only in the process that
        made the lifeline (a forked copy of this object does nothing)."""
        if self.read_fd is None or os.getpid() != self._owner:
            return
        _WRITE_ENDS.discard(self._write_fd)
        for fd in (self._write_fd, self.read_fd):
            try:
                os.close(fd)
            except OSError:
                pass
        self.read_fd = self._write_fd = None


def _wait_for_end_of_file(read_fd):
    while True:
        try:
            data = os.read(read_fd, 1)
        except OSError:   # not an open pipe: nothing to watch
            return
        if not data:
            end_this_process()


def watch_lifeline(read_fd):
    """In a forked child: end this process when the parent of ``read_fd``'s lifeline dies.

    Starts a daemon thread that blocks reading ``read_fd`` (it costs nothing while it waits).
    """
    threading.Thread(target=_wait_for_end_of_file, args=(read_fd,), name="sonotrack-lifeline",
                     daemon=True).start()


def tied_command(argv):
    """A command line that runs ``argv`` so that it ends when this process dies.

    On Linux, called from the main thread: a Python launcher arms the parent-death signal,
    checks that this process still lives, and ``exec``'s ``argv`` (found on ``PATH`` as
    :func:`os.execvp` does). Elsewhere, or from another thread (whose end would fire the
    signal while this process still runs), ``argv`` unchanged.

    Parameters
    ----------
    argv : sequence of str
        The program and its arguments.

    Returns
    -------
    list of str
    """
    argv = [str(part) for part in argv]
    if (not sys.platform.startswith("linux")
            or threading.current_thread() is not threading.main_thread()):
        return argv
    return [sys.executable, "-c", _LAUNCHER, str(os.getpid()), *argv]


def _exec_tied():
    """The launcher of :func:`tied_command`: ``python -c ... PARENT_PID PROGRAM ARGS...``."""
    parent_pid, argv = int(sys.argv[1]), sys.argv[2:]
    die_with_parent(parent_pid)
    os.execvp(argv[0], argv)
