"""The slave base: parameters and inputs declared from the port table, refusals, typed values."""

import importlib
import math
import tomllib
from pathlib import Path

import pytest

from components import FMU_PACKAGES
from components.common.errors import ParameterError
from components.common.ranges import RangeTable, ValidRange
from components.common.slave import SonotrackSlave

COMPONENTS = Path(__file__).resolve().parents[4] / "components"
MODELS = sorted(FMU_PACKAGES)
# FMI 2.0 rules for a declared port (Table 18): a parameter is fixed and exact; an input is
# continuous when Real and discrete otherwise, with no initial attribute.
_FMI_RULES = {
    ("parameter", "Real"): ("fixed", "exact"), ("parameter", "Integer"): ("fixed", "exact"),
    ("parameter", "Boolean"): ("fixed", "exact"), ("parameter", "String"): ("fixed", "exact"),
    ("input", "Real"): ("continuous", None), ("input", "Integer"): ("discrete", None),
    ("input", "Boolean"): ("discrete", None),
}


def _slave(model):
    module = importlib.import_module(f"components.{FMU_PACKAGES[model]}.fmu")
    return getattr(module, model)(instance_name="t")


def _table(model):
    """The part's ranges.toml as plain TOML, read here without the code under test."""
    path = COMPONENTS / FMU_PACKAGES[model] / "ranges.toml"
    return tomllib.loads(path.read_text(encoding="utf-8"))


@pytest.mark.parametrize("model", MODELS, ids=MODELS)
def test_declared_parameters_and_inputs_are_the_table_in_its_order(model):
    slave, table = _slave(model), _table(model)
    variables = list(slave.to_xml().find("ModelVariables"))
    for causality, section in (("parameter", "parameters"), ("input", "inputs")):
        declared = [v for v in variables if v.get("causality") == causality]
        entries = table.get(section, {})
        assert [v.get("name") for v in declared] == list(entries)
        for variable in declared:
            name = variable.get("name")
            spec = entries[name]
            (typed,) = list(variable)
            assert typed.tag == spec["type"], name
            assert variable.get("description") == spec["description"], name
            assert (variable.get("variability"), variable.get("initial")) == \
                _FMI_RULES[causality, spec["type"]], name
            assert typed.get("unit") == spec.get("unit"), name
            if spec["type"] == "Real":
                assert float(typed.get("min")) == spec["min"], name
                assert float(typed.get("max")) == spec["max"], name
                # the XML keeps 16 significant digits; the port itself holds the exact value
                assert math.isclose(float(typed.get("start")), spec["start"], rel_tol=1e-15)
                assert getattr(slave, name) == spec["start"], name
                assert type(getattr(slave, name)) is float, name
            elif spec["type"] == "Integer":
                assert (int(typed.get("min")), int(typed.get("max"))) == \
                    (spec["min"], spec["max"]), name
                assert int(typed.get("start")) == spec["start"], name
                assert getattr(slave, name) == spec["start"], name
            elif spec["type"] == "Boolean":
                assert typed.get("start") == ("true" if spec["start"] else "false"), name
                assert getattr(slave, name) is spec["start"], name
            else:
                assert typed.get("start") == spec["start"], name
                assert getattr(slave, name) == spec["start"], name
            if spec["type"] not in ("Real", "Integer"):
                assert typed.get("min") is None and typed.get("max") is None, name


@pytest.mark.parametrize("model", MODELS, ids=MODELS)
def test_parameter_values_are_every_parameter_with_its_type(model):
    slave, table = _slave(model), _table(model)
    values = slave.parameter_values()
    assert values == {name: spec["start"] for name, spec in table["parameters"].items()}
    python_type = {"Real": float, "Integer": int, "Boolean": bool, "String": str}
    assert {name: type(value) for name, value in values.items()} == \
        {name: python_type[spec["type"]] for name, spec in table["parameters"].items()}


def test_parameter_values_convert_an_integer_set_on_a_real():
    from components.control.fmu import WheelController

    slave = WheelController(instance_name="c")
    slave.v_supply = 12
    assert type(slave.parameter_values()["v_supply"]) is float


# The port table of a test slave, built directly (no file).
_GAIN = ValidRange("gain", "Real", "1", -1.0, 1.0, start=0.5, description="a gain")
_MODE = ValidRange("mode", "String", choices=("slow", "calm"), start="calm", description="a mode")
_U = ValidRange("u", "Real", "m/s", -10.0, 10.0, start=0.0, description="an input")
_STEP = ValidRange("step_size", "Real", "s", 1e-6, 1.0)
_TABLE = RangeTable("Probe", {"gain": _GAIN, "mode": _MODE}, {"u": _U}, _STEP,
                    "probe/ranges.toml")


def _probe(declare):
    class Probe(SonotrackSlave):
        valid_ranges = _TABLE

        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            declare(self)

        def do_step(self, current_time, step_size):
            return True

    return Probe(instance_name="p")


@pytest.mark.parametrize("declare, message", [
    (lambda s: s.declare_parameters("gian"),
     "parameter 'gian' has no entry in probe/ranges.toml; parameters of the table: gain, mode"),
    (lambda s: s.declare_inputs("gain"),
     "input 'gain' has no entry in probe/ranges.toml; inputs of the table: u"),
    (lambda s: (s.declare_parameters(), s.declare_parameters("gain")),
     "parameter 'gain' is declared already in probe/ranges.toml"),
], ids=["unknown name", "a parameter as an input", "twice"])
def test_a_port_not_in_the_table_or_declared_twice_is_refused(declare, message):
    with pytest.raises(ValueError) as caught:
        _probe(declare)
    assert str(caught.value).startswith(message)


def test_a_table_entry_left_undeclared_fails_the_model_description():
    slave = _probe(lambda s: s.declare_parameters())
    with pytest.raises(ValueError, match="probe/ranges.toml: u is not a declared input of Probe"):
        slave.to_xml()


def test_named_ports_first_then_the_rest_in_table_order():
    slave = _probe(lambda s: (s.declare_parameters("mode"), s.declare_inputs(),
                              s.declare_parameters()))
    assert [v.name for v in slave.vars.values()] == ["mode", "u", "gain"]
    assert (slave.mode, slave.u, slave.gain) == ("calm", 0.0, 0.5)


def test_the_slave_refuses_every_bad_parameter_at_once():
    from components.plant.fmu import RobotPlant

    slave = RobotPlant(instance_name="plant")
    slave.mass, slave.encoder_ppr = -1.0, 0
    with pytest.raises(ParameterError) as caught:
        slave.exit_initialization_mode()
    assert str(caught.value) == ("plant: parameter mass = -1.0 is outside its valid range "
                                 "[0.1, 1000.0] kg; parameter encoder_ppr = 0 is outside its "
                                 "valid range [1, 1000000]")


def test_a_core_refusal_names_the_instance():
    from components.acoustics.fmu import AcousticLocalizer

    slave = AcousticLocalizer(instance_name="localizer")
    slave.band_high = 500.0   # inside its range, but below band_low
    with pytest.raises(ParameterError, match=r"^localizer: AcousticLocalizer: band_high = 500.0"):
        slave.exit_initialization_mode()


def test_an_input_or_step_outside_its_range_is_a_logged_discard():
    from components.control.fmu import WheelController

    slave = WheelController(instance_name="c")
    logged = []
    slave.log = lambda message, status=None, *a, **k: logged.append(message)
    slave.exit_initialization_mode()
    slave.v_ref = 1e308
    assert slave.do_step(0.0, 0.02) is False
    slave.v_ref = 0.1
    assert slave.do_step(0.0, 0.0) is False
    assert logged == ["c: input v_ref = 1e+308 refused: outside its valid range [-100.0, 100.0] "
                      "m/s", "c: input step_size = 0.0 refused: the communication step must be "
                      "in [1e-06, 1.0] s"]
    assert slave.do_step(0.0, 0.02) is True
