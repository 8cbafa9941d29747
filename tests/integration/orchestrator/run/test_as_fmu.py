"""Building the whole-system FMU of a scenario needs FMUs of the same code as components/."""

import shutil

import pytest

from components.common.errors import BuildError
from orchestrator.builder.fmus import FMU_PACKAGES, REPO_ROOT, build_fmu
from orchestrator.run.as_fmu import build_scenario_fmu

pytestmark = pytest.mark.integration


def test_fmus_of_other_code_are_refused_naming_them(fmu_dir, tmp_path):
    # a WheelController built from a checkout that differs by one comment line
    other = tmp_path / "components"
    shutil.copytree(REPO_ROOT / "components", other,
                    ignore=shutil.ignore_patterns("__pycache__"))
    ranges = other / "control" / "ranges.toml"
    ranges.write_text(ranges.read_text() + "# another checkout\n")
    folder = tmp_path / "fmus"
    folder.mkdir()
    for name in FMU_PACKAGES:
        if name != "WheelController":
            shutil.copy2(fmu_dir / f"{name}.fmu", folder)
    build_fmu("WheelController", folder, components_dir=other)
    with pytest.raises(BuildError) as caught:
        build_scenario_fmu(REPO_ROOT / "scenarios" / "s_curve.toml", tmp_path / "out",
                           fmu_dir=folder)
    message = str(caught.value)
    assert "WheelController.fmu" in message and "RobotPlant.fmu" not in message
    assert not (tmp_path / "out" / "TrackingSystem.fmu").exists()
