"""The sonotrack system description against the system it describes.

The references are the ``.ssd`` generator's instance table (:data:`SONOTRACK_INSTANCES`, which
``fmus/SystemStructure.ssd`` is written from) and the slave classes themselves (the ports each
FMU declares), not the description's own values.
"""

import dataclasses
import doctest
from types import SimpleNamespace

import pytest

from components.common.errors import ConfigError
from orchestrator.fmu.inprocess import slave_class
from orchestrator.ssp import SONOTRACK_INSTANCES
from orchestrator.system import sonotrack
from orchestrator.system.sonotrack import SONOTRACK, SonotrackSystem

ROLES = {"source": "SoundSource", "localizer": "AcousticLocalizer",
         "planner": "CurvaturePlanner", "plant": "RobotPlant"}


@pytest.mark.parametrize("role, model", sorted(ROLES.items()), ids=sorted(ROLES))
def test_each_role_is_an_instance_of_its_model(role, model):
    assert SONOTRACK_INSTANCES[getattr(SONOTRACK, role)] == model


def test_the_wheel_controllers_are_the_two_wheel_controller_instances():
    expected = sorted(name for name, model in SONOTRACK_INSTANCES.items()
                      if model == "WheelController")
    assert sorted(SONOTRACK.wheel_controllers) == expected == ["controller_left",
                                                               "controller_right"]


def _ports(causality):
    """``instance.port`` of every port of that causality, from the slave classes."""
    ports = set()
    for instance, model in SONOTRACK_INSTANCES.items():
        slave = slave_class(model)(instance_name=instance)
        ports |= {f"{instance}.{v.name}" for v in slave.vars.values()
                  if v.causality.name == causality}
    return ports


def test_every_column_named_is_an_output_of_the_system():
    outputs = _ports("output")
    named = (set(SONOTRACK.recorded_columns) | set(SONOTRACK.position_columns)
             | {SONOTRACK.body_speed, *SONOTRACK.wheel_slips, SONOTRACK.fix_attempts,
                SONOTRACK.fix_status, SONOTRACK.rejected_fixes, SONOTRACK.wheel_check_stops,
                SONOTRACK.odometry_check_stops, *SONOTRACK.odometry_position,
                *SONOTRACK.fix_columns}
             | {getattr(SONOTRACK, f)(side) for f in ("wheel_speed", "rim_speed",
                                                      "wheel_reference")
                for side in SONOTRACK.sides})
    assert named - outputs == set()
    # the 20 always recorded, the two check counters, odometry, fixes, wheel speeds, references
    assert len(named) == 20 + 2 + 2 + 3 + 2 + 2
    assert f"{SONOTRACK.planner}.{SONOTRACK.stop_distance_parameter}" in _ports("parameter")


def test_columns_follow_the_roles():
    renamed = SonotrackSystem(source="beacon", plant="robot", localizer="ears",
                              planner="brain")
    assert renamed.position_columns == ("robot.x", "robot.y", "beacon.x", "beacon.y")
    assert renamed.recorded_columns == (
        "beacon.x", "beacon.y", "robot.x", "robot.y", "robot.heading", "robot.speed",
        "robot.slip_left", "robot.slip_right", "ears.fix_attempts", "ears.fix_status",
        "brain.rejected_fixes", "ears.faults_active", "beacon.faults_active",
        "robot.faults_active", "controller_left.kp", "controller_left.kd", "controller_right.kp",
        "controller_right.kd", "robot.rim_speed_left", "robot.rim_speed_right")
    assert (renamed.wheel_check_stops, renamed.odometry_check_stops) == (
        "brain.wheel_faults", "brain.odometry_faults")


def test_the_description_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        SONOTRACK.planner = "other"


def _system(planner_start):
    """A system whose planner declares ``stop_distance`` with that start value, or none."""
    variables = [SimpleNamespace(name="v_max", start="0.4"),
                 SimpleNamespace(name="stop_distance", start=planner_start)]
    planner = SimpleNamespace(model_description=SimpleNamespace(modelVariables=variables))

    def component(name):
        if name != "planner":
            raise ConfigError(f"no component {name!r}")
        return planner

    return SimpleNamespace(component=component)


@pytest.mark.parametrize("parameters, start, expected", [
    ({"planner": {"stop_distance": 0.75}}, "0.5", 0.75),     # the run's value wins
    ({"planner": {"stop_distance": 1}}, "0.5", 1.0),          # as a float
    ({"planner": {"v_max": 0.3}, "plant": {}}, "0.5", 0.5),   # else the FMU's start value
    ({}, None, 0.0),                                          # no start value either
], ids=["run-value", "int-value", "start-value", "nothing"])
def test_stop_distance_comes_from_the_run_then_the_fmu(parameters, start, expected):
    value = SONOTRACK.stop_distance(_system(start), parameters)
    assert value == expected and type(value) is float


def test_a_system_without_a_planner_stops_at_zero():
    no_planner = SimpleNamespace(component=lambda name: (_ for _ in ()).throw(
        ConfigError(f"no component {name!r}")))
    assert SONOTRACK.stop_distance(no_planner, {"plant": {"stop_distance": 3.0}}) == 0.0
    assert SonotrackSystem(planner="plant").stop_distance(
        no_planner, {"plant": {"stop_distance": 3.0}}) == 3.0


def _controllers(left_start, right_value=None):
    """A system of two wheel controllers declaring ``mode`` with ``left_start``."""
    def component(name):
        start = left_start if name in ("controller_left", "controller_right") else None
        if start is None:
            raise ConfigError(f"no component {name!r}")
        return SimpleNamespace(model_description=SimpleNamespace(
            modelVariables=[SimpleNamespace(name="mode", start=start)]))

    parameters = {} if right_value is None else {"controller_right": {"mode": right_value}}
    return SimpleNamespace(component=component), parameters


@pytest.mark.parametrize("left_start, right_value, expected", [
    ("fgs_pd", None, "fgs_pd"),          # both from the FMU's start value: said once
    ("fgs_pd", "pid", "fgs_pd / pid"),   # a run that sets one of them
    (None, None, ""),                    # no controllers
], ids=["same", "differ", "none"])
def test_the_controller_law_of_a_run(left_start, right_value, expected):
    system, parameters = _controllers(left_start, right_value)
    assert SONOTRACK.controller_mode(system, parameters) == expected


def test_the_module_examples_hold():
    assert doctest.testmod(sonotrack).failed == 0
