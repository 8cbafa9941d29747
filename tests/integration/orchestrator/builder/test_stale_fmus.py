"""FMUs built from other code than components/ holds now are named before they run."""

import shutil

import pytest

from orchestrator.builder.fmus import COMPONENTS
from orchestrator.builder.system_fmu import stale_fmus, stale_fmus_warning
from orchestrator.cli import main

pytestmark = pytest.mark.integration


@pytest.fixture()
def changed_components(tmp_path):
    """A copy of components/ with one line of the controller changed (a later checkout)."""
    copy = tmp_path / "components"
    shutil.copytree(COMPONENTS, copy, ignore=shutil.ignore_patterns("__pycache__"))
    law = copy / "control" / "default_form.py"
    law.write_text(law.read_text() + "\n# a change after the FMUs were built\n")
    return copy


def test_fmus_of_this_checkout_are_current(fmu_dir):
    assert stale_fmus(fmu_dir) == []
    assert stale_fmus_warning("run", fmu_dir) is None


def test_an_fmu_of_other_code_is_named_and_only_that_one(fmu_dir, changed_components):
    stale = stale_fmus(fmu_dir, changed_components)
    assert len(stale) == 1 and "WheelController.fmu" in stale[0]
    warning = stale_fmus_warning("reproduce", fmu_dir, changed_components)
    assert warning.startswith("sonotrack reproduce: warning: ")
    assert "WheelController.fmu" in warning and "make fmus" in warning
    assert "RobotPlant" not in warning


def test_an_fmu_of_another_tool_is_not_judged(fmu_dir, tmp_path):
    folder = tmp_path / "mixed"
    folder.mkdir()
    shutil.copy(fmu_dir / "RobotPlant.fmu", folder)
    (folder / "WheelController.fmu").write_bytes(b"not a sonotrack FMU")
    assert stale_fmus(folder) == []


def test_run_warns_on_stderr_and_still_runs(fmu_dir, tmp_path, capsys, monkeypatch):
    import orchestrator.builder.system_fmu as system_fmu

    folder = tmp_path / "fmus"
    shutil.copytree(fmu_dir, folder)
    other = tmp_path / "other"
    shutil.copytree(COMPONENTS, other, ignore=shutil.ignore_patterns("__pycache__"))
    (other / "plant" / "motor.py").write_text((other / "plant" / "motor.py").read_text() + "\n#\n")
    monkeypatch.setattr(system_fmu.stale_fmus_warning, "__defaults__", (other,))
    status = main(["run", "--fmu-dir", str(folder), "--stop-time", "0.2", "--no-plots",
                   "--quiet", "--out", str(tmp_path / "run")])
    err = capsys.readouterr().err
    assert status == 0
    assert err.count("warning") == 1 and "RobotPlant.fmu" in err and "make fmus" in err
