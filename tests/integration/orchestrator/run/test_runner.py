"""The whole system: a short closed-loop run, a killed run, and libcosim as a second master."""

import csv
import math
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from orchestrator.builder.fmus import REPO_ROOT
from orchestrator.run.runner import run_scenario
from orchestrator.scenario import scenario_from_dict
from orchestrator.ssp import read_ssd, write_ssd

pytestmark = pytest.mark.integration

SSD = REPO_ROOT / "fmus" / "SystemStructure.ssd"
INSTANCES = ("source", "localizer", "planner", "controller_left", "controller_right", "plant")


def _scenario(stop_time, step, master="gauss-seidel", steps=None, parameters=None):
    return scenario_from_dict({
        "name": "test", "system": str(SSD), "stop_time": stop_time, "base_step": step,
        "steps": steps or {name: step for name in INSTANCES}, "seed": 1,
        "parameters": parameters or {}, "master": master,
    })


def test_short_closed_loop_run_follows_the_source(fmu_dir, tmp_path):
    scenario = _scenario(8.0, 0.005, steps={"source": 0.01, "localizer": 0.01, "planner": 0.02,
                                            "controller_left": 0.005,
                                            "controller_right": 0.005, "plant": 0.005},
                         parameters={"source.path": "straight"})
    result = run_scenario(scenario, tmp_path / "run", progress=False, fmu_dir=fmu_dir)
    summary = result.summary
    assert summary["status"] == "ok"
    assert summary["steps"] == 1600
    assert summary["sim_time_s"] == pytest.approx(8.0)
    with open(result.results_csv) as f:
        rows = list(csv.DictReader(f))
    y = np.array([float(r["plant.y"]) for r in rows])
    source_y = np.array([float(r["source.y"]) for r in rows])
    # the source drives away along +y; the robot must have moved after it, not away from it
    assert y[-1] > 0.5
    assert abs(source_y[-1] - y[-1]) < abs(source_y[-1] - y[0])
    for name in ("trajectories.png", "wheel_speeds.png"):
        assert (result.out_dir / name).stat().st_size > 10_000


def test_every_path_of_the_result_is_absolute_for_a_relative_folder(fmu_dir, tmp_path,
                                                                    monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = run_scenario(_scenario(0.2, 0.01), "relative/run", progress=False,
                          fmu_dir=fmu_dir)
    paths = [result.out_dir, result.results_csv, result.summary_json, *result.plots]
    assert len(result.plots) == 4
    assert all(p.is_absolute() and p.exists() for p in paths)
    assert result.out_dir == tmp_path / "relative" / "run"
    # the summary names the controller law the plots are titled with (the FMU's default)
    assert result.summary["controller"] == "fgs_pd"


def test_a_killed_run_leaves_a_readable_csv(fmu_dir, tmp_path):
    scenario_file = tmp_path / "long.toml"
    scenario_file.write_text(
        f'name = "long"\nsystem = "{SSD}"\nstop_time = 60.0\nbase_step = 0.005\nseed = 1\n'
        '[steps]\nsource = 0.01\nlocalizer = 0.01\nplanner = 0.02\n'
        'controller_left = 0.005\ncontroller_right = 0.005\nplant = 0.005\n')
    out = tmp_path / "out"
    process = subprocess.Popen(
        [sys.executable, "-m", "orchestrator.cli", "run", str(scenario_file), "--out", str(out),
         "--fmu-dir", str(fmu_dir), "--quiet"], cwd=REPO_ROOT, start_new_session=True)
    csv_path = out / "results.csv"
    deadline = time.monotonic() + 240
    rows = 0
    while time.monotonic() < deadline and rows < 600:
        time.sleep(0.5)
        if csv_path.exists():
            with open(csv_path) as f:
                rows = sum(1 for _ in f)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    assert rows >= 600, "the run did not write rows while running"
    with open(csv_path) as f:
        reader = csv.reader(f)
        header = next(reader)
        complete = [row for row in reader if len(row) == len(header)]
    times = [float(row[0]) for row in complete]
    # flushed at least every simulated second: more than 2 s of rows survive, in order
    assert times[-1] >= 2.0
    assert all(b > a for a, b in zip(times, times[1:]))


def test_libcosim_and_our_jacobi_master_agree(fmu_dir, tmp_path):
    from orchestrator.hosts.libcosim import run_libcosim_ssd

    step, stop = 0.01, 10.0
    ssd = fmu_dir / "SingleRate.ssd"
    write_ssd(ssd, read_ssd(SSD).without_step_hints())
    _, rows = run_libcosim_ssd(ssd, step, stop, ["plant.x", "plant.y"])
    theirs = np.array(rows)
    # libcosim's two ways of recording (the benchmark times both) give the same rows
    _, series = run_libcosim_ssd(ssd, step, stop, ["plant.x", "plant.y"],
                                 observer="time_series")
    assert np.array_equal(np.array(series), theirs)

    scenario = _scenario(stop, step, master="jacobi")
    result = run_scenario(scenario, tmp_path / "ours", progress=False, fmu_dir=fmu_dir,
                          plots=False, record_interval=step)
    with open(result.results_csv) as f:
        rows = list(csv.DictReader(f))[1:]
    ours = np.array([[float(r["plant.x"]), float(r["plant.y"])] for r in rows])
    assert ours.shape == theirs.shape
    travelled = np.hypot(*(ours[-1] - ours[0]))
    assert travelled > 0.3, "the robot must move for the comparison to mean anything"
    difference = float(np.max(np.hypot(*(ours - theirs).T)))
    assert difference <= 1e-6


def test_default_s_curve_scenario_meets_its_targets(fmu_dir, tmp_path):
    from orchestrator.scenario import load_scenario

    scenario = load_scenario(REPO_ROOT / "scenarios" / "s_curve.toml")
    result = run_scenario(scenario, tmp_path / "s_curve", progress=False, fmu_dir=fmu_dir,
                          plots=False)
    summary = result.summary
    stop_distance = summary["stop_distance_m"]
    # the robot follows the source to the end without touching it ...
    assert summary["min_distance_to_source_m"] >= stop_distance / 2
    # ... and stops within 0.3 m of stop_distance from it
    assert abs(summary["final_distance_to_source_m"] - stop_distance) <= 0.3


def test_cli_reports_a_bad_scenario_field_in_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\nstop_time = 5.0\nmaster = "rk4"\n')
    completed = subprocess.run([sys.executable, "-m", "orchestrator.cli", "run", str(bad)],
                               cwd=REPO_ROOT, capture_output=True, text=True, timeout=120)
    assert completed.returncode != 0
    lines = [line for line in completed.stderr.splitlines() if line.strip()]
    assert "Traceback" not in completed.stderr
    assert any("bad.toml" in line and "master" in line and "rk4" in line and "jacobi" in line
               for line in lines)
