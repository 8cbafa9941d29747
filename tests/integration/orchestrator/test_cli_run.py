"""The default ``sonotrack run``: plots by default, ``--no-plots``, imports per sub-command."""

import json
import shutil
import subprocess
import sys

import pytest

from orchestrator.builder.fmus import REPO_ROOT

pytestmark = pytest.mark.integration

_MODULES_AFTER = """
import sys
from orchestrator.cli import main
status = main(sys.argv[1:])
heavy = ["matplotlib", "dask", "distributed", "orchestrator.verification",
         "orchestrator.reproduce", "control", "scipy"]
print("LOADED", [m for m in heavy if m in sys.modules])
sys.exit(status)
"""


def _run(tmp_path, *arguments):
    completed = subprocess.run(
        [sys.executable, "-c", _MODULES_AFTER, *arguments], cwd=REPO_ROOT,
        capture_output=True, text=True, timeout=300)
    assert completed.returncode == 0, completed.stderr
    line = [x for x in completed.stdout.splitlines() if x.startswith("LOADED")][-1]
    return eval(line.split(" ", 1)[1])  # a list literal printed by the child


def test_run_plots_by_default_and_not_with_no_plots(fmu_dir, tmp_path):
    scenario = tmp_path / "short.toml"
    text = (REPO_ROOT / "scenarios" / "s_curve.toml").read_text(encoding="utf-8")
    scenario.write_text(text.replace("stop_time = 30.0", "stop_time = 2.0").replace(
        "# system defaults to", 'system = "SystemStructure.ssd"\n#'), encoding="utf-8")
    shutil.copy(REPO_ROOT / "fmus" / "SystemStructure.ssd", tmp_path / "SystemStructure.ssd")
    plotted = _run(tmp_path, "run", str(scenario), "--out", str(tmp_path / "plots"),
                   "--fmu-dir", str(fmu_dir), "--quiet")
    pngs = sorted(p.name for p in (tmp_path / "plots").glob("*.png"))
    assert pngs == ["gains.png", "localizer.png", "trajectories.png", "wheel_speeds.png"]
    for name in pngs:
        assert (tmp_path / "plots" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # drawn by renderer processes: the command's own process never imports matplotlib
    assert "matplotlib" not in plotted
    summary = json.loads((tmp_path / "plots" / "summary.json").read_text())
    assert summary["status"] == "ok" and sorted(summary["plots"]) == pngs
    assert "plots_error" not in summary

    plain = _run(tmp_path, "run", str(scenario), "--out", str(tmp_path / "plain"),
                 "--fmu-dir", str(fmu_dir), "--quiet", "--no-plots")
    assert not list((tmp_path / "plain").glob("*.png"))
    assert json.loads((tmp_path / "plain" / "summary.json").read_text())["status"] == "ok"
    # the run without plots imports none of the heavy modules other commands need
    assert plain == []


def test_a_plot_that_cannot_be_drawn_is_reported_and_recorded(fmu_dir, tmp_path, monkeypatch,
                                                              capsys):
    """A renderer failure: one line, exit status 1, the reason in the summary; the results
    and the figures that could be drawn stay."""
    from orchestrator.run import plot_renderer
    from orchestrator.cli import main

    monkeypatch.setattr(plot_renderer, "FIGURE_SHARES",
                        (("trajectories.png", "missing.png"), ("gains.png", "localizer.png")))
    scenario = tmp_path / "short.toml"
    text = (REPO_ROOT / "scenarios" / "s_curve.toml").read_text(encoding="utf-8")
    scenario.write_text(text.replace("stop_time = 30.0", "stop_time = 1.0").replace(
        "# system defaults to", 'system = "SystemStructure.ssd"\n#'), encoding="utf-8")
    shutil.copy(REPO_ROOT / "fmus" / "SystemStructure.ssd", tmp_path / "SystemStructure.ssd")
    out = tmp_path / "run"
    status = main(["run", str(scenario), "--out", str(out), "--fmu-dir", str(fmu_dir),
                   "--quiet"])
    error = capsys.readouterr().err.strip()
    assert status == 1
    assert error.count("\n") == 0 and error.startswith("sonotrack run: error: plots ")
    assert "trajectories.png, missing.png: ValueError: unknown plot missing.png" in error
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok"
    assert "unknown plot missing.png" in summary["plots_error"]
    assert summary["plots"] == ["gains.png", "localizer.png"]
    assert sorted(p.name for p in out.glob("*.png")) == ["gains.png", "localizer.png"]


def test_a_shipped_scenario_by_name_from_any_folder_with_stop_time_set_and_compare(
        fmu_dir, tmp_path, monkeypatch, capsys):
    """``run straight --stop-time 1 --set planner.v_cruise=0.2`` from an empty folder, then
    ``compare`` against the same run at the scenario's own cruise speed."""
    import numpy as np

    from orchestrator.cli import main
    from orchestrator.run.results import read_results

    monkeypatch.chdir(tmp_path)
    common = ["--stop-time", "1", "--fmu-dir", str(fmu_dir), "--no-plots", "--quiet"]
    assert main(["run", "straight", *common, "--set", "planner.v_cruise=0.2",
                 "--out", "slow"]) == 0
    printed = capsys.readouterr().out
    assert "  final_distance_to_source_m " in printed and "(stop_distance_m 0.5)" in printed
    assert "planner.v_cruise = 0.2" in printed
    assert main(["run", "straight.toml", *common, "--out", "cruise"]) == 0
    capsys.readouterr()
    slow, cruise = (json.loads((tmp_path / n / "summary.json").read_text()) for n in
                    ("slow", "cruise"))
    assert slow["sim_time_s"] == cruise["sim_time_s"] == 1.0 and slow["steps"] == 100
    # the reference the planner ramps to is the cruise speed given, 0.2 against 0.3 m/s
    for name, cruise_speed in (("slow", 0.2), ("cruise", 0.3)):
        data = read_results(tmp_path / name / "results.csv")
        top = max(data["planner.v_ref_left"].max(), data["planner.v_ref_right"].max())
        assert top == pytest.approx(cruise_speed, abs=0.02), name
    assert main(["compare", "slow", "cruise", "--out", "cmp"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].split() == ["slow", "cruise"]
    table = (tmp_path / "cmp" / "comparison.md").read_text(encoding="utf-8")
    assert (f"| final_distance_to_source_m | {slow['final_distance_to_source_m']:.4g} | "
            f"{cruise['final_distance_to_source_m']:.4g} |") in table
    assert np.isclose(float(out.split("final_distance_to_source_m")[1].split()[0]),
                      slow["final_distance_to_source_m"], rtol=1e-3)


def test_info_lists_every_variable_the_model_description_declares(fmu_dir, capsys):
    import xml.etree.ElementTree as ET
    import zipfile

    from orchestrator.cli import main

    path = fmu_dir / "WheelController.fmu"
    assert main(["info", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    with zipfile.ZipFile(path) as archive:
        root = ET.fromstring(archive.read("modelDescription.xml"))
    assert lines[0] == f"model: {root.get('modelName')}"
    table = lines[lines.index("") + 1:]
    assert table[0].split() == ["name", "causality", "type", "unit", "start", "range",
                                "description"]
    variables = root.find("ModelVariables")
    assert len(table) - 1 == len(variables)
    for line, variable in zip(table[1:], variables):
        typed = variable[0]
        words = line.split()
        assert words[:3] == [variable.get("name"), variable.get("causality"), typed.tag]
        if typed.get("unit"):
            assert words[3] == typed.get("unit")
        if typed.get("min") is not None:
            assert f"[{float(typed.get('min')):.6g}, {float(typed.get('max')):.6g}]" in line
        assert line.endswith(" ".join(variable.get("description", "").split()))
