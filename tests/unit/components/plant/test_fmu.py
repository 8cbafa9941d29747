"""RobotPlant slave: complete FMU state, refusal of bad input, clamping log, model description."""

import json
import math

import pytest
from pythonfmu.enums import Fmi2Status

from components.plant import PlantParameters
from components.plant.fmu import RobotPlant

OUTPUTS = ("x", "y", "heading", "encoder_left", "encoder_right", "wheel_speed_left",
           "wheel_speed_right", "odom_x", "odom_y", "odom_heading", "slip_left", "slip_right",
           "lateral_slip_speed", "current_left", "current_right")


def make_slave(**parameters):
    slave = RobotPlant(instance_name="plant")
    for name, value in parameters.items():
        setattr(slave, name, value)
    slave.exit_initialization_mode()
    return slave


def run(slave, steps, step_size):
    trace = []
    for k in range(steps):
        slave.voltage_left = 6.0 + 5.0 * math.sin(0.013 * k)
        slave.voltage_right = 8.0 - 4.0 * math.cos(0.021 * k)
        assert slave.do_step(k * step_size, step_size)
        trace.append(tuple(getattr(slave, name) for name in OUTPUTS))
    return trace


@pytest.mark.parametrize("step_size, mu", [(0.001, 0.8), (0.003, 0.1), (0.01, 0.3)],
                         ids=["1ms-grip", "3ms-skid", "10ms"])
def test_state_round_trip_through_json_is_bit_identical(step_size, mu):
    slave = make_slave(mu=mu)
    run(slave, 137, step_size)                 # mid-window, encoder remainders non-zero
    saved = json.loads(json.dumps(slave._get_fmu_state()))
    first = run(slave, 500, step_size)
    slave._set_fmu_state(saved)
    second = run(slave, 500, step_size)
    assert first == second
    assert first[0] != first[-1]               # the robot moved in between


@pytest.mark.parametrize("port", ["voltage_left", "voltage_right"])
@pytest.mark.parametrize("bad", [math.nan, math.inf], ids=["nan", "inf"])
def test_non_finite_voltage_is_discarded_with_a_log_line_naming_port_and_value(port, bad):
    slave = make_slave()
    run(slave, 10, 0.01)
    before = (slave.x, slave.y, slave.encoder_left)
    setattr(slave, port, bad)
    assert slave.do_step(0.1, 0.01) is False
    errors = [m for m in slave.log_queue if m.status == Fmi2Status.error]
    assert len(errors) == 1 and port in errors[0].msg and repr(bad) in errors[0].msg
    assert (slave.x, slave.y, slave.encoder_left) == before
    setattr(slave, port, 3.0)                  # the instance keeps working
    assert slave.do_step(0.11, 0.01)


def test_voltage_beyond_supply_is_clamped_and_logged_once():
    slave = make_slave(v_supply=11.1)
    for k in range(600):
        slave.voltage_left = slave.voltage_right = 24.0
        slave.do_step(k * 0.01, 0.01)
    warnings = [m.msg for m in slave.log_queue if m.status == Fmi2Status.warning]
    assert len(warnings) == 2                  # one per port
    assert any("voltage_left = 24.0" in m for m in warnings)
    # Runs at the no-load speed for 11.1 V: V = N (Ke + R b / Kt) w, by hand.
    p = PlantParameters()
    omega = 11.1 / (14 * (p.back_emf_constant
                          + p.motor_resistance * p.motor_viscous_friction / p.torque_constant))
    assert slave.rim_speed_left == pytest.approx(omega * 0.06, rel=1e-5)


def test_parameters_reach_the_core():
    slave = make_slave(x0=1.0, y0=-2.0, heading0=0.0, encoder_ppr=100, mu=0.3)
    assert (slave.x, slave.y, slave.heading) == (1.0, -2.0, 0.0)
    assert (slave.odom_x, slave.odom_y) == (1.0, -2.0)
    assert slave.core.parameters.encoder_ppr == 100 and slave.core.parameters.mu == 0.3


def test_model_description_declares_units_and_no_direct_feedthrough():
    root = RobotPlant(instance_name="plant").to_xml()
    variables = {v.get("name"): v for v in root.find("ModelVariables")}
    assert variables["voltage_left"].find("Real").get("unit") == "V"
    assert variables["x"].find("Real").get("unit") == "m"
    assert variables["heading"].find("Real").get("unit") == "rad"
    assert variables["encoder_left"].get("variability") == "discrete"
    assert variables["encoder_left"].find("Integer") is not None
    outputs = root.find("ModelStructure").find("Outputs")
    assert len(outputs) == 22  # 19 Real (2 supply voltages), 2 encoders, faults_active
    assert all(unknown.get("dependencies") == "" for unknown in outputs)
