"""Valid-range tables: one per FMU, complete, consistent with the cores, strict on types."""

import math

import pytest

from components.acoustics.estimators import ESTIMATORS
from components.acoustics.gcc import WEIGHTINGS
from components.common.errors import ConfigError, ParameterError
from components.common.ranges import ValidRange, load_ranges
from components.control.controller import MODES as CONTROL_MODES
from components.control.inference import METHODS
from components.planner.planner import MODES as PLANNER_MODES
from orchestrator.builder.fmus import FMU_PACKAGES

PARTS = sorted(FMU_PACKAGES.values())


@pytest.mark.parametrize("part", PARTS)
def test_every_table_loads_with_finite_bounds_and_a_positive_step(part):
    table = load_ranges(part)
    assert table.step.minimum > 0 and math.isfinite(table.step.maximum)
    for entry in list(table.parameters.values()) + list(table.inputs.values()):
        if entry.type in ("Real", "Integer"):
            assert math.isfinite(entry.minimum) and entry.minimum <= entry.maximum


@pytest.mark.parametrize("model, part", sorted(FMU_PACKAGES.items()))
def test_every_declared_parameter_and_input_has_exactly_one_range(model, part):
    import importlib

    module = importlib.import_module(f"components.{part}.fmu")
    slave = getattr(module, model)(instance_name="t")
    slave.to_xml()   # raises if a table entry is not a declared port
    declared = {v.name for v in slave.vars.values()
                if v.causality.name in ("parameter", "input")}
    table = load_ranges(part)
    assert declared == set(table.parameters) | set(table.inputs)


def test_string_choices_are_the_cores_registries():
    # a mode added to a core without its table (or the reverse) fails here
    assert set(load_ranges("acoustics").parameters["method"].choices) == set(ESTIMATORS)
    assert set(load_ranges("acoustics").parameters["weighting"].choices) == set(WEIGHTINGS)
    assert set(load_ranges("planner").parameters["mode"].choices) == set(PLANNER_MODES)
    assert set(load_ranges("control").parameters["mode"].choices) == set(CONTROL_MODES)
    assert set(load_ranges("control").parameters["fuzzy_method"].choices) == set(METHODS)


REAL = ValidRange("v_cruise", "Real", "m/s", 0.001, 10.0)
INTEGER = ValidRange("adc_bits", "Integer", None, 2, 24)
BOOLEAN = ValidRange("mute_at_end", "Boolean")
PATH = ValidRange("path", "String", choices=("straight", "s_curve"), file_suffix=".csv")


@pytest.mark.parametrize("entry, value, message", [
    (REAL, True, "v_cruise = true is a boolean, expected a number in [0.001, 10.0] m/s"),
    (REAL, "0.3", "v_cruise = '0.3' is a string, expected a number"),
    (REAL, math.nan, "v_cruise = nan (not finite) is outside its valid range [0.001, 10.0] m/s"),
    (REAL, 1e308, "v_cruise = 1e+308 is outside its valid range [0.001, 10.0] m/s"),
    (REAL, 0.0, "v_cruise = 0.0 is outside its valid range"),
    (INTEGER, 4294967306, "adc_bits = 4294967306 is outside its valid range [2, 24]"),
    (INTEGER, 10.7, "adc_bits = 10.7 is a number, expected an integer in [2, 24]"),
    (INTEGER, 10.0, "adc_bits = 10.0 is a number, expected an integer in [2, 24]"),
    (INTEGER, False, "adc_bits = false is a boolean, expected an integer"),
    (BOOLEAN, "false", "mute_at_end = 'false' is a string, expected a boolean, true or false"),
    (BOOLEAN, 0, "mute_at_end = 0 is an integer, expected a boolean"),
    (PATH, "zigzag", "path = 'zigzag' is not valid; valid: one of 'straight', 's_curve' or a "
                     "file name ending in .csv"),
    (PATH, ".csv", "path = '.csv' is not valid"),
], ids=lambda v: repr(v)[:30])
def test_no_coercion_and_no_clamping(entry, value, message):
    assert entry.problem(value).startswith(message)


@pytest.mark.parametrize("entry, value", [
    (REAL, 0.001), (REAL, 10), (REAL, 10.0), (INTEGER, 2), (INTEGER, 24), (BOOLEAN, False),
    (PATH, "s_curve"), (PATH, "waypoints/lap.CSV"),
], ids=repr)
def test_valid_values_including_the_bounds_pass(entry, value):
    assert entry.problem(value) is None


def test_a_malformed_table_is_refused(tmp_path, monkeypatch):
    import components.common.ranges as ranges

    part = tmp_path / "components" / "bad"
    part.mkdir(parents=True)
    (tmp_path / "components" / "common").mkdir()
    monkeypatch.setattr(ranges, "__file__", str(tmp_path / "components" / "common" / "x.py"))
    (part / "ranges.toml").write_text('[step]\nstep_size = { type = "Real", unit = "s", '
                                      'min = 1e-6, max = 1.0 }\n[parameters]\n'
                                      'gain = { type = "Real", unit = "1", min = 1.0 }\n')
    with pytest.raises(ConfigError, match="gain needs finite min and max"):
        ranges.load_ranges("bad")
    (part / "ranges.toml").write_text('[parameters]\n')
    with pytest.raises(ConfigError, match=r"\[step\] step_size .* is missing"):
        ranges.load_ranges("bad")


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


def test_plant_core_bounds_the_work_of_one_step():
    from components.common.errors import InputError
    from components.plant import PlantParameters, RobotPlantCore
    from components.plant.plant import MAX_SUBSTEPS_PER_STEP

    core = RobotPlantCore(PlantParameters(max_substep=1e-9))
    with pytest.raises(InputError, match=f"more than MAX_SUBSTEPS_PER_STEP = "
                                         f"{MAX_SUBSTEPS_PER_STEP}"):
        core.step(1.0, 1.0, 0.02)
    assert core.time_ns == 0   # refused before any work
