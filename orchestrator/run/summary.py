"""The figures in a run's summary, computed once over a stream of row chunks from either source.

A *row source* holds some recorded columns of a run and yields its rows in chunks:

- ``names``: the columns it holds (``time`` first);
- ``chunks(columns)``: a new pass over every row, as successive ``{column: array}`` blocks of
  the columns asked for (each one of ``names``).

The figure functions (:func:`~orchestrator.run.metrics.tracking_summary`,
:func:`~orchestrator.run.fault_metrics.fault_summary`, and :func:`summary_figures` which
gathers them) read any source, as many passes as they need. There are two sources:

- :class:`RowTrace`: the summary's columns of each row, copied into a preallocated array as
  the recorder writes the row (one C-level copy of a tuple per row); one chunk;
- :class:`ResultRows`: ``results.csv`` read back in bounded chunks.

They give the same numbers: the CSV holds each float's shortest round-tripping text, so it
parses back to the very values the trace kept (``tests/unit/orchestrator/run/test_summary.py``
checks both ways agree).

Memory stays bounded: a run recording more than :data:`MAX_TRACE_ROWS` rows (400 simulated
seconds at the default 20 ms) keeps no trace, and its figures are read back from the file,
as they are for a run that did not end ``ok`` (the file, not the trace, is then the record
of what was kept).
"""

import operator

import numpy as np

from orchestrator.run.fault_metrics import fault_columns, fault_summary
from orchestrator.run.metrics import tracking_summary
from orchestrator.system.sonotrack import SONOTRACK

__all__ = ["MAX_TRACE_ROWS", "TRACE_COLUMNS", "ResultRows", "RowTrace", "has_figures",
           "summary_columns", "summary_figures"]

# 20,000 rows of ~15 columns: 2.4 MB at most, whatever the run's length.
MAX_TRACE_ROWS = 20_000
# Without these four there are no tracking figures (and no robustness section).
TRACE_COLUMNS = SONOTRACK.position_columns


def has_figures(columns):
    """Whether a run recording ``columns`` gets summary figures (all of :data:`TRACE_COLUMNS`)."""
    return all(c in columns for c in TRACE_COLUMNS)


def summary_columns(faults=()):
    """Every column the summary's figures read, ``time`` first, for a scenario's ``faults``."""
    return list(dict.fromkeys(("time",) + TRACE_COLUMNS + tuple(fault_columns(faults))))


class RowTrace:
    """The summary's columns of every recorded row, in memory: a row source of one chunk.

    Parameters
    ----------
    columns : sequence of str
        The recorded columns, in the order of the rows passed to :meth:`append` (after time).
    expected_rows : int
        Rows the run records if it runs to its end; no trace is kept (:attr:`kept` False)
        if that is more than :data:`MAX_TRACE_ROWS`.
    faults : sequence of (str, Fault)
        The scenario's faults (their targets' ``faults_active`` columns are kept too).
    every_column : bool
        Keep every recorded column, not only the summary's: the whole run, as
        :func:`~orchestrator.run.results.read_results` would read it back (a superset of
        columns is a row source like the file itself).

    Attributes
    ----------
    names : list of str
        ``time`` and the columns of :func:`summary_columns` that are recorded (every recorded
        column with ``every_column``).
    rows : int
        Rows appended so far.
    kept : bool
        Whether every row appended so far is held.
    """

    def __init__(self, columns, expected_rows, faults=(), every_column=False):
        self.names = ["time"] + (list(columns) if every_column else
                                 [c for c in summary_columns(faults)[1:] if c in columns])
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

    def column_copies(self):
        """``{column: array}`` of the rows kept, each a contiguous array of its own (as
        :func:`~orchestrator.run.results.read_results` returns them)."""
        return {name: np.ascontiguousarray(self._values[:self.rows, i])
                for i, name in enumerate(self.names)}

    def chunks(self, columns):
        """Yield the rows kept as one ``{column: array}`` chunk (views), none if empty."""
        if self.rows:
            index = {name: i for i, name in enumerate(self.names)}
            yield {name: self._values[:self.rows, index[name]] for name in columns}


class ResultRows:
    """A run's ``results.csv`` as a row source, read back in chunks of bounded size.

    Parameters
    ----------
    path : path-like
        The ``results.csv``.
    chunk_rows : int, optional
        Rows parsed at a time (default :data:`orchestrator.run.results.DEFAULT_CHUNK_ROWS`).

    Attributes
    ----------
    names : list of str
        The file's columns (its header).
    """

    def __init__(self, path, chunk_rows=None):
        from orchestrator.run.results import DEFAULT_CHUNK_ROWS, read_header

        self.path = path
        self.chunk_rows = chunk_rows or DEFAULT_CHUNK_ROWS
        self.names = read_header(path)

    def chunks(self, columns):
        """Yield successive ``{column: array}`` blocks of at most ``chunk_rows`` rows."""
        from orchestrator.run.results import iter_result_chunks

        return iter_result_chunks(self.path, columns, self.chunk_rows)


def summary_figures(rows, faults, stop_distance):
    """The tracking figures and the ``robustness`` section of a run.

    Parameters
    ----------
    rows : RowTrace or ResultRows
        The run's rows: kept while recording, or read back from ``results.csv``.
    faults : sequence of (str, Fault)
        The scenario's faults.
    stop_distance : float
        The planner's stop distance [m].

    Returns
    -------
    dict
        :func:`~orchestrator.run.metrics.tracking_summary`'s figures and ``robustness``,
        :func:`~orchestrator.run.fault_metrics.fault_summary`'s.
    """
    figures = tracking_summary(rows, stop_distance)
    figures["robustness"] = fault_summary(rows, faults, stop_distance)
    return figures
