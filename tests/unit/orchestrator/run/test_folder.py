"""Run outputs: atomic writes, the run folder's start order, a dead run's summary read back
as abandoned, the results reader, and a recorder that keeps no rows (the figures read back from
the file: test_metrics.py)."""

import json
import os
import socket
import subprocess
import sys
import tracemalloc

import numpy as np
import pytest

from components.common.errors import ConfigError
from orchestrator.run import folder as outputs
from orchestrator.processes import process_record
from orchestrator.run.folder import (RunFolder, atomic_write_bytes, atomic_write_json,
                                     mark_abandoned, read_summary)
from orchestrator.run.recorder import Recorder
from orchestrator.run.results import count_rows, iter_result_chunks, read_results


# ----- atomic writes ------------------------------------------------------------------------

def test_atomic_write_replaces_whole_file_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "summary.json"
    target.write_text("old content that is longer than the new one\n")
    atomic_write_json(target, {"status": "ok", "value": 1.5})
    assert json.loads(target.read_text()) == {"status": "ok", "value": 1.5}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["summary.json"]


def test_atomic_write_failure_keeps_the_old_file(tmp_path, monkeypatch):
    """A writer that dies half-way (here: the rename fails) leaves the old file whole."""
    target = tmp_path / "summary.json"
    target.write_text('{"status": "ok"}\n')

    def broken_replace(source, destination):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(outputs.os, "replace", broken_replace)
    with pytest.raises(OSError):
        atomic_write_bytes(target, b'{"status": "runn')
    assert json.loads(target.read_text()) == {"status": "ok"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["summary.json"]


def test_atomic_write_goes_through_a_rename(tmp_path, monkeypatch):
    """The target never holds partial bytes: the only write to it is os.replace."""
    calls = []
    original = os.replace
    monkeypatch.setattr(outputs.os, "replace",
                        lambda a, b: (calls.append((str(a), str(b))), original(a, b)))
    target = tmp_path / "table.csv"
    atomic_write_bytes(target, b"a,b\n1,2\n")
    assert len(calls) == 1 and calls[0][1] == str(target) and calls[0][0] != str(target)
    assert target.read_bytes() == b"a,b\n1,2\n"


# ----- the run folder ------------------------------------------------------------------------

def test_run_folder_start_clears_an_older_run_and_says_running(tmp_path):
    folder = RunFolder(tmp_path, own_files=("trajectories.png",))
    (tmp_path / "summary.json").write_text('{"status": "ok"}')
    (tmp_path / "results.csv").write_text("time\n0.0\n")
    (tmp_path / "trajectories.png").write_bytes(b"png")
    (tmp_path / ".summary.json.999.partial").write_text("{")
    (tmp_path / "notes.txt").write_text("the user's own file")
    folder.check()
    folder.start({"scenario": "x"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt", "summary.json"]
    summary = read_summary(tmp_path)
    assert summary == {"scenario": "x", "status": "running", "process": summary["process"]}
    assert (summary["process"]["pid"], summary["process"]["host"]) == (os.getpid(),
                                                                      socket.gethostname())


def test_run_folder_start_unlinks_the_old_summary_first(tmp_path, monkeypatch):
    """Killed between any two of its steps, start() never leaves an ok summary beside a
    half-cleared folder: the old summary goes first."""
    folder = RunFolder(tmp_path, own_files=("trajectories.png",))
    (tmp_path / "summary.json").write_text('{"status": "ok"}')
    (tmp_path / "results.csv").write_text("time\n0.0\n")
    (tmp_path / "trajectories.png").write_bytes(b"png")
    seen = []
    original = type(tmp_path).unlink

    def unlink(path, missing_ok=False):
        seen.append((path.name, read_summary(tmp_path)))
        return original(path, missing_ok=missing_ok)

    monkeypatch.setattr(type(tmp_path), "unlink", unlink)
    folder.start({})
    assert seen[0] == ("summary.json", {"status": "ok"})
    assert all(summary is None for name, summary in seen[1:])


def test_run_folder_refuses_a_file_and_an_unwritable_place(tmp_path):
    a_file = tmp_path / "results"
    a_file.write_text("x")
    with pytest.raises(ConfigError, match="is a file, not a folder"):
        RunFolder(a_file).check()
    if os.path.isdir("/proc/self"):
        with pytest.raises(ConfigError, match="cannot write there"):
            RunFolder("/proc/self/sonotrack-run").check()


def test_summary_status_must_be_known(tmp_path):
    with pytest.raises(ValueError, match="not one of"):
        RunFolder(tmp_path).write_summary({"status": "done"})
    with pytest.raises(ValueError, match="not one of"):   # read, never written
        RunFolder(tmp_path).write_summary({"status": "abandoned", "process": process_record()})


@pytest.mark.parametrize("summary", [{"status": "running"}, {"status": "ok", "plots": "drawing"}],
                         ids=["running", "drawing"])
def test_a_summary_of_a_run_in_progress_must_name_its_process(tmp_path, summary):
    with pytest.raises(ValueError, match="must name its process"):
        RunFolder(tmp_path).write_summary(summary)
    assert not (tmp_path / "summary.json").exists()


# ----- a summary whose process is gone ------------------------------------------------------

@pytest.fixture(scope="module")
def ended_process():
    """The record of a process that ran here and has ended (reaped)."""
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    record = process_record(child.pid)
    child.kill()
    child.wait()
    return record


def test_a_running_summary_whose_process_ended_reads_abandoned(tmp_path, ended_process):
    folder = RunFolder(tmp_path)
    folder.write_summary({"scenario": "x", "status": "running", "process": ended_process})
    summary = read_summary(tmp_path)
    assert summary["status"] == "abandoned"
    assert summary["error"] == (f"abandoned: the process that ran it (pid "
                                f"{ended_process['pid']} on {socket.gethostname()}) ended "
                                "before the run finished")
    assert json.loads((tmp_path / "summary.json").read_text())["status"] == "running"


def test_plots_being_drawn_by_a_process_that_ended_read_abandoned(tmp_path, ended_process):
    RunFolder(tmp_path).write_summary({"status": "ok", "plots": "drawing",
                                       "process": ended_process})
    summary = read_summary(tmp_path)
    assert (summary["status"], summary["plots"]) == ("ok", "abandoned")
    assert f"pid {ended_process['pid']} on " in summary["plots_error"]
    assert "error" not in summary


@pytest.mark.parametrize("case", ["alive", "other-host", "no-record", "finished"])
def test_what_is_not_known_to_be_dead_reads_as_written(tmp_path, ended_process, case):
    summary = {"status": "running", "process": process_record()}
    if case == "other-host":
        summary["process"] = dict(ended_process, host=socket.gethostname() + ".elsewhere")
    elif case == "no-record":   # written before summaries named their process
        summary.pop("process")
    elif case == "finished":
        summary = {"status": "ok", "plots": ["trajectories.png"], "process": ended_process}
    assert mark_abandoned(summary) is summary
    (tmp_path / "summary.json").write_text(json.dumps(summary))
    assert read_summary(tmp_path) == summary


# ----- recorder and reader ----------------------------------------------------------------

def test_recorder_keeps_no_rows(tmp_path):
    """Memory of a recorder does not grow with the rows it writes (traced allocations after
    50,000 rows of 30 columns stay below 1 MB; keeping them would take over 40 MB)."""
    columns = [f"x.c{i}" for i in range(30)]
    row = [0.1 * i for i in range(30)]
    recorder = Recorder(tmp_path / "results.csv", columns)
    tracemalloc.start()
    try:
        for k in range(50_000):
            recorder.record(k * 0.01, row)
        current, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
        recorder.close()
    assert peak < 1_000_000, peak
    assert count_rows(tmp_path / "results.csv") == 50_000
    assert not [name for name, value in vars(recorder).items()
                if isinstance(value, (list, dict, np.ndarray)) and name != "columns"]


def test_recorder_rows_read_back_exactly(tmp_path):
    rng = np.random.default_rng(3)
    values = rng.normal(size=(257, 3)) * 10.0 ** rng.integers(-300, 300, size=(257, 3))
    with Recorder(tmp_path / "r.csv", ["a.x", "a.y", "b.n"]) as recorder:
        for k, row in enumerate(values):
            recorder.record(k * 0.02, [row[0], row[1], int(k)])
    for chunk_rows in (1, 10, 1000):
        data = read_results(tmp_path / "r.csv", chunk_rows=chunk_rows)
        np.testing.assert_array_equal(data["a.x"], values[:, 0])
        np.testing.assert_array_equal(data["a.y"], values[:, 1])
        np.testing.assert_array_equal(data["b.n"], np.arange(257))
        np.testing.assert_array_equal(data["time"], np.arange(257) * 0.02)


def test_reader_skips_a_row_cut_short_by_a_kill(tmp_path):
    path = tmp_path / "results.csv"
    path.write_text("time,a.x\n0.0,1.0\n0.02,2.0\n0.04,3.")
    assert count_rows(path) == 2
    assert list(read_results(path)["a.x"]) == [1.0, 2.0]
    assert sum(len(c["time"]) for c in iter_result_chunks(path, chunk_rows=1)) == 2


def test_reader_thins_to_max_rows_and_keeps_the_last(tmp_path):
    path = tmp_path / "results.csv"
    path.write_text("time\n" + "".join(f"{k}.0\n" for k in range(1001)))
    data = read_results(path, max_rows=100, chunk_rows=37)
    expected = list(range(0, 1001, 11)) + [1000]
    assert list(data["time"]) == expected


def test_reader_names_a_missing_column(tmp_path):
    path = tmp_path / "results.csv"
    path.write_text("time,a.x\n0.0,1.0\n")
    with pytest.raises(ConfigError, match="no column b.y"):
        read_results(path, ["b.y"])


def test_thinned_read_keeps_no_parsed_block(tmp_path):
    """read_results(max_rows=...) holds only the rows it keeps: 40,000 rows of 20 columns
    (6.7 MB as floats) thinned to 100 rows peak at a few parsed blocks, not the whole file
    (strided views of each parsed block would keep every block alive until the end)."""
    columns = [f"x.c{i}" for i in range(20)]
    with Recorder(tmp_path / "r.csv", columns) as recorder:
        for k in range(40_000):
            recorder.record(k * 0.02, [k + 0.5 * i for i in range(20)])
    tracemalloc.start()
    try:
        data = read_results(tmp_path / "r.csv", max_rows=100)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert len(data["time"]) <= 101 and data["x.c0"][-1] == 39_999
    assert peak < 4_000_000, peak
