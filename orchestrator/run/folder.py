"""A run's output folder: atomic writes, the run's own files, and a status saying if it finished.

A run folder holds ``summary.json``, ``results.csv`` and the PNG plots. ``summary.json`` is the
marker of a finished run. Its ``status`` is

- ``"running"`` from the moment a run starts writing into the folder;
- ``"ok"`` only once the last step is done and ``results.csv`` is complete and on disk;
- ``"failed"`` or ``"interrupted"``, with the reason in ``error``, as soon as that is known.

A run killed by SIGKILL or a power cut cannot write anything more, so its file keeps saying
``"running"``. Every summary names the process that writes it (``process``: id, host, start
time; :mod:`orchestrator.processes.identity`), and :func:`read_summary` (with
:func:`mark_abandoned`, which every reader of summaries uses) reports a ``"running"`` run whose
process is gone from this host (no such process, or the id now names a newer process) as
``"abandoned"``, with ``error`` saying which process ended. The same holds for the plots:
``plots: "drawing"`` reads as ``plots: "abandoned"`` (with ``plots_error``) once the run's
process is gone. ``"abandoned"`` is never written, only read; a run recorded on another host
reads as it was written (this host cannot see that host's processes).

When a run starts in a folder that holds an older run, the order of its first writes is chosen
so that a kill at any instant never leaves an older summary beside newer results:

1. the old ``summary.json`` is unlinked (one system call: it is there or it is gone);
2. the run's own files (``results.csv``, the plots, leftover temporary files) are removed;
3. ``summary.json`` is written with status ``running``.

Every file but the streamed ``results.csv`` is written whole to a temporary name in the same
folder, flushed (and fsync'ed) and renamed over its target (:func:`atomic_write_bytes`, from
:mod:`orchestrator.files.atomic`, re-exported here), so a reader sees either the old content or
the new one, never a truncated file. ``summary.json`` follows the JSON policy of
:mod:`orchestrator.files.json_policy` (a non-finite number is written as ``null``).
"""

import contextlib
import json
import os
from pathlib import Path

from components.common.errors import ConfigError
from orchestrator.files.atomic import (TEMPORARY_PREFIX, TEMPORARY_SUFFIX, atomic_write_bytes,
                                       atomic_write_json, atomic_write_text)
from orchestrator.processes import GONE, describe, process_record, process_state

__all__ = [
    "ABANDONED",
    "RESULTS_NAME",
    "STATUSES",
    "SUMMARY_NAME",
    "RunFolder",
    "atomic_write_bytes",
    "atomic_write_json",
    "atomic_write_text",
    "mark_abandoned",
    "read_summary",
]

SUMMARY_NAME = "summary.json"
RESULTS_NAME = "results.csv"
# What a run writes; a reader may also see ABANDONED (see the module docstring).
STATUSES = ("running", "ok", "failed", "interrupted")
ABANDONED = "abandoned"
# Temporary files are named by the one atomic writer (orchestrator.files.atomic).
_TEMP_PREFIX = TEMPORARY_PREFIX
_TEMP_SUFFIX = TEMPORARY_SUFFIX


def _temporary_name(path):
    return path.with_name(f"{_TEMP_PREFIX}{path.name}.{os.getpid()}{_TEMP_SUFFIX}")


def mark_abandoned(summary):
    """A summary as a reader takes it: a run whose process is gone is ``"abandoned"``.

    Parameters
    ----------
    summary : dict
        A run's summary as written.

    Returns
    -------
    dict
        ``summary`` itself, unless it says ``status: "running"`` or ``plots: "drawing"`` while
        the process it names is gone from this host: then a copy saying ``"abandoned"``
        instead, with ``error`` (``plots_error``) naming the process. A run still going, one
        recorded on another host and one without a process record come back unchanged.
    """
    drawing = summary.get("plots") == "drawing"
    if summary.get("status") != "running" and not drawing:
        return summary
    record = summary.get("process")
    if process_state(record) != GONE:
        return summary
    summary = dict(summary)
    if summary["status"] == "running":
        summary["status"] = ABANDONED
        summary.setdefault("error", f"abandoned: the process that ran it ({describe(record)}) "
                                    "ended before the run finished")
    if drawing:
        summary["plots"] = ABANDONED
        summary.setdefault("plots_error", f"abandoned: the process drawing the plots "
                                          f"({describe(record)}) ended before they were written")
    return summary


def read_summary(run_dir):
    """Return the ``summary.json`` of a run folder as a dict, or None if there is none.

    A summary that cannot be parsed (not written by this module: atomic writes never leave
    one) counts as none. Whether the run finished is ``summary["status"] == "ok"``; a run
    killed before it finished reads as ``"abandoned"`` (:func:`mark_abandoned`).
    """
    path = Path(run_dir) / SUMMARY_NAME
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return mark_abandoned(data) if isinstance(data, dict) else None


class RunFolder:
    """The output folder of one run.

    Parameters
    ----------
    path : path-like
        The folder (created if missing).
    own_files : iterable of str
        Names of the files a run writes besides ``summary.json`` and ``results.csv`` (the
        plots); an older run's copies are removed when this run starts.
    fsync : bool
        fsync each summary and the folder after writing it (survives a power cut, not only a
        kill); a sweep's runs leave it off (see :func:`orchestrator.run.runner.run_scenario`).
    """

    def __init__(self, path, own_files=(), fsync=True):
        self.path = Path(path)
        self.fsync = fsync
        self.summary_json = self.path / SUMMARY_NAME
        self.results_csv = self.path / RESULTS_NAME
        self.own_files = tuple(own_files)

    def check(self):
        """Create the folder and make sure a file can be written in it.

        Raises
        ------
        ConfigError
            Naming the folder and why it cannot hold results (a file is in the way, no
            permission, a read-only or special file system such as /proc).
        """
        if self.path.exists() and not self.path.is_dir():
            raise ConfigError(f"results folder {self.path}: is a file, not a folder; "
                              f"choose another --out")
        try:
            self.path.mkdir(parents=True, exist_ok=True)
            probe = _temporary_name(self.path / ".write-probe")
            with open(probe, "wb") as stream:
                stream.write(b"probe")
            probe.unlink()
        except OSError as error:
            reason = error.strerror or type(error).__name__
            raise ConfigError(f"results folder {self.path}: cannot write there ({reason}); "
                              f"choose another --out") from None

    def start(self, summary):
        """Clear an older run's files and write ``summary`` with status ``running``.

        See the module docstring for why the steps come in this order. The summary names this
        process (``process``) unless it names one already.
        """
        with contextlib.suppress(FileNotFoundError):
            self.summary_json.unlink()
        stale = [self.results_csv] + [self.path / name for name in self.own_files]
        stale += [p for p in self.path.glob(f"{_TEMP_PREFIX}*{_TEMP_SUFFIX}") if p.is_file()]
        for path in stale:
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
        summary = {**summary, "status": "running"}
        summary.setdefault("process", process_record())
        self.write_summary(summary)

    def write_summary(self, summary):
        """Write ``summary`` atomically.

        Its ``status`` must be one of :data:`STATUSES`, and a summary saying ``running`` or
        plots ``drawing`` must name its process (``process``), or no reader could ever tell it
        from an abandoned one.
        """
        if summary.get("status") not in STATUSES:
            raise ValueError(f"summary status {summary.get('status')!r} is not one of "
                             f"{', '.join(STATUSES)}")
        if ((summary["status"] == "running" or summary.get("plots") == "drawing")
                and not isinstance(summary.get("process"), dict)):
            raise ValueError(f"summary status {summary['status']!r}, plots "
                             f"{summary.get('plots')!r}: a summary of a run in progress must "
                             "name its process ('process', from orchestrator.processes."
                             "process_record)")
        atomic_write_json(self.summary_json, summary, fsync=self.fsync)
