"""The sweep's files: stored runs read defensively, the table written atomically.

A run is stored in ``<out>/runs/<key>/`` and counts as done only when its ``summary.json``
parses as a JSON object whose ``status`` is ``"ok"``. Anything else (no summary, a summary
truncated by a kill, a failed or interrupted run, a run abandoned by a killed process) means
"run it again", never a crash and never a stale answer. Summaries are read as the run folder
reads them (:func:`orchestrator.run.folder.mark_abandoned`): a ``"running"`` run whose process
is gone reads as ``"abandoned"``.

The table (``sweep.csv`` and ``sweep.json``) is written to a temporary file in the same
folder and renamed over the old one, so a reader (or a killed sweep) sees either the previous
table or the new one, never half of one. A temporary table file whose writer is gone (a sweep
killed while writing) is removed by the next write.
"""

import contextlib
import csv
import io
import json
import socket
from pathlib import Path

from orchestrator.files.atomic import TEMPORARY_PREFIX, TEMPORARY_SUFFIX, atomic_write_text
from orchestrator.files.json_policy import dumps
from orchestrator.processes import GONE, process_state
from orchestrator.run.folder import mark_abandoned

__all__ = ["finished_summary", "read_summary", "table_columns", "write_atomic", "write_table"]

# Row fields that come first in the table, after the swept settings.
_LEADING = ("seed", "status", "error", "hash", "run_dir")


def read_summary(path):
    """Return the summary in ``path``, or None if it is missing, unreadable or not an object.

    A ``"running"`` summary whose process is gone comes back ``"abandoned"``
    (:func:`orchestrator.run.folder.mark_abandoned`).
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
        data = json.loads(text)
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    return mark_abandoned(data) if isinstance(data, dict) else None


def finished_summary(run_dir):
    """The summary of a finished run in ``run_dir``, or None if it must run (again)."""
    summary = read_summary(Path(run_dir) / "summary.json")
    if summary is None or summary.get("status") != "ok":
        return None
    return summary


def write_atomic(path, text):
    """Write ``text`` to ``path`` (folder created) with the one atomic writer, fsync'ed."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, text)


def table_columns(rows, settings=()):
    """Column order: swept settings, then seed/status/error/hash/run_dir, then the figures."""
    present = list(dict.fromkeys(k for row in rows for k in row))
    leading = [k for k in settings if k in present and k not in _LEADING]
    leading += [k for k in _LEADING if k in present]
    return leading + [k for k in present if k not in leading]


def _remove_abandoned_temporaries(out_dir):
    """Remove ``.sweep.csv.<pid>.<random>.partial`` files whose writing process is gone."""
    host = socket.gethostname()
    for path in out_dir.glob(f"{TEMPORARY_PREFIX}sweep.*{TEMPORARY_SUFFIX}"):
        parts = path.name.split(".")   # "", "sweep", "csv", pid, random, "partial"
        if len(parts) == 6 and parts[3].isdigit() and process_state(
                {"pid": int(parts[3]), "host": host}) == GONE:
            with contextlib.suppress(OSError):
                path.unlink()


def write_table(rows, out_dir, settings=()):
    """Write ``sweep.json`` and ``sweep.csv`` in ``out_dir`` atomically; return their paths."""
    out_dir = Path(out_dir)
    _remove_abandoned_temporaries(out_dir)
    table_json = out_dir / "sweep.json"
    table_csv = out_dir / "sweep.csv"
    write_atomic(table_json, dumps(rows, indent=2) + "\n")
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, table_columns(rows, settings), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    write_atomic(table_csv, buffer.getvalue())
    return table_csv, table_json
