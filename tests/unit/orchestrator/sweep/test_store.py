"""The sweep's store read as every reader reads a run folder, and the table's leftovers."""

import json
import os
import subprocess
import sys

from orchestrator.processes import process_record
from orchestrator.sweep.store import finished_summary, read_summary, write_table


def _ended_record():
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    record = process_record(child.pid)
    child.kill()
    child.wait()
    return record


def test_a_stored_run_whose_process_ended_is_abandoned_and_runs_again(tmp_path):
    gone, alive = tmp_path / "gone", tmp_path / "alive"
    for folder, record in ((gone, _ended_record()), (alive, process_record())):
        folder.mkdir()
        (folder / "summary.json").write_text(json.dumps({"status": "running",
                                                         "process": record}))
    assert read_summary(gone / "summary.json")["status"] == "abandoned"
    assert read_summary(alive / "summary.json")["status"] == "running"
    assert finished_summary(gone) is None and finished_summary(alive) is None


def test_a_killed_writers_temporary_table_goes_and_a_live_writers_stays(tmp_path):
    dead = _ended_record()["pid"]
    left = tmp_path / f".sweep.csv.{dead}.0a1b2c3d.partial"
    left.write_text("seed,status\n1,ok\n")
    live = tmp_path / f".sweep.json.{os.getpid()}.0a1b2c3d.partial"
    live.write_text("[")
    other = tmp_path / f".notes.txt.{dead}.0a1b2c3d.partial"   # not the table's
    other.write_text("x")
    csv_path, json_path = write_table([{"seed": 1, "status": "ok"}], tmp_path, ["seed"])
    assert not left.exists()
    assert live.exists() and other.exists()
    assert csv_path.read_text() == "seed,status\n1,ok\n"
    assert json.loads(json_path.read_text()) == [{"seed": 1, "status": "ok"}]
