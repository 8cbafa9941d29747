"""A function run in a forked child while this process goes on.

For work that reads much of this process's memory and returns little: the reproduction study
draws its figures from every run's data (about 1 GB for the full study) while this process
judges the claims from the same data; a fork shares that memory instead of pickling it. The
child ends with this process however it dies (:func:`~.lifetime.die_with_parent`), returns its
value through a pipe, and a child that raises or dies is reported, never taken for a result.
Linux only (fork); elsewhere :class:`Beside` runs the function when :meth:`Beside.result` is
called.
"""

import multiprocessing
import os
import sys
import traceback

__all__ = ["Beside"]


class Beside:
    """Start ``function()`` in a forked child now; :meth:`result` waits for its value.

    Examples
    --------
    >>> data = list(range(1000))
    >>> Beside(lambda: sum(data)).result()
    499500
    """

    def __init__(self, function):
        self._function = function
        self._process = None
        if not sys.platform.startswith("linux"):
            return
        context = multiprocessing.get_context("fork")
        self._receive, send = context.Pipe(duplex=False)
        self._process = context.Process(target=_child, args=(function, send, os.getpid()),
                                        daemon=True)
        self._process.start()
        send.close()   # the child holds the only write end: its death is end-of-file here

    def result(self):
        """The function's value.

        Raises
        ------
        RuntimeError
            If the child raised (with its traceback) or ended without a value (with its exit
            code).
        """
        if self._process is None:
            return self._function()
        try:
            kind, value = self._receive.recv()
        except EOFError:
            kind, value = "died", None
        finally:
            self._receive.close()
            self._process.join()
        if kind == "ok":
            return value
        if kind == "died":
            raise RuntimeError(f"the child process ended without a result (exit code "
                               f"{self._process.exitcode})")
        raise RuntimeError(f"the child process raised:\n{value}")


def _child(function, send, parent):
    from .lifetime import die_with_parent

    die_with_parent(parent)
    try:
        value = ("ok", function())
    except BaseException as exc:   # reported to the parent, which raises it
        value = ("error", "".join(traceback.format_exception(exc)).rstrip())
    send.send(value)
    send.close()
