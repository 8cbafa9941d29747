"""ModelStructure tells the truth: declared direct dependencies equal the measured ones."""

import re
import zipfile

import fmpy
import pytest

from orchestrator.builder.fmus import FMU_PACKAGES

from tests.support.feedthrough import declared_dependencies, feedthrough_mismatches, measured_dependencies
from tests.support.fmu_checks import DRIVES

pytestmark = pytest.mark.integration

NAMES = list(FMU_PACKAGES)


def _drive(name):
    step, drive = DRIVES[name]
    return step, drive


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_declared_dependencies_are_the_measured_ones(fmu_paths, name):
    path = fmu_paths[name]
    step, drive = _drive(name)
    declared = declared_dependencies(fmpy.read_model_description(str(path)))
    measured = measured_dependencies(path, drive, step)
    assert feedthrough_mismatches(declared, measured) == []


def _with_false_feedthrough(source, target):
    """Copy ``source`` declaring that ``voltage`` depends directly on ``v_ref`` (index 1)."""
    with zipfile.ZipFile(source) as old, zipfile.ZipFile(target, "w") as new:
        for item in old.infolist():
            data = old.read(item)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                index = _index_of(text, "voltage")
                outputs = text[text.index("<Outputs>"):text.index("</Outputs>")]
                patched = re.sub(rf'<Unknown index="{index}"[^>]*/>',
                                 f'<Unknown index="{index}" dependencies="{_index_of(text, "v_ref")}"'
                                 ' dependenciesKind="dependent"/>', outputs)
                assert patched != outputs
                data = text.replace(outputs, patched).encode()
            new.writestr(item, data)
    return target


def _index_of(xml_text, name):
    names = re.findall(r'<ScalarVariable\s+name="([^"]+)"', xml_text)
    return names.index(name) + 1


def test_a_false_feedthrough_declaration_is_caught(fmu_paths, tmp_path):
    """The check fails on a WheelController that claims voltage feeds through from v_ref."""
    path = _with_false_feedthrough(fmu_paths["WheelController"], tmp_path / "WheelController.fmu")
    step, drive = _drive("WheelController")
    declared = declared_dependencies(fmpy.read_model_description(str(path)))
    assert declared["outputs"]["voltage"] == {"v_ref"}
    measured = measured_dependencies(path, drive, step)
    assert feedthrough_mismatches(declared, measured) == [
        "Outputs voltage: declared ['v_ref'], measured []"]
