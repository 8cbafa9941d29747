"""Coulomb friction and the load_torque fault against the analytic steady state of a wheel.

On a straight line at constant voltage the body does not accelerate, so the rim force is 0
and each wheel balances ``eta N (Kt i - b N w - T_c) = T_load`` with ``V = R i + Ke N w``:

    w = (V - R T_c / Kt - R T_load / (eta N Kt)) / (N (Ke + R b / Kt))

(eta cancels from the Coulomb term, not from a load at the wheel). Below the break-away
voltage ``R T_c / Kt`` a wheel at rest stays there (stiction), up to the creep of the tanh
regularisation, ``(COULOMB_SPEED / N) atanh(V Kt / (R T_c))`` at the wheel.
"""

import math

import pytest

from components.common.errors import ParameterError
from components.common.faults import Fault, encode_schedule
from components.plant import PlantParameters, RobotPlantCore
from components.plant.dynamics import COULOMB_SPEED

STEP = 0.02


def _analytic_speed(p, voltage, coulomb=0.0, load=0.0):
    """Steady rim speed [m/s] of both wheels driven at ``voltage`` in a straight line."""
    drive = voltage - p.motor_resistance * coulomb / p.torque_constant \
        - p.motor_resistance * load / (p.gear_efficiency * p.gear_ratio * p.torque_constant)
    per_omega = p.gear_ratio * (p.back_emf_constant
                                + p.motor_resistance * p.motor_viscous_friction
                                / p.torque_constant)
    return p.wheel_radius * drive / per_omega


def _drive(core, voltage, seconds):
    for _ in range(int(round(seconds / STEP))):
        core.step(voltage, voltage, STEP)


@pytest.mark.parametrize("coulomb", [0.0, 0.005, 0.02], ids=["none", "5 mN m", "20 mN m"])
@pytest.mark.parametrize("voltage", [3.0, 11.1], ids=["3 V", "11.1 V"])
def test_steady_speed_with_coulomb_and_viscous_friction_is_analytic(coulomb, voltage):
    p = PlantParameters(coulomb_friction=coulomb)
    core = RobotPlantCore(p)
    _drive(core, voltage, 8.0)      # 20 mechanical time constants
    expected = _analytic_speed(p, voltage, coulomb=coulomb)
    assert core.rim_speed_left == pytest.approx(expected, rel=1e-6)
    assert core.rim_speed_right == pytest.approx(expected, rel=1e-6)
    assert core.speed == pytest.approx(expected, rel=1e-5)


def test_coulomb_friction_costs_its_break_away_voltage_of_speed():
    """The difference of two analytic speeds: R T_c / Kt volts, independent of eta."""
    plain, dry = RobotPlantCore(), RobotPlantCore(PlantParameters(coulomb_friction=0.02))
    _drive(plain, 6.0, 8.0)
    _drive(dry, 6.0, 8.0)
    p = dry.parameters
    lost = p.motor_resistance * 0.02 / p.torque_constant            # 2.65 V
    assert plain.rim_speed_left - dry.rim_speed_left == pytest.approx(
        p.wheel_radius * lost / (p.gear_ratio * (p.back_emf_constant + p.motor_resistance
                                                 * p.motor_viscous_friction
                                                 / p.torque_constant)), rel=1e-6)


@pytest.mark.parametrize("fraction", [0.5, 0.9], ids=["half", "90 %"])
def test_a_wheel_at_rest_below_break_away_stays_there(fraction):
    p = PlantParameters(coulomb_friction=0.02)
    break_away = p.motor_resistance * p.coulomb_friction / p.torque_constant
    core = RobotPlantCore(p)
    _drive(core, fraction * break_away, 3.0)
    creep = p.wheel_radius * COULOMB_SPEED / p.gear_ratio * math.atanh(fraction)
    assert abs(core.rim_speed_left) <= creep * 1.01
    assert abs(core.y) < 3.0 * creep * 1.01          # at most the creep for 3 s
    assert core.encoder_left == 0 or abs(core.encoder_left) <= 3


def test_above_break_away_the_wheel_turns_at_the_analytic_speed():
    p = PlantParameters(coulomb_friction=0.02)
    break_away = p.motor_resistance * p.coulomb_friction / p.torque_constant
    core = RobotPlantCore(p)
    _drive(core, 1.5 * break_away, 8.0)
    assert core.rim_speed_left == pytest.approx(
        _analytic_speed(p, 1.5 * break_away, coulomb=0.02), rel=1e-6)


def test_negative_coulomb_friction_is_refused():
    with pytest.raises(ParameterError, match="coulomb_friction"):
        PlantParameters(coulomb_friction=-0.01).validate()


def test_load_torque_fault_slows_the_wheel_to_the_analytic_speed():
    schedule = encode_schedule([Fault("load_torque", 2.0, magnitude=0.19, channel="both")])
    core = RobotPlantCore(PlantParameters(), fault_schedule=schedule)
    p = core.parameters
    _drive(core, 6.0, 2.0)
    assert core.load_torque_left == 0.0
    _drive(core, 6.0, 8.0)
    assert core.load_torque_left == core.load_torque_right == 0.19
    expected = _analytic_speed(p, 6.0, load=0.19)
    assert expected < 0.9 * _analytic_speed(p, 6.0)
    assert core.rim_speed_left == pytest.approx(expected, rel=1e-6)


def test_load_torque_on_one_wheel_turns_the_robot_towards_it():
    schedule = encode_schedule([Fault("load_torque", 0.0, magnitude=0.1, channel="left")])
    core = RobotPlantCore(PlantParameters(), fault_schedule=schedule)
    _drive(core, 6.0, 2.0)
    assert core.rim_speed_left < core.rim_speed_right
    assert core.heading > core.parameters.heading0       # slower left wheel: a left turn
    assert core.faults_active == 1
