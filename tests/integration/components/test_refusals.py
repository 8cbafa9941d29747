"""Refusals by the built FMUs reach the host as the model's own line, per instance.

The slave logs its refusal before raising, so the line is the model's under any binary
(pythonfmu 0.7.0's turned every exception into fmi2Fatal with "unknown error"; sonotrack's maps
the project's exceptions to fmi2Error and repeats the message behind its own prefix).
"""

import json
import math
import struct
import zipfile
from xml.etree import ElementTree

import pytest
from fmpy.fmi1 import FMICallException

from orchestrator.builder.fmus import FMU_PACKAGES
from orchestrator.fmu.handle import FmuInstance
from orchestrator.scenario import model_ranges

from tests.support.fmu_checks import DRIVES

pytestmark = pytest.mark.integration

NAMES = list(FMU_PACKAGES)


def test_each_instance_keeps_its_own_messages(fmu_paths):
    # fmpy's logger proxy is one per process: before the dispatcher, the plant's line landed
    # in the handle created last (the source).
    plant = FmuInstance(fmu_paths["RobotPlant"], "plant")
    source = FmuInstance(fmu_paths["SoundSource"], "source")
    with pytest.raises(FMICallException):
        plant.instantiate(parameters={"mass": -1.0})
    assert plant.last_error() == ("plant: parameter mass = -1.0 is outside its valid range "
                                  "[0.1, 1000.0] kg")
    assert list(source.messages) == []
    # the interpreter's trailer, if any, is never what the host reports
    assert "Fatal py exception" not in plant.last_error()
    with pytest.raises(FMICallException):
        source.instantiate(parameters={"emit_period": 5e-324})
    assert source.last_error().startswith("source: parameter emit_period = 5e-324 is outside")
    assert all("emit_period" not in text for _, text in plant.messages)
    plant.terminate()
    source.terminate()


@pytest.mark.parametrize("name, parameter, value", [
    ("RobotPlant", "mass", 1e308),
    ("RobotPlant", "max_substep", 1e-9),
    ("RobotPlant", "speed_window", 1e-9),
    ("SoundSource", "amplitude", 1e300),
    ("AcousticLocalizer", "adc_bits", 25),
    ("WheelController", "v_supply", 0.0),
    ("CurvaturePlanner", "v_cruise", math.inf),
], ids=lambda v: str(v))
def test_values_that_used_to_kill_the_step_are_refused_at_initialisation(
        fmu_paths, name, parameter, value):
    instance = FmuInstance(fmu_paths[name], "bad")
    with pytest.raises(FMICallException) as caught:
        instance.instantiate(parameters={parameter: value})
    assert caught.value.status == 3   # fmi2Error: a refusal, not a broken interpreter
    said = instance.last_error()
    assert said.startswith(f"bad: parameter {parameter} = {value!r}")
    assert model_ranges(name).parameters[parameter].text() in said
    instance.terminate()


def test_a_relation_between_parameters_is_refused_with_the_core_s_words(fmu_paths):
    instance = FmuInstance(fmu_paths["AcousticLocalizer"], "localizer")
    with pytest.raises(FMICallException):
        instance.instantiate(parameters={"band_high": 500.0})
    assert "band_high = 500.0 Hz must exceed band_low = 1000.0 Hz" in instance.last_error()
    instance.terminate()


@pytest.mark.parametrize("name, port, value", [
    ("CurvaturePlanner", "wheel_speed_left", 1e308),
    ("WheelController", "v_ref", 1e308),
    ("RobotPlant", "voltage_left", -1e6),
    ("AcousticLocalizer", "robot_x", 1e300),
], ids=lambda v: str(v))
def test_an_input_outside_its_range_is_refused_and_the_instance_lives_on(
        fmu_paths, name, port, value):
    h, drive = DRIVES[name]
    instance = FmuInstance(fmu_paths[name], "in")
    instance.instantiate()
    before = instance.get_state()
    instance.set_values({**drive(0.0), port: value})
    with pytest.raises(FMICallException) as caught:
        instance.do_step(0.0, h)
    assert caught.value.status == 2   # fmi2Discard: the instance is intact
    entry = model_ranges(name).inputs[port]
    assert instance.last_error() == (f"in: input {port} = {value!r} refused: outside its valid "
                                     f"range {entry.text()}")
    instance.set_state(before)   # FMI 2.0: leave stepFailed by restoring a state
    instance.free_state(before)
    instance.set_values(drive(0.0))
    instance.do_step(0.0, h)
    instance.terminate()


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
@pytest.mark.parametrize("step", [0.0, -0.01, math.nan, math.inf, 2.0],
                         ids=["zero", "negative", "nan", "inf", "too_long"])
def test_a_bad_communication_step_is_refused(fmu_paths, name, step):
    h, drive = DRIVES[name]
    instance = FmuInstance(fmu_paths[name], "h")
    instance.instantiate()
    instance.set_values(drive(0.0))
    before = instance.get_state()
    with pytest.raises(FMICallException) as caught:
        instance.do_step(0.0, step)
    if math.isfinite(step) and step > 0:  # a step the model cannot take: fmi2Discard
        assert caught.value.status == 2
        assert instance.last_error().startswith(f"h: input step_size = {step!r} refused: the "
                                                "communication step must be in [1e-06, 1.0] s")
    else:  # not positive and finite: the FMI binary refuses it for every FMU (fmi2Error)
        assert caught.value.status == 3
        assert instance.last_error() == (f"fmi2DoStep: communicationStepSize = {step:.17g} "
                                         "must be positive and finite")
    instance.set_state(before)
    instance.free_state(before)
    instance.do_step(0.0, h)
    instance.terminate()


# sonotrack's binary frames a serialized state with a 32-byte header (magic, version, mode,
# payload length at byte 16, GUID hash); these tests keep a valid header and corrupt the payload
# the slave reads, which the binary cannot judge.
_HEADER = 32


def _with_payload(blob, payload):
    header = bytearray(blob[:_HEADER])
    header[16:24] = struct.pack("<Q", len(payload))
    return bytes(header) + payload


@pytest.mark.parametrize("payload, reason", [
    (b"{}", "restore: FMU state refused: not a state of RobotPlant; missing"),
    (b"[1, 2, 3]", "a serialized state must decode to a dict, not list"),
    (b"\xff\xfe not json", "FMU state refused: the serialized state is not valid"),
    (b"", "FMU state refused: the serialized state is not valid"),
], ids=["empty_table", "list", "garbage", "no_payload"])
def test_a_corrupted_state_is_refused_naming_what_is_wrong(fmu_paths, payload, reason):
    instance = FmuInstance(fmu_paths["RobotPlant"], "restore")
    instance.instantiate()
    state = instance.get_state()
    blob = bytes(instance.serialize_state(state))
    instance.free_state(state)
    with pytest.raises(FMICallException) as caught:
        instance.set_state(instance.deserialize_state(_with_payload(blob, payload)))
    assert caught.value.status == 3   # fmi2Error: never fatal, never a silent OK
    assert reason in instance.last_error()


def test_a_state_with_its_hidden_core_removed_is_refused(fmu_paths):
    instance = FmuInstance(fmu_paths["RobotPlant"], "restore")
    instance.instantiate()
    state = instance.get_state()
    blob = bytes(instance.serialize_state(state))
    instance.free_state(state)
    saved = json.loads(blob[_HEADER:].decode())
    saved["__hidden__"] = {}
    with pytest.raises(FMICallException):
        instance.set_state(instance.deserialize_state(
            _with_payload(blob, json.dumps(saved).encode())))
    assert "hidden state does not hold exactly core" in instance.last_error()


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_model_description_carries_the_valid_ranges(fmu_paths, name):
    table = model_ranges(name)
    with zipfile.ZipFile(fmu_paths[name]) as archive:
        root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    seen = set()
    for variable in root.find("ModelVariables"):
        entry = table.entry(variable.get("name"))
        if variable.get("causality") not in ("parameter", "input"):
            continue
        assert entry is not None, variable.get("name")
        seen.add(entry.name)
        typed = variable[0]
        if entry.type in ("Real", "Integer"):
            number = float if entry.type == "Real" else int
            assert number(typed.get("min")) == entry.minimum
            assert number(typed.get("max")) == entry.maximum
            assert entry.minimum <= number(typed.get("start")) <= entry.maximum
        else:
            assert typed.get("min") is None and typed.get("max") is None
    assert seen == set(table.parameters) | set(table.inputs)
