"""The build pipeline on a minimal slave: what pythonfmu 0.7.0 gets wrong is fixed in ours."""

import shutil
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest

from components.common.errors import BuildError
from orchestrator.builder.fmus import REPO_ROOT, build_fmu
from orchestrator.fmu.handle import FmuInstance
from orchestrator.builder.validation import validate_fmu

from tests.support.fmu_checks import run_isolated, run_libcosim, same_bits, state_round_trip, step_and_record

pytestmark = pytest.mark.integration


@pytest.fixture(scope="module")
def dummy_fmu(tmp_path_factory):
    components = tmp_path_factory.mktemp("components")
    shutil.copytree(REPO_ROOT / "components" / "common", components / "common")
    shutil.copytree(Path(__file__).resolve().parents[3] / "support" / "fixtures" / "pipeline" / "dummy",
                    components / "dummy")
    return build_fmu("Dummy", tmp_path_factory.mktemp("out"), components_dir=components,
                     packages={"Dummy": "dummy"})


def _model_description(path):
    with zipfile.ZipFile(path) as archive:
        return ElementTree.fromstring(archive.read("modelDescription.xml"))


def test_model_description_is_fixed(dummy_fmu):
    root = _model_description(dummy_fmu)
    variables = {v.get("name"): v for v in root.find("ModelVariables")}
    assert variables["u"].find("Real").get("unit") == "m/s"
    assert variables["y"].find("Real").get("unit") == "m"
    assert variables["n"].get("variability") == "discrete"
    assert variables["on"].get("variability") == "discrete"
    units = {u.get("name"): u.find("BaseUnit").attrib for u in root.find("UnitDefinitions")}
    assert units["m/s"] == {"m": "1", "s": "-1"}
    assert list(root).index(root.find("UnitDefinitions")) == \
        list(root).index(root.find("CoSimulation")) + 1
    initial = [u.get("index") for u in root.find("ModelStructure/InitialUnknowns")]
    assert initial == ["3", "4", "5"]
    outputs = {u.get("index"): u.get("dependencies") for u in root.find("ModelStructure/Outputs")}
    assert outputs == {"3": "", "4": "", "5": "2"}
    cosim = root.find("CoSimulation")
    assert cosim.get("canGetAndSetFMUstate") == "true"
    assert cosim.get("canSerializeFMUstate") == "true"


def test_both_checkers_and_a_run_find_no_problem(dummy_fmu):
    assert validate_fmu(dummy_fmu).problems == []


def test_runs_without_the_repository(dummy_fmu):
    result = run_isolated(dummy_fmu, 1.0)
    # y = gain * u * t = 2 * 1 * 1 after 100 steps of the default experiment's 0.01 s
    assert result["last"]["y"] == pytest.approx(2.0, rel=1e-12)
    assert result["last"]["n"] == 100


def test_state_round_trip_includes_hidden_state(dummy_fmu):
    def drive(t):
        return {"u": 1.0 + t}

    first, second = state_round_trip(dummy_fmu, drive, 0.01, warmup=10, steps=50)
    assert all(same_bits(a, b) for a, b in zip(first, second))
    # the step counter is core state only: restored, it continues from the warm-up count
    assert first[0][1] == 11 and second[0][1] == 11


def test_nan_input_is_refused_and_host_survives(dummy_fmu):
    from fmpy.fmi1 import FMICallException

    instance = FmuInstance(dummy_fmu, "nan")
    instance.instantiate()
    instance.set_values({"u": float("nan")})
    with pytest.raises(FMICallException) as caught:
        instance.do_step(0.0, 0.01)
    assert caught.value.status in (2, 3)
    assert "u = nan" in instance.last_error()
    instance.terminate()


def test_libcosim_matches_fmpy(dummy_fmu):
    def drive(t):
        return {"u": 0.5 + t}

    instance = FmuInstance(dummy_fmu, "fmpy")
    instance.instantiate(parameters={"gain": 3.0})
    groups = {"Real": ["y"], "Integer": ["n"], "Boolean": ["on"]}
    ours = step_and_record(instance, groups, drive, 0.0, 0.01, 20)
    instance.terminate()
    theirs = run_libcosim(dummy_fmu, drive, 0.01, 20, parameters={"gain": 3.0})
    assert [r[0] for r in theirs] == pytest.approx([r[0] for r in ours], abs=1e-12)
    assert [r[1] for r in theirs] == [r[1] for r in ours]


def test_several_instances_of_one_fmu_in_one_process(dummy_fmu):
    # pythonfmu 0.7.0 breaks on the second instance unless the slave class is defined in the
    # entry module; the controller FMU is used twice, and tests instantiate FMUs many times.
    instances = [FmuInstance(dummy_fmu, f"copy{k}") for k in range(3)]
    for k, instance in enumerate(instances):
        instance.instantiate(parameters={"gain": float(k + 1)})
    for instance in instances:
        instance.set_values({"u": 1.0})
        instance.do_step(0.0, 0.5)
    values = [instance.get_values(["y"])["y"] for instance in instances]
    for instance in instances:
        instance.terminate()
    assert values == [0.5, 1.0, 1.5]
    again = FmuInstance(dummy_fmu, "after")
    again.instantiate()
    again.do_step(0.0, 0.25)
    assert again.get_values(["y"])["y"] == 0.5
    again.terminate()



def _dummy_components(folder):
    shutil.copytree(REPO_ROOT / "components" / "common", folder / "common")
    shutil.copytree(Path(__file__).resolve().parents[3] / "support" / "fixtures" / "pipeline" /
                    "dummy", folder / "dummy")
    return folder


def _build_dummy(components, out):
    return build_fmu("Dummy", out, components_dir=components, packages={"Dummy": "dummy"})


def test_a_build_from_the_same_code_is_the_same_fmu_byte_for_byte(tmp_path, monkeypatch):
    # pythonfmu writes a time-based GUID and the build time: every rebuild changed every
    # stored run's key (the FMUs' SHA-256), and a study computed all its runs again
    import uuid

    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    components = _dummy_components(tmp_path / "components")
    first = _build_dummy(components, tmp_path / "a")
    second = _build_dummy(components, tmp_path / "b")
    assert first.read_bytes() == second.read_bytes()
    root = _model_description(first)
    assert uuid.UUID(root.get("guid")).version == 5
    assert root.get("generationDateAndTime") is None
    with zipfile.ZipFile(first) as archive:
        assert {info.date_time for info in archive.infolist()} == {(1980, 1, 1, 0, 0, 0)}
    # other code, another GUID (and still a valid FMU)
    slave = components / "dummy" / "fmu.py"
    slave.write_text(slave.read_text() + "\n# changed\n")
    changed = _build_dummy(components, tmp_path / "c")
    assert _model_description(changed).get("guid") != root.get("guid")
    assert validate_fmu(changed).problems == []
    # the reproducible-builds convention dates it when asked, and a bad value is named
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1796601600")
    dated = _model_description(_build_dummy(components, tmp_path / "d"))
    assert dated.get("generationDateAndTime") == "2026-12-07T00:00:00Z"
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "yesterday")
    with pytest.raises(BuildError, match="SOURCE_DATE_EPOCH = 'yesterday'"):
        _build_dummy(components, tmp_path / "e")
