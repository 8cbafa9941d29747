"""The validated Scenario: built from a dict, its dict form, overrides and the input hash."""

import hashlib
import json
from pathlib import Path

import pytest

from components.common.errors import ConfigError
from orchestrator.scenario import load_scenario, scenario_from_dict

REPO = Path(__file__).resolve().parents[4]
SCENARIOS = REPO / "scenarios"
SSD = REPO / "fmus" / "SystemStructure.ssd"


def test_dict_scenario_defaults_to_the_repository_system():
    scenario = scenario_from_dict({"stop_time": 1.0})
    assert scenario.system == SSD.resolve()
    assert scenario.name == "scenario"


def test_to_dict_round_trips_and_is_json():
    scenario = load_scenario(SCENARIOS / "dynamic_case2.toml")
    data = scenario.to_dict()
    assert json.loads(json.dumps(data)) == data
    assert scenario_from_dict(data) == scenario


def test_overrides_merge_parameters_and_steps_and_revalidate():
    base = load_scenario(SCENARIOS / "s_curve.toml")
    fast = base.with_overrides(parameters={"planner.v_cruise": 0.4}, steps={"planner": 0.05},
                               seed=7)
    assert fast.parameters == {"source.path": "s_curve", "planner.mode": "curvature",
                               "planner.v_cruise": 0.4}
    assert fast.steps["planner"] == 0.05 and fast.steps["plant"] == 0.02
    assert fast.seed == 7 and base.seed == 1 and base.parameters["planner.v_cruise"] == 0.3
    with pytest.raises(ConfigError, match=r"field 'master': 'rk4' is not one of"):
        base.with_overrides(master="rk4")
    with pytest.raises(ConfigError, match=r"unknown field 'stoptime'"):
        base.with_overrides(stoptime=3.0)


def test_input_hash_is_sha256_of_the_canonical_inputs():
    scenario = load_scenario(SCENARIOS / "static_case1.toml")
    data = scenario.to_dict()
    del data["name"], data["description"], data["system"], data["max_steps"]
    data["system_sha256"] = hashlib.sha256(SSD.read_bytes()).hexdigest()
    canonical = json.dumps(data, sort_keys=True, separators=(",", ":"))
    assert scenario.input_hash() == hashlib.sha256(canonical.encode()).hexdigest()


def test_input_hash_ignores_names_and_follows_results_inputs(tmp_path):
    scenario = load_scenario(SCENARIOS / "static_case1.toml")
    renamed = scenario.with_overrides(name="other", description="same run")
    assert renamed.input_hash() == scenario.input_hash()
    assert renamed != scenario
    assert hash(load_scenario(SCENARIOS / "static_case1.toml")) == hash(scenario)
    changed = scenario.with_overrides(parameters={"planner.v_cruise": 0.31})
    assert changed.input_hash() != scenario.input_hash()
    assert scenario.input_hash(extra={"RobotPlant.fmu": "abc"}) != scenario.input_hash()
    # The .ssd enters by content: a copy elsewhere hashes alike, an edited one does not.
    copy = tmp_path / "SystemStructure.ssd"
    copy.write_bytes(SSD.read_bytes())
    assert scenario.with_overrides(system=str(copy)).input_hash() == scenario.input_hash()
    copy.write_bytes(SSD.read_bytes().replace(b"s_curve", b"straight"))
    assert scenario.with_overrides(system=str(copy)).input_hash() != scenario.input_hash()
