"""RobotPlant building blocks: traction law, encoder, odometry, motor constants, inputs."""

import math

import numpy as np
import pytest

from components.common.errors import InputError, ParameterError
from components.plant import (EncoderOdometry, PlantParameters, RobotPlantCore, WheelEncoder,
                              motor_constants_from_datasheet, slip_ratio, steady_wheel_speed,
                              traction_force, turn_radius)

LOAD = 22.0725                                       # half of 4.5 kg x 9.81 m/s^2 [N]


@pytest.mark.parametrize("slip", [(1e-5, 0.0), (0.0, -2e-5), (3e-6, 4e-6)],
                         ids=["long", "lat", "combined"])
def test_small_slip_force_is_linear_with_slope_stiffness_times_load(slip):
    fx, fy, kx, ky = traction_force(*slip, LOAD, 0.8, 10.0)
    assert fx == pytest.approx(10.0 * LOAD * slip[0], rel=1e-6, abs=1e-12)
    assert fy == pytest.approx(10.0 * LOAD * slip[1], rel=1e-6, abs=1e-12)
    assert kx == pytest.approx(10.0 * LOAD, rel=1e-6)


@pytest.mark.parametrize("slip", [(0.9, 0.0), (-0.5, 0.3), (0.2, 0.6), (0.0, -1.5)],
                         ids=["spin", "brake-skid", "drive-skid", "side-slide"])
def test_large_slip_force_saturates_on_the_friction_circle_along_the_slip(slip):
    mu = 0.6
    fx, fy, _, _ = traction_force(*slip, LOAD, mu, 10.0)
    magnitude = math.hypot(fx, fy)
    assert magnitude <= mu * LOAD * (1 + 1e-12)
    assert magnitude > 0.99 * mu * LOAD
    # Parallel to the slip vector: zero cross product, positive dot product.
    assert abs(fx * slip[1] - fy * slip[0]) < 1e-9 * magnitude
    assert fx * slip[0] + fy * slip[1] > 0


@pytest.mark.parametrize("slip", [(0.01, 0.0), (0.05, 0.02), (-0.3, 0.1), (0.02, -0.4)],
                         ids=["linear", "knee", "braking", "lateral"])
def test_reported_stiffnesses_are_the_partial_derivatives(slip):
    step = 1e-7
    _, _, kx, ky = traction_force(*slip, LOAD, 0.8, 10.0)
    plus = traction_force(slip[0] + step, slip[1], LOAD, 0.8, 10.0)[0]
    minus = traction_force(slip[0] - step, slip[1], LOAD, 0.8, 10.0)[0]
    assert kx == pytest.approx((plus - minus) / (2 * step), rel=1e-5)
    plus = traction_force(slip[0], slip[1] + step, LOAD, 0.8, 10.0)[1]
    minus = traction_force(slip[0], slip[1] - step, LOAD, 0.8, 10.0)[1]
    assert ky == pytest.approx((plus - minus) / (2 * step), rel=1e-5)


@pytest.mark.parametrize("rim, ground, expected", [(1.0, 1.0, 0.0), (1.0, 0.8, 0.2),
                                                   (0.8, 1.0, -0.2), (0.5, 0.0, 1.0),
                                                   (0.01, 0.0, 0.2)],
                         ids=["rolling", "driving", "braking", "spinning", "standstill-floor"])
def test_slip_ratio(rim, ground, expected):
    assert slip_ratio(rim, ground, 0.05) == pytest.approx(expected)


def test_encoder_counts_floor_of_angle_in_counts_and_keeps_the_remainder():
    encoder = WheelEncoder(728, 0.06)
    angle = 0.0
    for increment in [0.001, 0.0042, -0.003, 0.2, 1e-5, -0.5, 0.0086] * 20:
        encoder.turn(increment)
        angle += increment
        assert encoder.count == math.floor(angle * 728 / (2 * math.pi) + 1e-9)
    assert encoder.distance_per_count == pytest.approx(2 * math.pi * 0.06 / 728)   # 0.52 mm


def test_windowed_speed_is_whole_counts_per_window_around_the_true_speed():
    p = PlantParameters()
    core = RobotPlantCore(p)
    for _ in range(400):                               # 4 s: steady at 5 V
        core.step(5.0, 5.0, 0.01)
    per_count = 2 * math.pi * p.wheel_radius / p.encoder_ppr
    true_counts = core.rim_speed_left * p.speed_window / per_count
    for _ in range(25):
        core.step(5.0, 5.0, 0.004)
        counts = core.wheel_speed_left * p.speed_window / per_count
        assert counts == pytest.approx(round(counts), abs=1e-9)
        assert round(counts) in (math.floor(true_counts), math.ceil(true_counts))


@pytest.mark.parametrize("radius, angle", [(0.5, 2.0), (-1.2, 1.0), (0.1, 6.0)],
                         ids=["left", "right", "tight"])
def test_odometry_of_arc_increments_lands_on_the_exact_circle(radius, angle):
    track = 0.289
    odometry = EncoderOdometry(0.0, 0.0, math.pi / 2, track)
    pieces = 37
    turn = math.copysign(angle, radius) / pieces
    for _ in range(pieces):
        odometry.advance((radius - track / 2) * turn, (radius + track / 2) * turn)
    total = turn * pieces
    # Facing +y from the origin, the centre of the turn is at (-radius, 0).
    assert odometry.x == pytest.approx(-radius + radius * math.cos(total), abs=1e-12)
    assert odometry.y == pytest.approx(radius * math.sin(total), abs=1e-12)
    assert odometry.heading == pytest.approx(math.pi / 2 + total, abs=1e-12)


def test_turn_radius_is_eq_31():
    assert turn_radius(0.258, 0.342, 0.40) == pytest.approx(0.2 * 0.6 / 0.084)
    assert turn_radius(0.3, 0.3, 0.289) == math.inf


def test_motor_constants_reproduce_the_datasheet_points():
    volts, no_load_speed, no_load_current, stall_current = 12.0, 630.4, 0.25, 5.0
    motor = motor_constants_from_datasheet(volts, no_load_speed, no_load_current,
                                           stall_current, 1e-3)
    # No load: V = R i + Ke w and Kt i = b w must hold at the datasheet's (w0, I0).
    matrix = np.array([[motor.resistance, motor.back_emf_constant],
                       [motor.torque_constant, -motor.viscous_friction]])
    current, speed = np.linalg.solve(matrix, [volts, 0.0])
    assert speed == pytest.approx(no_load_speed, rel=1e-12)
    assert current == pytest.approx(no_load_current, rel=1e-12)
    assert volts / motor.resistance == pytest.approx(stall_current)
    assert motor.inductance / motor.resistance == pytest.approx(1e-3)
    # The defaults are these constants, rounded.
    p = PlantParameters()
    assert p.motor_resistance == pytest.approx(motor.resistance, rel=1e-3)
    assert p.back_emf_constant == pytest.approx(motor.back_emf_constant, rel=1e-3)
    assert p.motor_viscous_friction == pytest.approx(motor.viscous_friction, rel=1e-3)


def test_default_no_load_speed_is_that_of_the_geared_motor_at_battery_voltage():
    # 6020 rpm motor at 12 V through 14:1 -> 430 rpm at the wheel; at 11.1 V it is 11.1/12 of it.
    expected = 6020 * 2 * math.pi / 60 / 14 * 11.1 / 12
    assert steady_wheel_speed(11.1, PlantParameters()) == pytest.approx(expected, rel=2e-3)


def test_invalid_parameters_are_all_reported_at_once():
    with pytest.raises(ParameterError) as error:
        PlantParameters(mass=-1.0, gear_efficiency=1.5, encoder_ppr=0).validate()
    message = str(error.value)
    assert "mass = -1.0" in message and "gear_efficiency = 1.5" in message
    assert "encoder_ppr = 0" in message


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf], ids=["nan", "inf", "-inf"])
def test_non_finite_voltage_is_refused_and_the_state_is_kept(bad):
    core = RobotPlantCore()
    core.step(5.0, 5.0, 0.1)
    before = (core.x, core.y, core.speed, core.time_ns)
    with pytest.raises(InputError, match="voltage_right"):
        core.step(5.0, bad, 0.01)
    assert (core.x, core.y, core.speed, core.time_ns) == before


def test_voltage_beyond_the_supply_is_clamped():
    clamped, reference = RobotPlantCore(), RobotPlantCore()
    for _ in range(50):
        clamped.step(30.0, -20.0, 0.01)
        reference.step(11.1, -11.1, 0.01)
    assert clamped.clamped and not reference.clamped
    assert (clamped.x, clamped.y, clamped.heading) == (reference.x, reference.y,
                                                       reference.heading)
