"""Read a run's ``results.csv`` in bounded chunks, whatever its length.

The recorder streams rows to disk and keeps none, so everything computed after a run (the
summary's figures, the plots) reads the file back. :func:`iter_result_chunks` parses a fixed
number of rows at a time (memory bounded by ``chunk_rows`` x the columns asked for, not by the
run's length) and :func:`read_results` returns chosen columns thinned to at most ``max_rows``.

A run that was killed may leave a last line without its newline (a write cut short); such a
line is not a complete row and is skipped, so a killed run's file still reads.
"""

from itertools import islice
from pathlib import Path

import numpy as np

from components.common.errors import ConfigError

__all__ = ["DEFAULT_CHUNK_ROWS", "count_rows", "iter_result_chunks", "read_header",
           "read_results"]

# 2,048 rows of ~60 columns are ~2 MB of text and ~1 MB of floats: small beside a run, and
# large enough that parsing stays in numpy's C loop (measured: 16,384 rows added ~35 MB to a
# long run's peak RSS over a short run's).
DEFAULT_CHUNK_ROWS = 2048


def read_header(path):
    """Column names of a results file (``time`` first)."""
    with open(path, encoding="utf-8", newline="") as stream:
        header = stream.readline()
    if not header.endswith("\n"):
        raise ConfigError(f"{path}: no complete header line; not a results file")
    return header.rstrip("\r\n").split(",")


def count_rows(path):
    """Number of complete data rows (lines ending in a newline, after the header)."""
    lines = 0
    with open(path, "rb") as stream:
        while block := stream.read(1 << 20):
            lines += block.count(b"\n")
    return max(0, lines - 1)


def _parse(lines, usecols):
    try:
        return np.loadtxt(lines, delimiter=",", usecols=usecols, ndmin=2, dtype=float)
    except ValueError:
        # Booleans from the in-process backend are written as True/False
        lines = [line.replace("True", "1").replace("False", "0") for line in lines]
        return np.loadtxt(lines, delimiter=",", usecols=usecols, ndmin=2, dtype=float)


def iter_result_chunks(path, columns=None, chunk_rows=DEFAULT_CHUNK_ROWS):
    """Yield ``{column: array}`` for successive blocks of at most ``chunk_rows`` rows.

    Parameters
    ----------
    path : path-like
        A ``results.csv`` written by :class:`orchestrator.run.recorder.Recorder`.
    columns : sequence of str, optional
        Columns to read (default all, ``time`` included).
    chunk_rows : int
        Rows per block.

    Raises
    ------
    ConfigError
        If a column is not in the file (naming the columns that are).
    """
    path = Path(path)
    header = read_header(path)
    names = list(header) if columns is None else list(columns)
    missing = [name for name in names if name not in header]
    if missing:
        raise ConfigError(f"{path}: no column {', '.join(missing)}; columns: "
                          f"{', '.join(header)}")
    usecols = [header.index(name) for name in names]
    with open(path, encoding="utf-8", newline="") as stream:
        stream.readline()
        while True:
            lines = list(islice(stream, chunk_rows))
            if not lines:
                return
            if not lines[-1].endswith("\n"):
                lines.pop()  # a row cut short by a kill: not a row
                if not lines:
                    return
            block = _parse(lines, usecols)
            yield {name: block[:, i] for i, name in enumerate(names)}


def read_results(path, columns=None, max_rows=None, chunk_rows=DEFAULT_CHUNK_ROWS):
    """Read columns of a results file, thinned to at most about ``max_rows`` rows.

    Parameters
    ----------
    path : path-like
        The ``results.csv``.
    columns : sequence of str, optional
        Columns to read (default all).
    max_rows : int, optional
        Keep every k-th row, with k the smallest step giving at most ``max_rows`` rows, plus
        the last row (default: every row).

    Returns
    -------
    dict of str to numpy.ndarray
    """
    names = read_header(path) if columns is None else list(columns)
    every = 1
    if max_rows is not None:
        every = max(1, -(-count_rows(path) // max(1, int(max_rows))))
    parts = {name: [] for name in names}
    seen = 0
    last = None
    for chunk in iter_result_chunks(path, names, chunk_rows):
        length = len(chunk[names[0]]) if names else 0
        first = (-seen) % every
        for name in names:
            # a copy: a strided view would keep the whole parsed block alive
            parts[name].append(chunk[name][first::every].copy())
        if length:
            last_index = seen + length - 1
            last = (last_index, {name: chunk[name][-1:] for name in names})
        seen += length
    if last is not None and last[0] % every:
        for name in names:
            parts[name].append(last[1][name])
    return {name: (np.concatenate(parts[name]) if parts[name] else np.zeros(0))
            for name in names}
