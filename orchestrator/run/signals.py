"""Turn SIGINT (Ctrl-C) and SIGTERM into a request to stop a run at its next step.

Python's default SIGINT handler raises :class:`KeyboardInterrupt` wherever the main thread
is, which in a co-simulation is usually inside an FMU's own Python code (pythonfmu slaves run
in the host's interpreter): the FMU then reports ``fmi2Fatal`` and the user reads that an
instance failed. :class:`StopSignals` only records the signal; the run loop checks
:attr:`StopSignals.received` after each step, stops cleanly and keeps what it computed. A
second signal of either kind gets the previous behaviour back (a second Ctrl-C aborts at once).
"""

import signal
import threading

__all__ = ["StopSignals"]


class StopSignals:
    """Context manager recording SIGINT and SIGTERM while a run steps.

    Handlers are installed only in the main thread (Python allows no other); elsewhere, e.g. in
    a Dask worker's thread, the context does nothing and :attr:`received` stays None.

    Attributes
    ----------
    received : int or None
        The first signal received, or None.
    """

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self):
        self.received = None
        self._previous = {}

    @property
    def name(self):
        """Name of the received signal (``"SIGINT"``), or None."""
        return signal.Signals(self.received).name if self.received is not None else None

    def _handle(self, number, frame):
        if self.received is None:
            self.received = number
        self._restore()

    def _restore(self):
        for number, handler in self._previous.items():
            # None: a handler installed outside Python; the default is the closest we can give
            signal.signal(number, signal.SIG_DFL if handler is None else handler)
        self._previous = {}

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for number in self.SIGNALS:
                self._previous[number] = signal.getsignal(number)
                signal.signal(number, self._handle)
        return self

    def __exit__(self, *exc):
        self._restore()
        return False
