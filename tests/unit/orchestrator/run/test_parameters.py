"""Parameter values per instance: bindings, then overrides, then the seed; every problem at once."""

import pytest

from components.common.errors import ConfigError
from orchestrator.run import instance_parameters
from tests.support.fake_system import fake_scenario, fake_system

INSTANCES = {
    "source": [("x", "output", "Real", None), ("path", "parameter", "String", "static")],
    "localizer": [("distance", "output", "Real", None), ("seed", "parameter", "Integer", "0"),
                  ("noise", "parameter", "Real", "0.01")],
    "planner": [("stop_distance", "parameter", "Real", "0.5"),
                ("v_max", "parameter", "Real", "0.4")],
}


class _WaypointFile:
    """A bound value that resolves to another when the run uses it (as a waypoint CSV does)."""

    def run_value(self):
        return "/abs/waypoints.csv"


def test_bindings_then_overrides_then_the_seed():
    system = fake_system(INSTANCES, bindings={"source.path": _WaypointFile(),
                                              "planner.v_max": 0.3, "planner.stop_distance": 0.6})
    scenario = fake_scenario(parameters={"planner.v_max": 0.25, "localizer.noise": 0.02},
                             seed=11.0)
    assert instance_parameters(system, scenario) == {
        "source": {"path": "/abs/waypoints.csv"},
        "localizer": {"noise": 0.02, "seed": 11},
        "planner": {"v_max": 0.25, "stop_distance": 0.6},
    }
    assert type(instance_parameters(system, scenario)["localizer"]["seed"]) is int


def test_a_scenario_seed_of_its_own_is_kept():
    scenario = fake_scenario(parameters={"localizer.seed": 3}, seed=11)
    assert instance_parameters(fake_system(INSTANCES), scenario)["localizer"] == {"seed": 3}


def test_every_unknown_name_is_reported_at_once():
    scenario = fake_scenario(parameters={"nobody.mass": 1.0, "planner.bogus": 2.0,
                                         "planner.v_max": 0.3, "localizer.distance": 1.0},
                             source="bad.toml")
    with pytest.raises(ConfigError) as caught:
        instance_parameters(fake_system(INSTANCES), scenario)
    assert str(caught.value) == (
        "bad.toml: parameters.nobody.mass: no instance 'nobody'; instances are source, "
        "localizer, planner; parameters.planner.bogus: planner has no parameter 'bogus'; "
        "valid: stop_distance, v_max; parameters.localizer.distance: localizer has no "
        "parameter 'distance'; valid: seed, noise")
