"""A run plan written down as the whole-system FMU's description (no FMU is built here)."""

from types import SimpleNamespace

import pytest

from components.common.errors import ConfigError
from orchestrator.run.as_fmu import system_description


def _component(name, model, parameters=(), outputs=()):
    variables = ([SimpleNamespace(name=p, causality="parameter") for p in parameters]
                 + [SimpleNamespace(name=o, causality="output") for o in outputs])
    return SimpleNamespace(name=name, model_description=SimpleNamespace(
        modelName=model, modelVariables=variables))


def _plan(scenario_parameters=None, models=None):
    models = models or {}
    components = [
        _component("source", models.get("source", "SoundSource"), ("path",), ("x", "y")),
        _component("localizer", "AcousticLocalizer", ("seed",), ("distance",)),
        _component("plant", "RobotPlant", ("mu", "seed_like"), ("x", "y")),
    ]
    by_name = {c.name: c for c in components}
    system = SimpleNamespace(
        components=components, component=by_name.__getitem__,
        connections=[SimpleNamespace(start="source.x", end="localizer.source_x")])
    scenario = SimpleNamespace(name="demo", base_step=0.01, stop_time=3.0, seed=9,
                               parameters=dict(scenario_parameters or {}), source="demo.toml")
    parameters = {"source": {"path": "s_curve"}, "localizer": {"seed": 9},
                  "plant": {"mu": 0.5}}
    return SimpleNamespace(scenario=scenario, system=system, parameters=parameters,
                           rates={"source": 1, "localizer": 1, "plant": 2},
                           order=("source", "localizer", "plant"), algorithm="jacobi")


def test_the_plan_becomes_instances_in_stepping_order_with_their_values_and_rates():
    description = system_description(_plan())
    assert [(p.name, p.model, p.package, p.rate) for p in description.instances] == [
        ("source", "SoundSource", "source", 1), ("localizer", "AcousticLocalizer",
                                                 "acoustics", 1),
        ("plant", "RobotPlant", "plant", 2)]
    source, localizer, plant = description.instances
    assert source.parameters == {"path": "s_curve"} and plant.parameters == {"mu": 0.5}
    # the scenario's seed goes to the FMU's seed parameter, not to the instance's values
    assert localizer.seeded and localizer.parameters == {} and description.seed == 9
    assert not plant.seeded
    assert (description.algorithm, description.base_step, description.stop_time) == (
        "jacobi", 0.01, 3.0)
    assert description.links == (("source.x", "localizer.source_x"),)
    assert description.robot_position == ("plant.x", "plant.y")
    assert description.source_position == ("source.x", "source.y")


def test_a_seed_the_scenario_sets_itself_stays_with_its_instance():
    description = system_description(_plan({"localizer.seed": 9}))
    localizer = description.instances[1]
    assert not localizer.seeded and localizer.parameters == {"seed": 9}


def test_an_instance_of_another_model_cannot_be_carried():
    with pytest.raises(ConfigError, match="instance source: model 'ThirdParty' is not a "
                                          "sonotrack FMU"):
        system_description(_plan(models={"source": "ThirdParty"}))
