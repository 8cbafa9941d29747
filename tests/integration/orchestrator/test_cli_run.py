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
