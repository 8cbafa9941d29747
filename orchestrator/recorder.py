"""Stream recorded outputs to ``results.csv`` while a run goes.

Rows are written as they come and the file is flushed (and fsync'ed) at least once every
simulated second, so a run that is killed leaves a readable CSV up to its last second. The
rows are also kept in memory for the summary and plots at the end of the run.
"""

import csv
import os
from pathlib import Path

import numpy as np

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
        Simulated seconds between flushes to disk (at most 1 s).
    """

    def __init__(self, path, columns, flush_period=1.0):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.columns = list(columns)
        self.flush_period = min(float(flush_period), 1.0)
        self._file = open(self.path, "w", newline="")
        self._writer = csv.writer(self._file)
        self._writer.writerow(["time"] + self.columns)
        self._rows = []
        self._next_flush = self.flush_period
        self.flush()

    def record(self, time, values):
        """Append one row; flush when a simulated flush period has passed."""
        row = [time] + list(values)
        self._rows.append(row)
        # repr round-trips floats exactly; ints and bools (as 0/1 from FMI) print as they are
        self._file.write(",".join(map(repr, row)) + "\n")
        if time >= self._next_flush:
            self.flush()
            while self._next_flush <= time:
                self._next_flush += self.flush_period

    def flush(self):
        """Push the rows written so far to disk."""
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self):
        """Flush and close the file (safe to call twice)."""
        if not self._file.closed:
            self.flush()
            self._file.close()

    def as_arrays(self):
        """Return ``{"time": array, column: array, ...}`` of everything recorded."""
        data = np.array(self._rows, dtype=float) if self._rows else \
            np.zeros((0, len(self.columns) + 1))
        names = ["time"] + self.columns
        return {name: data[:, i] for i, name in enumerate(names)}

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
