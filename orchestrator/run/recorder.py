"""Stream recorded outputs to ``results.csv`` while a run goes, keeping no rows in memory.

Each row is written as it comes (``str`` of each value joined by commas: the shortest text
that reads back as the same float, produced in C, with no per-value formatting in Python).
The file is flushed to the operating system once every simulated second, so a run that is
killed leaves a CSV readable up to its last second; ``fsync=True`` also forces every flush
to the disk (a power cut then loses at most a second; a killed process never loses what was
flushed, fsync or not). The file is always fsync'ed when the recorder closes, before a run
calls itself finished.

Memory does not grow with simulated time: the recorder holds one open file and its buffer.
Figures and plots are computed afterwards from the file (:mod:`orchestrator.run.results`).
"""

import os
from pathlib import Path

__all__ = ["Recorder"]


class Recorder:
    """Record ``(time, values...)`` rows to a CSV file.

    Parameters
    ----------
    path : path-like
        The CSV file to write (its folder is created).
    columns : list of str
        Column names after ``time`` (``instance.port``).
    flush_period : float
        Simulated seconds between flushes to the operating system (at most 1 s).
    fsync : bool
        Also fsync at every flush (default: only when closing).
    """

    def __init__(self, path, columns, flush_period=1.0, fsync=False):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.columns = list(columns)
        self.flush_period = min(float(flush_period), 1.0)
        self.fsync = bool(fsync)
        self.rows = 0
        self._file = open(self.path, "w", newline="", encoding="utf-8", buffering=1 << 16)
        self._write = self._file.write
        self._write(",".join(["time"] + self.columns) + "\n")
        self._next_flush = self.flush_period
        self.flush()

    def record(self, time, values):
        """Append one row; flush when a simulated flush period has passed."""
        # str of a float is its shortest round-tripping text (also for numpy scalars, whose
        # repr is "np.float64(...)"); ints and bools (0/1 from FMI) print as they are
        self._write(f"{time},{','.join(map(str, values))}\n")
        self.rows += 1
        if time >= self._next_flush:
            self.flush()
            while self._next_flush <= time:
                self._next_flush += self.flush_period

    def flush(self, fsync=None):
        """Push the rows written so far to the operating system (and to disk with fsync)."""
        self._file.flush()
        if self.fsync if fsync is None else fsync:
            os.fsync(self._file.fileno())

    def close(self):
        """Flush, fsync and close the file (safe to call twice)."""
        if not self._file.closed:
            try:
                self.flush(fsync=True)
            finally:
                self._file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
