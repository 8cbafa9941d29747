"""Port tables: one per FMU, complete, consistent with the cores, strict on types; a malformed
table is refused naming the file, the entry and the valid choices."""

import math

import pytest

from components import FMU_PACKAGES
from components.acoustics.estimators import ESTIMATORS
from components.acoustics.gcc import WEIGHTINGS
from components.common.errors import ConfigError
from components.common.ranges import ValidRange, load_ranges
from components.control.controller import MODES as CONTROL_MODES
from components.control.inference import METHODS
from components.planner.planner import MODES as PLANNER_MODES

PARTS = sorted(FMU_PACKAGES.values())


@pytest.mark.parametrize("part", PARTS)
def test_every_table_loads_with_finite_bounds_and_a_positive_step(part):
    table = load_ranges(part)
    assert table.step.minimum > 0 and math.isfinite(table.step.maximum)
    for entry in list(table.parameters.values()) + list(table.inputs.values()):
        if entry.type in ("Real", "Integer"):
            assert math.isfinite(entry.minimum) and entry.minimum <= entry.maximum


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


@pytest.fixture
def write_table(tmp_path, monkeypatch):
    """Write ``components/bad/ranges.toml`` under ``tmp_path``; return its path and a loader."""
    import components.common.ranges as ranges

    part = tmp_path / "components" / "bad"
    part.mkdir(parents=True)
    (tmp_path / "components" / "common").mkdir()
    monkeypatch.setattr(ranges, "__file__", str(tmp_path / "components" / "common" / "x.py"))
    path = part / "ranges.toml"

    def write(text, step=STEP):
        path.write_text(step + text)
        return path

    return write


STEP = '[step]\nstep_size = { type = "Real", unit = "s", min = 1e-6, max = 1.0 }\n'
GAIN = {"description": '"a gain"', "type": '"Real"', "unit": '"1"', "start": "0.5",
        "min": "-1.0", "max": "1.0"}
MODE = {"description": '"a mode"', "type": '"String"', "start": '"slow"',
        "choices": '["slow", "calm"]'}


def _entry(name, spec, **change):
    """A ``[parameters]`` line: ``spec`` with keys replaced (value None: key removed)."""
    spec = {k: v for k, v in dict(spec, **change).items() if v is not None}
    return f"[parameters]\n{name} = {{ {', '.join(f'{k} = {v}' for k, v in spec.items())} }}\n"


def test_a_complete_table_loads(write_table):
    from components.common.ranges import load_ranges

    write_table(_entry("gain", GAIN))
    entry = load_ranges("bad").parameters["gain"]
    assert (entry.description, entry.start, entry.unit, entry.minimum) == ("a gain", 0.5, "1", -1.0)


@pytest.mark.parametrize("text, message", [
    (_entry("gain", GAIN, unit=None),
     "parameter gain: a Real needs its unit, one of 1, m, m2, s, Hz, m/s"),
    (_entry("gain", GAIN, unit='"furlong"'),
     "parameter gain: unit 'furlong' is not known, one of 1, m, m2, s, Hz, m/s"),
    (_entry("gain", GAIN, type='"Float"'),
     "parameter gain: type 'Float' is not one of Real, Integer, Boolean, String"),
    (_entry("gain", GAIN, start="5.0"),
     "start value of parameter gain = 5.0 is outside its valid range [-1.0, 1.0]"),
    (_entry("gain", GAIN, start='"0.5"'),
     "start value of parameter gain = '0.5' is a string, expected a number in [-1.0, 1.0]"),
    (_entry("gain", GAIN, start="true"),
     "start value of parameter gain = true is a boolean, expected a number in [-1.0, 1.0]"),
    (_entry("mode", MODE, start='"fast"'),
     "start value of parameter mode = 'fast' is not valid; valid: one of 'slow', 'calm'"),
    (_entry("gain", GAIN, start=None), "parameter gain: needs a start value of type Real"),
    (_entry("gain", GAIN, description=None), "parameter gain: needs a description"),
    (_entry("gain", GAIN, description='" "'), "parameter gain: needs a description"),
    (_entry("gain", GAIN, default="0.5"),
     "parameter gain: unknown keys ['default']; valid keys: description, type, unit, start, "
     "min, max, choices, file_suffix, why"),
    (_entry("mode", MODE, unit='"m"'), "parameter mode: a unit applies to a Real only"),
    (_entry("gain", GAIN, max=None), "parameter gain: needs finite min and max"),
    (_entry("gain", GAIN, min="2.0"), "parameter gain: min 2.0 > max 1.0"),
    ('[inputs]\nu = { description = "u", type = "Integer", start = 1.5, min = 0, max = 3 }\n',
     "start value of input u = 1.5 is a number, expected an integer in [0, 3]"),
], ids=["missing unit", "unknown unit", "unknown type", "start outside its range",
        "start a string", "start a bool", "start not a choice", "missing start",
        "missing description", "blank description", "unknown key", "unit on a String",
        "missing max", "min above max", "integer input with a float start"])
def test_a_malformed_entry_is_refused_naming_file_entry_and_valid_choices(
        write_table, text, message):
    from components.common.ranges import load_ranges

    path = write_table(text)
    with pytest.raises(ConfigError) as caught:
        load_ranges("bad")
    assert f"{path}: {message}" in str(caught.value)


def test_every_problem_of_a_table_is_reported_at_once(write_table):
    from components.common.ranges import load_ranges

    path = write_table(_entry("gain", GAIN, unit=None, start="5.0")
                       + 'mode = { description = "m", type = "Text", start = "a" }\n')
    with pytest.raises(ConfigError) as caught:
        load_ranges("bad")
    lines = str(caught.value).splitlines()
    assert [line.split(": ")[1] for line in lines] == ["parameter gain", "parameter mode"]
    assert all(line.startswith(f"{path}: ") for line in lines)


def test_the_communication_step_range_is_required(write_table):
    from components.common.ranges import load_ranges

    path = write_table(_entry("gain", GAIN), step="")
    with pytest.raises(ConfigError, match=r"\[step\] step_size .* is missing") as caught:
        load_ranges("bad")
    assert str(caught.value).startswith(str(path))


# Each core's own defaults, read from the core (its keyword defaults or its DEFAULTS table).
def _keyword_defaults(function):
    import inspect

    return {name: p.default for name, p in inspect.signature(function).parameters.items()
            if p.default is not inspect.Parameter.empty}


def _core_defaults(part):
    import dataclasses

    if part == "acoustics":
        from components.acoustics.localizer import LocalizerCore
        from components.acoustics.settings import DEFAULTS
        return dict(DEFAULTS, **_keyword_defaults(LocalizerCore))
    if part == "control":
        from components.control.controller import DEFAULTS
        return dict(DEFAULTS)
    if part == "plant":
        from components.plant import PlantParameters, RobotPlantCore
        defaults = _keyword_defaults(RobotPlantCore)
        del defaults["parameters"]
        return dict(dataclasses.asdict(PlantParameters()), **defaults)
    if part == "planner":
        from components.planner.planner import TargetPlanner
        return _keyword_defaults(TargetPlanner)
    from components.source.source import MovingSource
    return _keyword_defaults(MovingSource)


@pytest.mark.parametrize("part", PARTS)
def test_start_values_are_the_cores_defaults(part, repo_root):
    import tomllib

    table = tomllib.loads((repo_root / "components" / part / "ranges.toml").read_text())
    starts = {name: spec["start"] for name, spec in table["parameters"].items()}
    defaults = _core_defaults(part)
    assert starts == defaults
    assert {n for n, v in starts.items() if isinstance(v, bool)} == \
        {n for n, v in defaults.items() if isinstance(v, bool)}


def test_plant_core_bounds_the_work_of_one_step():
    from components.common.errors import InputError
    from components.plant import PlantParameters, RobotPlantCore
    from components.plant.plant import MAX_SUBSTEPS_PER_STEP

    core = RobotPlantCore(PlantParameters(max_substep=1e-9))
    with pytest.raises(InputError, match=f"more than MAX_SUBSTEPS_PER_STEP = "
                                         f"{MAX_SUBSTEPS_PER_STEP}"):
        core.step(1.0, 1.0, 0.02)
    assert core.time_ns == 0   # refused before any work
