"""Scenario files: read, validated against the schema and the system, every problem at once."""

from pathlib import Path

import pytest

from components.common.errors import ConfigError
from orchestrator.scenario import SCHEMA, Scenario, load_scenario, scenario_from_dict

REPO = Path(__file__).resolve().parents[4]
SCENARIOS = REPO / "scenarios"
SSD = REPO / "fmus" / "SystemStructure.ssd"


def write(tmp_path, text, name="case.toml"):
    """A scenario file in tmp_path/scenarios, with the repo's .ssd at tmp_path/fmus."""
    (tmp_path / "fmus").mkdir(exist_ok=True)
    (tmp_path / "fmus" / "SystemStructure.ssd").write_bytes(SSD.read_bytes())
    (tmp_path / "scenarios").mkdir(exist_ok=True)
    path = tmp_path / "scenarios" / name
    path.write_text(text, encoding="utf-8")
    return path


def test_minimal_file_gets_the_documented_defaults(tmp_path):
    path = write(tmp_path, "stop_time = 2\n")
    scenario = load_scenario(path)
    assert scenario == Scenario(
        name="case", description="", system=(tmp_path / "fmus" / "SystemStructure.ssd").resolve(),
        stop_time=2.0, base_step=0.01, steps={}, seed=1, parameters={}, outputs=[],
        master="gauss-seidel")
    assert isinstance(scenario.stop_time, float)
    assert scenario.step("plant") == 0.01
    assert scenario.step_count == 200


def test_dotted_and_table_parameters_flatten_to_instance_dot_parameter(tmp_path):
    path = write(tmp_path, 'stop_time = 1.0\n'
                           '[parameters]\n'
                           'source.path = "static"\n'
                           '"planner.v_cruise" = 0.3\n'
                           '[parameters.localizer]\n'
                           'seed = 4\n'
                           'snr_db = 20\n')
    assert load_scenario(path).parameters == {"source.path": "static", "planner.v_cruise": 0.3,
                                              "localizer.seed": 4, "localizer.snr_db": 20}


def test_relative_system_resolves_from_the_scenario_directory(tmp_path):
    path = write(tmp_path, 'stop_time = 1.0\nsystem = "../fmus/SystemStructure.ssd"\n')
    assert load_scenario(path).system == (tmp_path / "fmus" / "SystemStructure.ssd").resolve()


def test_every_problem_is_reported_at_once(tmp_path):
    path = write(tmp_path, '\n'.join([
        'stoptime = 10.0',
        'base_step = 0.005',
        'seed = 1.5',
        'master = "gauss_seidel"',
        'outputs = ["plant.x", "plant"]',
        '[steps]',
        'planner = 0.012',
        'plant = 0.005',
        '[parameters]',
        'source.path = ["s_curve"]',
    ]) + '\n')
    with pytest.raises(ConfigError) as caught:
        load_scenario(path)
    fields = ", ".join(sorted(SCHEMA))
    assert str(caught.value).splitlines() == [
        f"{path}: 7 problems in the scenario:",
        f"  {path}: unknown field 'stoptime' (did you mean 'stop_time'?); valid fields: {fields}",
        f"  {path}: field 'stop_time' is required (end time in s, > 0)",
        f"  {path}: field 'seed': 1.5 is a number, expected an integer",
        f"  {path}: field 'parameters.source.path': ['s_curve'] is a list, expected a number, "
        f"integer, boolean or string",
        f"  {path}: field 'outputs[1]': 'plant' is not an 'instance.port' string",
        f"  {path}: field 'master': 'gauss_seidel' is not one of 'gauss-seidel', 'jacobi'",
        f"  {path}: field 'steps.planner': 0.012 is not an integer multiple of base_step 0.005 "
        f"(ratio 2.4)",
    ]


@pytest.mark.parametrize("field, value, message", [
    ("master", "euler", "'euler' is not one of 'gauss-seidel', 'jacobi'"),
    ("master", 3, "3 is an integer, expected a string"),
    ("stop_time", "10", "'10' is a string, expected a number"),
    ("stop_time", 0.0, "0.0 must be > 0"),
    ("stop_time", float("inf"), "inf is not finite, expected a number > 0"),
    ("base_step", True, "true is a boolean, expected a number"),
    ("seed", True, "true is a boolean, expected an integer"),
    ("seed", -1, "-1 is outside 0..2147483647"),
    ("seed", 2**31, "2147483648 is outside 0..2147483647"),
    ("steps", 0.01, "0.01 is a number, expected a table of instance = step in s"),
    ("outputs", "plant.x", "'plant.x' is a string, expected a list of 'instance.port' strings"),
    ("name", 7, "7 is an integer, expected a string"),
], ids=lambda v: str(v) if not isinstance(v, str) or len(v) < 20 else v[:20])
def test_one_clear_line_per_bad_field(field, value, message):
    data = {"stop_time": 1.0, field: value}
    with pytest.raises(ConfigError) as caught:
        scenario_from_dict(data, source="sweep.toml")
    assert str(caught.value).splitlines() == [f"sweep.toml: field '{field}': {message}"]


@pytest.mark.parametrize("step, ok", [
    (0.005, True), (0.01, True), (0.015, True), (0.1, True), (0.3, True),
    (0.0075, False), (0.0049, False), (0.005 * (1 + 1e-7), False),
], ids=str)
def test_steps_must_be_integer_multiples_of_base_step(step, ok):
    data = {"stop_time": 3.0, "base_step": 0.005, "steps": {"planner": step}}
    if ok:
        scenario = scenario_from_dict(data)
        assert scenario.step_ratio("planner") == round(step / 0.005)
    else:
        with pytest.raises(ConfigError, match=r"field 'steps\.planner': .* is not an integer "
                                              r"multiple of base_step 0\.005"):
            scenario_from_dict(data)


def test_stop_time_must_be_a_whole_number_of_base_steps():
    with pytest.raises(ConfigError, match=r"field 'stop_time': 1\.005 is not an integer "
                                          r"multiple of base_step 0\.01 \(ratio 100\.5\)"):
        scenario_from_dict({"stop_time": 1.005})


def test_missing_system_file_and_bad_toml(tmp_path):
    path = write(tmp_path, 'stop_time = 1.0\nsystem = "nowhere.ssd"\n')
    missing = (tmp_path / "scenarios" / "nowhere.ssd").resolve()
    with pytest.raises(ConfigError) as caught:
        load_scenario(path)
    assert str(caught.value).splitlines() == [
        f"{path}: field 'system': '{missing}' does not exist (a path to an .ssd file)"]
    bad = write(tmp_path, "stop_time = \n", name="bad.toml")
    with pytest.raises(ConfigError, match=r"bad\.toml: not valid TOML \(.*line 1"):
        load_scenario(bad)
    with pytest.raises(ConfigError, match=r"absent\.toml: scenario file does not exist"):
        load_scenario(tmp_path / "absent.toml")


def test_shipped_scenarios():
    loaded = {path.stem: load_scenario(path) for path in sorted(SCENARIOS.glob("*.toml"))}
    assert sorted(loaded) == ["dynamic_case2", "room", "s_curve", "static_case1", "straight"]
    for scenario in loaded.values():
        assert scenario.system == SSD.resolve()
        assert scenario.base_step == 0.01
        assert [scenario.step_ratio(i) for i in ("source", "localizer", "planner",
                                                 "controller_left", "controller_right",
                                                 "plant")] == [1, 1, 2, 2, 2, 2]
    assert loaded["s_curve"].parameters["source.path"] == "s_curve"
    assert loaded["straight"].parameters["source.path"] == "straight"
    # only the room scenario hears a room; the others stay in free field
    assert [name for name, s in loaded.items() if s.parameters.get("localizer.room")] == ["room"]
    # Case 1: 2 m at 45 deg right of a robot at the origin facing +y.
    case1 = loaded["static_case1"].parameters
    assert (case1["source.x0"], case1["source.y0"]) == pytest.approx((2 * 0.5**0.5,) * 2,
                                                                     abs=1e-8)
    assert case1["planner.v_cruise"] == 0.3 and case1["planner.mode"] == "curvature"
    # Case 2: 1 m at 45 deg right, then 1 m at 45 deg left of the pose (0.707, 0.707), facing +x.
    case2 = loaded["dynamic_case2"].parameters
    assert (case2["source.x0"], case2["source.y0"]) == pytest.approx((0.5**0.5,) * 2, abs=1e-8)
    assert (case2["source.x1"], case2["source.y1"]) == pytest.approx((2 * 0.5**0.5,) * 2,
                                                                     abs=1e-8)
