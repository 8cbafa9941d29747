"""RobotPlant core against analytic references: DC-motor steady state, Eq. (31), skid onset."""

import functools
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from components.plant import PlantParameters, RobotPlantCore, plant_rates

STEP = 0.01


def drive(core, voltage_left, voltage_right, duration, step=STEP):
    """Step ``core`` with held voltages; return the true and odometry paths as arrays."""
    count = round(duration / step)
    path = np.empty((count, 4))
    for k in range(count):
        core.step(voltage_left, voltage_right, step)
        path[k] = core.x, core.y, core.odom_x, core.odom_y
    return path


def hand_steady_state(p, voltage):
    """Wheel speed and current with no tyre force, from the motor equations solved anew.

    ``V = R i + Ke N w`` (armature) and ``eta N (Kt i - b N w) = 0`` (wheel, no load).
    """
    n, eta = p.gear_ratio, p.gear_efficiency
    matrix = np.array([[p.motor_resistance, p.back_emf_constant * n],
                       [eta * n * p.torque_constant, -eta * n * n * p.motor_viscous_friction]])
    current, omega = np.linalg.solve(matrix, [voltage, 0.0])
    return omega, current


def fit_circle(x, y):
    """Least-squares (Kasa) circle through points; returns the radius."""
    design = np.column_stack([x, y, np.ones_like(x)])
    (c0, c1, c2), *_ = np.linalg.lstsq(design, x * x + y * y, rcond=None)
    return math.sqrt(c2 + (c0 / 2) ** 2 + (c1 / 2) ** 2)


@pytest.mark.parametrize("voltage", [2.0, 6.0, 11.1, -7.5], ids=["2V", "6V", "11.1V", "-7.5V"])
def test_equal_voltages_drive_straight_along_the_start_heading(voltage):
    core = RobotPlantCore()
    path = drive(core, voltage, voltage, 3.0)
    assert np.max(np.abs(path[:, 0])) < 1e-9          # start heading is +y: x stays 0
    assert abs(core.heading - math.pi / 2) < 1e-12
    assert math.copysign(1.0, core.y) == math.copysign(1.0, voltage)
    assert abs(core.lateral_slip_speed) < 1e-12


@pytest.mark.parametrize("voltage", [3.0, 6.0, 11.1], ids=["3V", "6V", "11.1V"])
def test_steady_wheel_speed_and_current_match_the_dc_motor_steady_state(voltage):
    p = PlantParameters()
    omega, current = hand_steady_state(p, voltage)
    core = RobotPlantCore(p)
    drive(core, voltage, voltage, 8.0)                # about 20 mechanical time constants
    assert core.wheel_omega_left == pytest.approx(omega, rel=1e-5)
    assert core.wheel_omega_right == pytest.approx(omega, rel=1e-5)
    assert core.current_left == pytest.approx(current, rel=1e-4)
    assert core.speed == pytest.approx(omega * p.wheel_radius, rel=1e-5)


@pytest.mark.parametrize("voltages", [(2.0, 3.0), (3.0, 1.5), (1.0, 4.0)],
                         ids=["left-0.72m", "right-0.43m", "left-0.24m"])
def test_unequal_voltages_drive_the_circle_of_eq_31(voltages):
    # Lateral demands 0.4-1.3 m/s^2, far below mu*g: the wheels roll without skidding.
    p = PlantParameters()
    rim_left = hand_steady_state(p, voltages[0])[0] * p.wheel_radius
    rim_right = hand_steady_state(p, voltages[1])[0] * p.wheel_radius
    expected = abs(0.5 * p.track_width * (rim_right + rim_left) / (rim_right - rim_left))
    core = RobotPlantCore(p)
    path = drive(core, *voltages, 10.0)
    steady = path[round(4.0 / STEP):]                 # after the speed transient
    assert fit_circle(steady[:, 0], steady[:, 1]) == pytest.approx(expected, rel=0.02)


def ramp_into_tight_turn(mu):
    """Accelerate slowly (no wheel spin) onto a circle of about 0.57 m until 8 s.

    The final centripetal demand v^2/R is about 2.3 m/s^2: above mu*g for mu = 0.1 (0.98),
    far below it for mu = 0.8 (7.8).
    """
    core = RobotPlantCore(PlantParameters(mu=mu))
    demand, lateral, gap = [], [], []
    for k in range(800):
        ramp = min(1.0, k * STEP / 6.0)
        core.step(3.9 * ramp, 6.5 * ramp, STEP)
        demand.append(abs(core.speed * core.yaw_rate))
        lateral.append(abs(core.lateral_slip_speed))
        gap.append(math.hypot(core.x - core.odom_x, core.y - core.odom_y))
    return np.array(demand), np.array(lateral), np.array(gap)


def test_low_mu_fast_tight_turn_skids_sideways_and_leaves_the_odometry_path():
    mu, g = 0.1, 9.81
    demand, lateral, gap = ramp_into_tight_turn(mu)
    assert lateral.max() > 0.3
    onset = int(np.argmax(lateral > 0.05))
    # The skid starts once the centripetal demand reaches the friction limit mu*g.
    assert demand[onset] > 0.9 * mu * g
    assert demand[:onset].max() < 1.5 * mu * g
    assert gap[-1] > 0.3


def test_high_mu_same_manoeuvre_rolls_and_odometry_follows():
    demand, lateral, gap = ramp_into_tight_turn(0.8)
    assert demand.max() > 2.0                         # the same demand as the low-mu case
    assert lateral.max() < 0.03                       # tyre deflection only, < 3 % of v
    assert gap[-1] < 0.05                             # after about 6 m of travel


def voltage_profile(t):
    if t < 0.5:
        return 8.0, 4.0
    if t < 1.0:
        return -5.0, 11.1
    return 11.1, 11.1


@functools.lru_cache(maxsize=None)
def radau_reference(mu):
    """State after 1.5 s of ``voltage_profile``, by scipy's Radau at rtol 1e-9."""
    p = PlantParameters(mu=mu)
    state = [0.0] * 9 + [p.heading0]
    for start in (0.0, 0.5, 1.0):
        held = voltage_profile(start)
        solution = solve_ivp(lambda t, y: plant_rates(p, y, *held), (start, start + 0.5),
                             state, method="Radau", rtol=1e-9, atol=1e-11)
        state = solution.y[:, -1]
    return tuple(state)


def run_profile(parameters):
    core = RobotPlantCore(parameters)
    for k in range(150):
        core.step(*voltage_profile(k * STEP), STEP)
    return core


@pytest.mark.parametrize("mu", [0.8, 0.1], ids=["grip", "skid"])
def test_trajectory_matches_a_tight_tolerance_radau_solution(mu):
    state = radau_reference(mu)
    core = run_profile(PlantParameters(mu=mu, max_substep=2.5e-4))
    assert math.hypot(core.x - state[7], core.y - state[8]) < 3e-3   # 1.5 s of full-voltage turns
    assert abs(core.heading - state[9]) < 5e-3
    assert core.speed == pytest.approx(state[4], abs=5e-3)


@pytest.mark.parametrize("mu", [0.8, 0.1], ids=["grip", "skid"])
def test_default_substep_stays_within_half_a_millimetre_of_radau(mu):
    # Measured 0.02 mm / 0.02 mrad (grip) and 0.08 mm / 0.3 mrad (skid); the start from rest
    # and the voltage reversals are where substeps get split.
    state = radau_reference(mu)
    core = run_profile(PlantParameters(mu=mu))
    assert math.hypot(core.x - state[7], core.y - state[8]) < 5e-4
    assert abs(core.heading - state[9]) < 1e-3


def test_integration_error_is_second_order():
    # Without step splitting, halving the substep cuts the error about four-fold
    # (first order would halve it): measured 0.185 / 0.057 / 0.015 / 0.004 mm.
    state = radau_reference(0.8)
    errors = []
    for substep in (1e-3, 5e-4, 2.5e-4):
        core = run_profile(PlantParameters(max_substep=substep, substep_tolerance=1e9))
        errors.append(math.hypot(core.x - state[7], core.y - state[8]))
    assert errors[0] / errors[1] > 3.0
    assert errors[1] / errors[2] > 3.0


@pytest.mark.parametrize("step, tolerance", [(0.001, 1e-12), (0.01, 1e-12), (0.02, 1e-12),
                                             (0.000625, 1e-3)],
                         ids=["1ms", "10ms", "20ms", "0.625ms-off-grid"])
def test_communication_step_does_not_change_the_trajectory(step, tolerance):
    # Steps on the 0.25 ms substep grid integrate identically; an off-grid step uses slightly
    # shorter substeps and differs by the truncation error only.
    fine = PlantParameters(max_substep=2.5e-4)
    reference = RobotPlantCore(fine)
    for k in range(round(1.5 / 0.005)):
        reference.step(*voltage_profile(k * 0.005), 0.005)
    core = RobotPlantCore(fine)
    count = round(1.5 / step)
    for k in range(count):
        core.step(*voltage_profile(k * step), step)
    assert math.hypot(core.x - reference.x, core.y - reference.y) < tolerance


@pytest.mark.parametrize("step, tolerance", [(0.001, 1e-4), (0.002, 1e-12), (0.005, 1e-4),
                                             (0.01, 1e-12)],
                         ids=["1ms", "2ms", "5ms", "10ms"])
def test_default_substep_is_stable_and_consistent_for_every_communication_step(step, tolerance):
    # Steps that are multiples of the 2 ms default substep repeat the 20 ms trajectory exactly;
    # 1 ms and 5 ms steps use shorter substeps (measured within 0.02 mm after 1.5 s).
    reference = RobotPlantCore()
    for k in range(round(1.5 / 0.02)):
        reference.step(*voltage_profile(k * 0.02), 0.02)
    core = RobotPlantCore()
    for k in range(round(1.5 / step)):
        core.step(*voltage_profile(k * step), step)
    assert math.hypot(core.x - reference.x, core.y - reference.y) < tolerance
