"""The CurvaturePlanner slave without building it: ports, units, refusals, complete state."""

import json
import math

import pytest

from components.planner.fmu import CurvaturePlanner

STEP = 0.02


def variables(slave):
    return {node.get("name"): node for node in slave.to_xml().find("ModelVariables")}


def step_loop(slave, steps, t0=0.0):
    rows = []
    for k in range(steps):
        slave.wheel_speed_left, slave.wheel_speed_right = slave.v_ref_left, slave.v_ref_right
        assert slave.do_step(t0 + k * STEP, STEP) is True
        rows.append((slave.v_ref_left, slave.v_ref_right, slave.radius, slave.curvature,
                     slave.arc_remaining, slave.state, slave.target_x, slave.target_y))
    return rows


@pytest.mark.parametrize("port, causality, unit", [
    ("distance", "input", "m"), ("bearing", "input", "rad"), ("valid", "input", None),
    ("measurement_id", "input", None), ("wheel_speed_left", "input", "m/s"),
    ("wheel_speed_right", "input", "m/s"), ("v_ref_left", "output", "m/s"),
    ("v_ref_right", "output", "m/s"), ("radius", "output", "m"), ("curvature", "output", "1/m"),
    ("arc_remaining", "output", "m"), ("track_width", "parameter", "m"),
    ("mode", "parameter", None), ("stop_distance", "parameter", "m")],
    ids=lambda value: str(value))
def test_contract_ports_and_units(port, causality, unit):
    node = variables(CurvaturePlanner(instance_name="t"))[port]
    assert node.get("causality") == causality
    if unit is not None:
        assert node.find("Real").get("unit") == unit


def test_manual_loop_drives_table6_and_state_round_trip_is_exact():
    slave = CurvaturePlanner(instance_name="t")
    slave.track_width, slave.v_cruise, slave.stop_distance = 0.40, 0.3, 0.0
    slave.exit_initialization_mode()
    slave.distance, slave.bearing, slave.valid, slave.measurement_id = 2.0, -math.pi / 4, True, 1
    rows = step_loop(slave, 60)
    assert rows[0][2] == pytest.approx(2.0 / (2 * math.sin(math.pi / 4)))      # Eq. (36)
    saved = json.loads(json.dumps(slave._get_fmu_state()))
    # A second fix half-way makes the continuation exercise the blend and the re-plan.
    slave.distance, slave.bearing, slave.measurement_id = 1.0, math.pi / 4, 2
    first = step_loop(slave, 150, t0=60 * STEP)
    slave._set_fmu_state(saved)
    slave.distance, slave.bearing, slave.measurement_id = 1.0, math.pi / 4, 2
    second = step_loop(slave, 150, t0=60 * STEP)
    assert first == second


def test_nan_fix_is_refused_and_negative_distance_only_logged():
    slave = CurvaturePlanner(instance_name="t")
    slave.exit_initialization_mode()
    slave.distance, slave.valid, slave.measurement_id = math.nan, True, 1
    assert slave.do_step(0.0, STEP) is False
    assert "distance = nan" in slave.log_queue[-1].msg
    slave.distance, slave.measurement_id = -0.5, 2
    assert slave.do_step(0.0, STEP) is True
    assert "negative" in slave.log_queue[-1].msg and (slave.v_ref_left, slave.state) == (0.0, 0)
    slave.valid, slave.distance = False, math.nan          # an invalid fix may carry NaN
    assert slave.do_step(STEP, STEP) is True
