"""`sonotrack run` from any working folder reads the waypoint CSV its scenario or .ssd names."""

import subprocess
import sys
from pathlib import Path

import pytest

from orchestrator.run.results import read_results

pytestmark = pytest.mark.integration

REPO = Path(__file__).resolve().parents[4]
WAYPOINTS = [(0.3, 2.0), (0.8, 3.0), (1.2, 4.0)]


def _write_waypoints(path):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("x,y\n" + "".join(f"{x},{y}\n" for x, y in WAYPOINTS))


def _run(args, cwd):
    return subprocess.run([sys.executable, "-m", "orchestrator.cli", "run", *args, "--quiet"],
                          cwd=cwd, capture_output=True, text=True, timeout=600,
                          env={**__import__("os").environ, "PYTHONPATH": str(REPO)})


def _first_source_position(out):
    data = read_results(out / "results.csv", ["source.x", "source.y"])
    return data["source.x"][0], data["source.y"][0]


def test_scenario_csv_from_another_working_folder(fmu_dir, tmp_path):
    scenario = tmp_path / "study" / "scenario.toml"
    _write_waypoints(tmp_path / "study" / "paths" / "w.csv")
    scenario.write_text(f'stop_time = 1.0\nsystem = "{REPO / "fmus" / "SystemStructure.ssd"}"\n'
                        '[parameters]\nsource.path = "paths/w.csv"\n')
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    completed = _run(["../study/scenario.toml", "--out", "run", "--fmu-dir", str(fmu_dir)],
                     elsewhere)
    assert completed.returncode == 0, completed.stderr
    # the source starts at the CSV's first waypoint
    assert _first_source_position(elsewhere / "run") == WAYPOINTS[0]


def test_csv_bound_in_the_ssd_resolves_from_the_ssd(fmu_dir, tmp_path):
    system = tmp_path / "system"
    system.mkdir()
    text = (REPO / "fmus" / "SystemStructure.ssd").read_text()
    assert text.count('<ssv:String value="s_curve"/>') == 1
    (system / "SystemStructure.ssd").write_text(
        text.replace('<ssv:String value="s_curve"/>', '<ssv:String value="paths/w.csv"/>'))
    _write_waypoints(system / "paths" / "w.csv")
    scenario = tmp_path / "scenarios" / "scenario.toml"
    scenario.parent.mkdir()
    scenario.write_text('stop_time = 1.0\nsystem = "../system/SystemStructure.ssd"\n')
    completed = _run([str(scenario), "--out", str(tmp_path / "run"), "--fmu-dir", str(fmu_dir)],
                     tmp_path / "scenarios")
    assert completed.returncode == 0, completed.stderr
    assert _first_source_position(tmp_path / "run") == WAYPOINTS[0]


def test_csv_outside_the_scenario_folder_is_one_refusal(fmu_dir, tmp_path):
    _write_waypoints(tmp_path / "w.csv")
    scenario = tmp_path / "study" / "scenario.toml"
    scenario.parent.mkdir()
    scenario.write_text(f'stop_time = 1.0\nsystem = "{REPO / "fmus" / "SystemStructure.ssd"}"\n'
                        '[parameters]\nsource.path = "../w.csv"\n')
    refused = _run([str(scenario), "--out", str(tmp_path / "run"), "--fmu-dir", str(fmu_dir)],
                   tmp_path)
    assert refused.returncode == 2
    assert "parameters.source.path" in refused.stderr and "--allow-outside" in refused.stderr
    assert "Traceback" not in refused.stderr
    allowed = _run([str(scenario), "--out", str(tmp_path / "run"), "--fmu-dir", str(fmu_dir),
                    "--allow-outside"], tmp_path)
    assert allowed.returncode == 0, allowed.stderr
    assert _first_source_position(tmp_path / "run") == WAYPOINTS[0]
