"""The run plan: what a run needs, resolved once from a scenario and its system (no FMU)."""

import dataclasses

import pytest

from components.common.errors import ConfigError
from orchestrator.run import RunPlan, plan_run
from orchestrator.system.sonotrack import SONOTRACK
from tests.support.fake_system import fake_scenario, fake_system

# a small sonotrack-like system: the summary's columns exist, plus some others
INSTANCES = {
    "source": [("x", "output", "Real", None), ("y", "output", "Real", None),
               ("label", "output", "String", None)],
    "planner": [("v_ref_left", "output", "Real", None), ("state", "output", "Integer", None),
                ("rejected_fixes", "output", "Integer", None),
                ("stop_distance", "parameter", "Real", "0.5"),
                ("distance", "input", "Real", None)],
    "plant": [("x", "output", "Real", None), ("y", "output", "Real", None),
              ("heading", "output", "Real", None), ("moving", "output", "Boolean", None),
              ("mass", "parameter", "Real", "3.0")],
}


def _plan(system=None, **fields):
    options = {k: fields.pop(k) for k in ("algorithm", "record_interval", "backend", "fsync",
                                          "handles") if k in fields}
    return plan_run(fake_scenario(**fields), system or fake_system(INSTANCES), **options)


def test_every_output_is_recorded_when_the_scenario_lists_none():
    plan = _plan()
    # the String output is not recorded; the rest in declaration order, instance by instance
    assert plan.columns == ("source.x", "source.y", "planner.v_ref_left", "planner.state",
                            "planner.rejected_fixes", "plant.x", "plant.y", "plant.heading",
                            "plant.moving")


def test_listed_outputs_then_the_summary_columns_the_system_has():
    plan = _plan(outputs=["plant.moving", "plant.x"])
    assert plan.columns == ("plant.moving", "plant.x", "source.x", "source.y", "plant.y",
                            "plant.heading", "planner.rejected_fixes")
    # in the order of the description's list, none twice
    forced = [c for c in SONOTRACK.recorded_columns if c in plan.columns]
    assert list(plan.columns[2:]) == [c for c in forced if c != "plant.x"]


def test_an_unknown_output_is_refused():
    with pytest.raises(ConfigError, match="plant.bogus: no such variable"):
        _plan(outputs=["plant.bogus"])


@pytest.mark.parametrize("steps, rates", [
    ({}, {"source": 1, "planner": 1, "plant": 1}),
    ({"planner": 0.02, "plant": 0.05}, {"source": 1, "planner": 2, "plant": 5}),
    ({"plant": 0.03}, {"source": 1, "planner": 1, "plant": 3}),   # 0.03 / 0.01 is 2.9999...
], ids=["base", "multiples", "inexact-quotient"])
def test_rates_are_whole_base_steps(steps, rates):
    assert _plan(steps=steps).rates == rates


def test_a_step_that_is_no_multiple_is_refused():
    with pytest.raises(ConfigError) as caught:
        _plan(steps={"plant": 0.015})
    assert str(caught.value) == ("steps.plant = 0.015 is not a positive integer multiple of "
                                 "base_step = 0.01")


@pytest.mark.parametrize("interval, every, rows", [
    (0.02, 2, 51), (0.05, 5, 21), (0.001, 1, 101), (0.014, 1, 101), (0.016, 2, 51)],
    ids=["default", "coarser", "below-a-step", "rounds-down", "rounds-up"])
def test_record_interval_in_base_steps(interval, every, rows):
    plan = _plan(record_interval=interval)     # 1 s at 10 ms: 100 steps
    assert plan.record_every == every and plan.expected_rows == rows


def test_stop_distance_from_the_scenario_else_the_fmu():
    assert _plan(parameters={"planner.stop_distance": 0.8}).stop_distance == 0.8
    assert _plan().stop_distance == 0.5                           # the FMU's start value
    no_planner = fake_system({k: v for k, v in INSTANCES.items() if k != "planner"})
    assert _plan(system=no_planner).stop_distance == 0.0


def test_parameters_order_and_options_are_resolved():
    system = fake_system(INSTANCES, bindings={"plant.mass": 4.0},
                         order=["plant", "source", "planner"])
    handles = object()
    plan = _plan(system=system, parameters={"plant.mass": 5.0}, master="jacobi",
                 backend="in-process", fsync=True, handles=handles)
    assert plan.parameters == {"source": {}, "planner": {}, "plant": {"mass": 5.0}}
    assert plan.order == ("plant", "source", "planner")
    assert (plan.algorithm, plan.backend, plan.fsync, plan.handles) == (
        "jacobi", "in-process", True, handles)
    assert _plan(master="jacobi", algorithm="gauss-seidel").algorithm == "gauss-seidel"


def test_an_unknown_backend_is_refused():
    with pytest.raises(ConfigError, match="backend 'cosim' is not one of fmi, in-process"):
        _plan(backend="cosim")


def test_the_plan_is_frozen():
    plan = _plan()
    assert isinstance(plan, RunPlan)
    with pytest.raises(dataclasses.FrozenInstanceError):
        plan.record_every = 3
