"""A function run in a forked child while this process goes on.

For work that reads much of this process's memory and returns little: the reproduction study
draws its figures from every run's data (about 1 GB for the full study) while this process
judges the claims from the same data; a fork shares that memory instead of pickling it. The
child ends with this process however it dies (:func:`~.lifetime.die_with_parent`), returns its
value through a pipe, and a child that raises or dies is reported, never taken for a result.
Linux only (fork); elsewhere :class:`Beside` runs the function when :meth:`Beside.result` is
called.

:class:`BesideEach` spreads a list of such functions over a few forked children, each taking
the next function not yet taken (the study's figures on every free core).
"""

import multiprocessing
import os
import sys
import traceback

__all__ = ["Beside", "BesideEach"]


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


class BesideEach:
    """Call each of ``functions`` in up to ``processes`` forked children (:class:`Beside`);
    :meth:`result` waits for their values, in the order of ``functions``.

    Each child calls the next function that no child has taken yet, until none is left, so a
    long function does not hold up the others behind it.

    Examples
    --------
    >>> squares = BesideEach([lambda i=i: i * i for i in range(5)], processes=2)
    >>> squares.result()
    [0, 1, 4, 9, 16]
    """

    def __init__(self, functions, processes):
        functions = list(functions)
        self._count = len(functions)
        taken = multiprocessing.Value("l", 0)   # shared memory: the children take in turn

        def take():
            values = {}
            while True:
                with taken.get_lock():
                    index = taken.value
                    taken.value += 1
                if index >= len(functions):
                    return values
                values[index] = functions[index]()
        self._children = [Beside(take) for _ in range(max(1, min(processes, len(functions))))]

    def result(self):
        """The functions' values, in order.

        Raises
        ------
        RuntimeError
            Once every child has ended, if one raised or died (as :meth:`Beside.result`).
        """
        values, failure = {}, None
        for child in self._children:
            try:
                values.update(child.result())
            except RuntimeError as error:
                failure = failure or error
        if failure is not None:
            raise failure
        return [values[index] for index in range(self._count)]


def _child(function, send, parent):
    from .lifetime import die_with_parent

    die_with_parent(parent)
    try:
        value = ("ok", function())
    except BaseException as exc:   # reported to the parent, which raises it
        value = ("error", "".join(traceback.format_exception(exc)).rstrip())
    send.send(value)
    send.close()
