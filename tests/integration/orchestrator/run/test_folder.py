"""A run's folder never lies: killed, interrupted or failed runs are never taken for finished.

``sonotrack run`` is started as a child process and stopped with SIGKILL at random moments
(into a fresh folder and into one holding an older finished run), with SIGINT and SIGTERM,
and pointed at folders it cannot use.
"""

import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from orchestrator.run.folder import read_summary
from orchestrator.run.plots import PLOT_FILES
from orchestrator.run.results import count_rows, read_results
from tests.support.process_group import (end_command, pause_env, read_to_eof, wait_for_stopped,
                                         wait_until_gone)

pytestmark = pytest.mark.integration

REPO = Path(__file__).resolve().parents[4]
STOP_TIME = 30.0
RECORD_INTERVAL = 0.02


def _scenario(tmp_path, stop_time=STOP_TIME):
    """The shipped S-curve scenario with another stop time, its system given absolutely."""
    text = (REPO / "scenarios" / "s_curve.toml").read_text()
    lines = [line for line in text.splitlines()
             if not line.startswith(("stop_time", "system"))]
    path = tmp_path / f"s_curve_{int(stop_time)}.toml"
    path.write_text(f'stop_time = {stop_time}\n'
                    f'system = "{REPO / "fmus" / "SystemStructure.ssd"}"\n' + "\n".join(lines))
    return path


def _start(scenario, out, fmu_dir, *extra):
    command = [sys.executable, "-m", "orchestrator.cli", "run", str(scenario), "--out", str(out),
               "--fmu-dir", str(fmu_dir), "--quiet", *extra]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=REPO)


def _files(folder):
    """name -> (inode, mtime_ns, size) of every file in the folder."""
    return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns, p.stat().st_size)
            for p in Path(folder).iterdir() if p.is_file()}


def _full_rows(stop_time=STOP_TIME):
    return int(round(stop_time / RECORD_INTERVAL)) + 1


def _check_after_kill(out, returncode, old):
    """The invariants a folder keeps whenever its run is stopped.

    - ``summary.json``, if present, parses (it is never half-written);
    - it says ``ok`` only with a complete ``results.csv`` (every row up to the stop time)
      and ``sim_time_s`` equal to the stop time: an ok summary is a finished run;
    - if it is a new summary (not the older run's file), no older run's file is beside it:
      no old ``results.csv``, no old PNG;
    - if the old summary is still there, nothing of the old run was touched;
    - ``results.csv``, if present, reads (complete rows only).
    Returns whether the run counts as finished.
    """
    now = _files(out)
    summary = read_summary(out)
    if (out / "summary.json").exists():
        assert summary is not None, (out / "summary.json").read_text()
    if summary is not None and summary["status"] == "ok":
        assert summary["sim_time_s"] == STOP_TIME
        assert count_rows(out / "results.csv") == _full_rows()
    if "summary.json" in now and now["summary.json"] == old.get("summary.json"):
        # killed before the run touched the folder: the older run is whole
        assert {n: v for n, v in now.items() if n in old} == old
    elif "summary.json" in now:
        stale = [name for name, stamp in now.items() if old.get(name) == stamp]
        assert stale == [], f"older run's files beside a new summary: {stale}"
        # a killed run's file says running; its process is gone, so it reads as abandoned
        assert summary["status"] in ("abandoned", "ok")
    if (out / "results.csv").exists() and (out / "results.csv").stat().st_size:
        data = read_results(out / "results.csv", ["time", "plant.x"])
        assert len(data["time"]) == count_rows(out / "results.csv")
    return returncode == 0 and summary is not None and summary["status"] == "ok"


def test_killed_runs_never_pass_for_finished(fmu_dir, tmp_path):
    """SIGKILL at random moments, into fresh folders and into a folder holding an older
    finished run (its summary ok and its PNGs present), at least four times each."""
    scenario = _scenario(tmp_path)
    finished = tmp_path / "finished"
    started = time.monotonic()
    completed = _start(scenario, finished, fmu_dir)
    _, stderr = completed.communicate(timeout=300)
    duration = time.monotonic() - started
    assert completed.returncode == 0, stderr
    assert read_summary(finished)["status"] == "ok"
    assert {p.name for p in finished.glob("*.png")} <= set(PLOT_FILES)
    assert len(list(finished.glob("*.png"))) >= 3

    rng = random.Random(20261201)
    outcomes = []
    # At least eight kills; more (up to 16) while fewer than four landed before the end: a
    # run can be faster than the first, timed one when the machine's load just dropped.
    for attempt in range(16):
        if attempt >= 8 and outcomes.count(False) >= 4:
            break
        existing = attempt % 2 == 1
        out = tmp_path / f"run{attempt}"
        if existing:
            subprocess.run(["cp", "-a", str(finished), str(out)], check=True)
        old = _files(out) if existing else {}
        delay = rng.uniform(0.2, 1.0) * duration
        process = _start(scenario, out, fmu_dir)
        started = time.monotonic()
        try:
            process.wait(timeout=delay)
            # finished before its kill: the machine got faster; aim the next kills earlier
            duration = min(duration, time.monotonic() - started)
        except subprocess.TimeoutExpired:
            process.send_signal(signal.SIGKILL)
            process.wait(timeout=60)
        process.communicate()
        outcomes.append(_check_after_kill(out, process.returncode, old) if out.exists()
                        else False)
    # most kills land before the end: the checks above ran on killed runs, not finished ones
    assert outcomes.count(False) >= 3, outcomes


def _wait_for_rows(out, rows, process, timeout=120):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if (out / "results.csv").exists() and count_rows(out / "results.csv") >= rows:
            return
        assert process.poll() is None, process.communicate()
        time.sleep(0.05)
    raise AssertionError("the run wrote no rows in time")


@pytest.mark.parametrize("signal_number", [signal.SIGINT, signal.SIGTERM],
                         ids=["SIGINT", "SIGTERM"])
def test_a_signal_stops_at_the_next_step_with_one_line(fmu_dir, tmp_path, signal_number):
    """Ctrl-C or SIGTERM: one line on stderr, exit 128 + signal, summary interrupted with the
    time reached, results.csv readable up to that time."""
    scenario = _scenario(tmp_path, stop_time=3000.0)
    out = tmp_path / "run"
    out.mkdir()
    (out / "trajectories.png").write_bytes(b"an older run's plot")
    process = _start(scenario, out, fmu_dir)
    _wait_for_rows(out, 200, process)
    process.send_signal(signal_number)
    stdout, stderr = process.communicate(timeout=120)
    name = signal.Signals(signal_number).name
    assert process.returncode == 128 + signal_number, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and f"interrupted by {name}" in lines[0], stderr
    assert "Traceback" not in stderr and "fmi2" not in stderr
    summary = read_summary(out)
    assert summary["status"] == "interrupted"
    assert summary["error"].startswith(f"interrupted by {name} at t = ")
    assert 0 < summary["sim_time_s"] < 3000.0
    data = read_results(out / "results.csv", ["time", "plant.x", "plant.y"])
    assert len(data["time"]) >= 200
    # every step done was recorded up to the last recording instant before the stop
    assert summary["sim_time_s"] - RECORD_INTERVAL < data["time"][-1] <= summary["sim_time_s"]
    assert not (out / "trajectories.png").exists()
    assert "path_rmse_m" in summary  # the figures of what was computed


@pytest.mark.parametrize("where", ["file", "proc"])
def test_out_that_cannot_hold_results_is_one_line(fmu_dir, tmp_path, where):
    if where == "file":
        out = tmp_path / "a_file"
        out.write_text("not a folder")
    else:
        if not os.path.isdir("/proc/self"):
            pytest.skip("no /proc on this system")
        out = Path("/proc/self/sonotrack-results")
    process = _start(_scenario(tmp_path, 1.0), out, fmu_dir)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 2
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and str(out) in lines[0] and "--out" in lines[0], stderr
    if where == "file":
        assert out.read_text() == "not a folder"


def test_a_failed_run_says_failed_and_keeps_its_rows(fmu_dir, tmp_path):
    """An FMU refusing a step mid-run: summary failed with the reason, rows so far kept."""
    from orchestrator.run.runner import run_scenario
    from orchestrator.scenario import load_scenario
    from components.common.errors import SimulationError
    from orchestrator.run import master as master_module

    scenario = load_scenario(_scenario(tmp_path, 5.0))
    original = master_module.Master.step

    def step(self, k):
        if k == 250:
            raise SimulationError("instance plant returned fmi2Error in doStep at t = 2.5 s")
        return original(self, k)

    master_module.Master.step = step
    try:
        with pytest.raises(SimulationError, match="results so far"):
            run_scenario(scenario, tmp_path / "run", progress=False, fmu_dir=fmu_dir)
    finally:
        master_module.Master.step = original
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["status"] == "failed" and "fmi2Error" in summary["error"]
    assert summary["sim_time_s"] == pytest.approx(2.5)
    assert count_rows(tmp_path / "run" / "results.csv") == 126  # t = 0, 0.02, ..., 2.5


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="process states from /proc")
def test_a_killed_run_reads_back_as_abandoned(fmu_dir, tmp_path):
    """kill -9 of ``sonotrack run`` while it steps: its file still says running, and every
    reader takes it as abandoned, naming the process; its renderer (warming up) ends too."""
    out = tmp_path / "killed"
    # the run stops itself as it opens results.csv: its summary already says running
    process = subprocess.Popen(
        [sys.executable, "-m", "orchestrator.cli", "run", str(_scenario(tmp_path, 5.0)),
         "--out", str(out), "--fmu-dir", str(fmu_dir), "--quiet"], cwd=REPO,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
        env=pause_env("open */killed/results.csv 1"))
    try:
        assert wait_for_stopped(process.pid, process=process) == [process.pid]
        written = json.loads((out / "summary.json").read_text())
        assert written["status"] == "running"
        assert written["process"]["pid"] == process.pid
        assert read_summary(out)["status"] == "running"   # stopped, not dead: still running
        os.kill(process.pid, signal.SIGKILL)
        process.wait(timeout=30)
        elapsed, left = wait_until_gone(process.pid, 3.0)
        assert left == [], f"still running {elapsed:.1f} s after the kill: {left}"
        assert read_to_eof(process.stdout, 1.0) is not None
        assert read_to_eof(process.stderr, 1.0) is not None
    finally:
        end_command(process)
    assert json.loads((out / "summary.json").read_text())["status"] == "running"
    summary = read_summary(out)
    assert summary["status"] == "abandoned"
    assert f"pid {process.pid} on " in summary["error"]
