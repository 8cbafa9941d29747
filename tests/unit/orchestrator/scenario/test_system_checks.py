"""The scenario schema checks values against the FMUs' valid ranges before any FMU is loaded."""

import pytest

from components.common.errors import ConfigError
from orchestrator.scenario import DEFAULT_MAX_STEPS, scenario_from_dict

BASE = {"stop_time": 1.0}


def _problem(**fields):
    with pytest.raises(ConfigError) as caught:
        scenario_from_dict({**BASE, **fields}, source="s.toml")
    lines = str(caught.value).splitlines()
    assert len(lines) == 1, lines
    return lines[0]


@pytest.mark.parametrize("key, value, message", [
    ("source.mute_at_end", "false",
     "source.mute_at_end = 'false' is a string, expected a boolean, true or false"),
    ("localizer.adc_bits", 4294967306,
     "localizer.adc_bits = 4294967306 is outside its valid range [2, 24]"),
    ("localizer.adc_bits", 10.7, "localizer.adc_bits = 10.7 is a number, expected an integer"),
    ("planner.v_cruise", True, "planner.v_cruise = true is a boolean, expected a number"),
    ("plant.mass", -1.0, "plant.mass = -1.0 is outside its valid range [0.1, 1000.0] kg"),
    ("plant.max_substep", 1e-9, "plant.max_substep = 1e-09 is outside its valid range"),
    ("plant.speed_window", 1e-9, "plant.speed_window = 1e-09 is outside its valid range"),
    ("source.emit_period", 5e-324, "source.emit_period = 5e-324 is outside its valid range"),
    ("source.amplitude", 1e300, "source.amplitude = 1e+300 is outside its valid range"),
    ("localizer.method", "magic",
     "localizer.method = 'magic' is not valid; valid: one of 'exact', 'paper', 'far_field'"),
    ("planner.bogus", 1, "planner (CurvaturePlanner) has no parameter 'bogus'; parameters: "),
    ("nobody.mass", 1.0, "no instance 'nobody' in "),
], ids=lambda v: str(v)[:24])
def test_a_bad_parameter_names_file_field_value_and_valid_range(key, value, message):
    line = _problem(parameters={key: value})
    assert line.startswith(f"s.toml: field 'parameters.{key}': {message}")


def test_unknown_steps_instance_is_refused_with_the_instances():
    line = _problem(steps={"bogus_instance": 0.02})
    assert line.startswith("s.toml: field 'steps.bogus_instance': no instance 'bogus_instance'")
    listed = line.rpartition("; instances: ")[2].split(", ")
    assert sorted(listed) == sorted(["source", "localizer", "planner", "controller_left",
                                     "controller_right", "plant"])


def test_an_instance_step_outside_its_fmu_range_is_refused():
    line = _problem(steps={"controller_left": 2.0}, stop_time=2.0)
    assert line == ("s.toml: field 'steps.controller_left': 2.0 s is outside the step range of "
                    "controller_left (WheelController): [1e-06, 1.0] s")


@pytest.mark.parametrize("fields, message", [
    ({"stop_time": 1e300}, "1e+300 s at base_step 0.01 s is 1e+302 steps, more than "
                           f"max_steps = {DEFAULT_MAX_STEPS}; raise max_steps"),
    ({"stop_time": 10.0, "max_steps": 100}, "is 1000 steps, more than max_steps = 100"),
], ids=["huge", "raised_bound"])
def test_the_step_count_is_bounded_and_the_bound_named(fields, message):
    assert message in _problem(**fields)


def test_raising_max_steps_admits_a_longer_run():
    scenario = scenario_from_dict({"stop_time": 10.0, "max_steps": 1000})
    assert scenario.step_count == 1000 and scenario.max_steps == 1000


def test_tiny_base_step_is_refused_by_the_step_count_and_the_fmu_step_ranges():
    with pytest.raises(ConfigError) as caught:
        scenario_from_dict({"stop_time": 1.0, "base_step": 1e-300}, source="s.toml")
    text = str(caught.value)
    assert "more than max_steps" in text
    assert "field 'base_step': 1e-300 s (the step of every instance not in [steps]) is " \
           "outside the step range of source [1e-06, 1.0] s" in text


def test_a_bad_binding_in_the_ssd_is_refused_naming_the_ssd(tmp_path):
    from dataclasses import replace

    from orchestrator.scenario import default_system_path
    from orchestrator.ssp import ParameterValue, read_ssd, write_ssd

    # bind plant.mass = -1 in a copy of the shipped .ssd
    description = read_ssd(default_system_path())
    components = [replace(c, parameters={**c.parameters,
                                         "mass": ParameterValue("Real", -1.0)})
                  if c.name == "plant" else c for c in description.components]
    ssd = tmp_path / "bad.ssd"
    write_ssd(ssd, replace(description, components=components))
    with pytest.raises(ConfigError) as caught:
        scenario_from_dict({"stop_time": 1.0, "system": str(ssd)}, source="s.toml")
    assert str(caught.value) == (f"{ssd}: parameter binding of component 'plant': plant.mass = "
                                 "-1.0 is outside its valid range [0.1, 1000.0] kg")
    # a scenario override of the same parameter replaces the binding
    scenario_from_dict({"stop_time": 1.0, "system": str(ssd),
                        "parameters": {"plant.mass": 4.5}}, source="s.toml")


def test_a_run_whose_metrics_are_not_finite_is_not_ok():
    from orchestrator.run.runner import _non_finite_metrics

    summary = {"status": "ok", "path_rmse_m": float("nan"), "final_distance_to_source_m": 1.0,
               "realtime_factor": float("inf")}
    error = _non_finite_metrics(summary, None)
    assert summary["status"] == "failed" and summary["error"] == error
    assert error.startswith("metrics not finite: path_rmse_m = nan")
    finite = {"status": "ok", "path_rmse_m": 0.1, "realtime_factor": float("inf")}
    assert _non_finite_metrics(finite, None) is None and finite["status"] == "ok"


@pytest.mark.parametrize("type_name, value, problem", [
    ("Integer", 10.7, "is float, expected an fmi2Integer value"),
    ("Integer", 2**32 + 10, "does not fit a 32-bit fmi2Integer"),
    ("Integer", True, "is bool, expected an fmi2Integer value"),
    ("Real", True, "is bool, expected an fmi2Real value"),
    ("Real", "0.3", "is str, expected an fmi2Real value"),
    ("Boolean", "false", "is str, expected an fmi2Boolean value"),
    ("Boolean", 1, "is int, expected an fmi2Boolean value"),
    ("String", 5, "is int, expected an fmi2String value"),
    ("Real", 3, ""), ("Integer", 10, ""), ("Boolean", False, ""), ("String", "pd", ""),
], ids=repr)
def test_fmu_handle_sets_values_without_coercion(type_name, value, problem):
    from orchestrator.fmu.handle import _type_problem

    assert _type_problem(type_name, value) == problem
