"""The figures in a run's summary, kept from the rows as the recorder writes them.

The summary's tracking figures (:func:`orchestrator.run.metrics.tracking_summary`) and its
robustness section (:func:`orchestrator.run.fault_metrics.fault_summary`) read about fifteen of
the recorded columns. Re-reading them from ``results.csv`` after the run parses the file
three times; a :class:`RowTrace` instead copies those columns of each row into a
preallocated array as the row is recorded (one C-level copy of a tuple per row), and
:func:`summary_figures` computes the same figures from it. They are the same numbers: the
CSV holds each float's shortest round-tripping text, so it parses back to the very values
the trace kept (``tests/unit/orchestrator/run/test_summary.py`` checks both ways agree).

Memory stays bounded: a run recording more than :data:`MAX_TRACE_ROWS` rows (400 simulated
seconds at the default 20 ms) keeps no trace, and its figures are read back from the file in
chunks (:func:`summary_figures_from_csv`), as they are for a run that did not end ``ok``
(the file, not the trace, is then the record of what was kept).
"""

import operator

import numpy as np

from orchestrator.run.fault_metrics import fault_columns, fault_summary
from orchestrator.run.metrics import tracking_summary, tracking_summary_from_csv

__all__ = ["MAX_TRACE_ROWS", "TRACE_COLUMNS", "RowTrace", "summary_figures",
           "summary_figures_from_csv"]

# 20,000 rows of ~15 columns: 2.4 MB at most, whatever the run's length.
MAX_TRACE_ROWS = 20_000
# Without these four there are no tracking figures (and no robustness section).
TRACE_COLUMNS = ("plant.x", "plant.y", "source.x", "source.y")


class RowTrace:
    """The summary's columns of every recorded row, in memory.

    Parameters
    ----------
    columns : sequence of str
        The recorded columns, in the order of the rows passed to :meth:`append` (after time).
    expected_rows : int
        Rows the run records if it runs to its end; no trace is kept (:attr:`kept` False)
        if that is more than :data:`MAX_TRACE_ROWS`.
    faults : sequence of (str, Fault)
        The scenario's faults (their targets' ``faults_active`` columns are kept too).
    """

    def __init__(self, columns, expected_rows, faults=()):
        wanted = list(dict.fromkeys(TRACE_COLUMNS + tuple(fault_columns(faults))))
        self.names = ["time"] + [c for c in wanted if c != "time" and c in columns]
        self.rows = 0
        self.kept = 0 < expected_rows <= MAX_TRACE_ROWS
        self._capacity = expected_rows if self.kept else 0
        self._values = np.empty((self._capacity, len(self.names)))
        positions = [list(columns).index(c) for c in self.names[1:]]
        # itemgetter of one index returns the item, not a 1-tuple
        self._pick = (operator.itemgetter(*positions) if len(positions) > 1 else
                      (lambda row, i=positions[0]: (row[i],)) if positions else
                      (lambda row: ()))

    def append(self, time, row):
        """Keep the summary's columns of one recorded row."""
        if self.rows < self._capacity:
            values = self._values[self.rows]
            values[0] = time
            values[1:] = self._pick(row)
        else:
            self.kept = False   # more rows than the run was expected to record
        self.rows += 1

    def columns(self):
        """``{column: array}`` of the rows kept (views, not copies)."""
        return {name: self._values[:self.rows, i] for i, name in enumerate(self.names)}


def summary_figures(trace, faults, stop_distance):
    """The tracking figures and the ``robustness`` section from a complete :class:`RowTrace`.

    Returns
    -------
    dict
        As :func:`summary_figures_from_csv` on the file the same rows were written to.
    """
    data = trace.columns()
    figures = tracking_summary(data["time"],
                               np.column_stack([data["plant.x"], data["plant.y"]]),
                               np.column_stack([data["source.x"], data["source.y"]]),
                               stop_distance)
    figures["robustness"] = fault_summary([data], trace.names, faults, stop_distance)
    return figures


def summary_figures_from_csv(path, faults, stop_distance):
    """The tracking figures and the ``robustness`` section read back from ``results.csv``
    in bounded chunks (the reference :func:`summary_figures` is checked against)."""
    from orchestrator.run.fault_metrics import fault_summary_from_csv

    figures = tracking_summary_from_csv(path, stop_distance)
    figures["robustness"] = fault_summary_from_csv(path, faults, stop_distance)
    return figures
