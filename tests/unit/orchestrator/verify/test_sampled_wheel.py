"""The simulated discrete-time loop against the transfer function and closed forms."""

import math
from dataclasses import replace

import control
import numpy as np
import pytest

from components.control import DEFAULTS, WheelSpeedController
from orchestrator.verify.designs import design_settings, loop_gains, loop_model
from orchestrator.verify.loop_model import WheelLoopModel, linear_wheel_model
from orchestrator.verify.sampled_wheel import SampledWheel, run_loop, stall_force

T = 0.02


@pytest.mark.parametrize("design", ["default", "paper"])
@pytest.mark.parametrize("cell", [(1.0, 1.0), (0.5, 2.0), (2.0, 0.5)],
                         ids=["nominal", "weak-slow", "strong-fast"])
def test_loop_equals_the_closed_loop_transfer_function(design, cell):
    # frozen gains, no clipping: the simulation is the TF at the samples (one sample at zero
    # reference first, as the TF assumes a derivative of zero before the step), to round-off
    # (with the speed observer the loop is of ninth order, its triple pole ill-conditioned:
    # 1.3e-11 measured)
    settings = dict(design_settings(dict(DEFAULTS), design), mode="pd", v_supply=1e9)
    model = loop_model(replace(WheelLoopModel(), gain_factor=cell[0],
                               time_constant_factor=cell[1]), settings)
    wheel = SampledWheel(model.linear, T, v_supply=1e9)
    trace = run_loop(WheelSpeedController(**settings), wheel,
                     lambda t: 0.05 if t > 0.01 else 0.0, 2.0)
    tf = model.closed_loop_tf(*loop_gains(settings, settings["pd_kp"], settings["pd_kd"]))
    expected = 0.05 * control.step_response(tf, trace.t[:-1]).outputs
    assert np.max(np.abs(trace.rim_speed[1:] - expected)) < 1e-10


@pytest.mark.parametrize("broken", ["paper-mapping", "no-observer"])
def test_a_wrong_model_of_the_law_misses_the_transfer_function(broken):
    # the broken inputs for the test above: the default form read as the paper's law, or
    # its loop model without the speed observer (on a wheel unlike the nominal one: on that
    # one the feedback sees no error and any gains give the same response)
    settings = dict(DEFAULTS, mode="pd", v_supply=1e9)
    model = loop_model(replace(WheelLoopModel(), gain_factor=0.5, time_constant_factor=2.0),
                       settings)
    trace = run_loop(WheelSpeedController(**settings), SampledWheel(model.linear, T, v_supply=1e9),
                     lambda t: 0.05 if t > 0.01 else 0.0, 2.0)
    if broken == "paper-mapping":
        tf = model.closed_loop_tf(settings["pd_kp"], settings["pd_kd"], settings["integral_gain"])
    else:
        tf = replace(model, speed_observer=0.0).closed_loop_tf(
            *loop_gains(settings, settings["pd_kp"], settings["pd_kd"]))
    expected = 0.05 * control.step_response(tf, trace.t[:-1]).outputs
    assert np.max(np.abs(trace.rim_speed[1:] - expected)) > 1e-4


def test_steady_speed_under_voltage_and_load_is_the_motor_equation():
    # 0 = K_f i - B u - F, 0 = G V - R i - K_e u  =>  u = (G K_f V / R - F) / (B + K_f K_e / R)
    linear = linear_wheel_model().scaled(0.5, 2.0)
    wheel = SampledWheel(linear, T)
    force = 0.2 * stall_force(linear, 11.1)
    for _ in range(2000):
        wheel.step(6.0, force)
    R, kf, ke, B = linear.resistance, linear.force_per_current, linear.emf_per_speed, \
        linear.damping
    expected = (0.5 * kf * 6.0 / R - force) / (B + kf * ke / R)
    assert wheel.rim_speed == pytest.approx(expected, rel=1e-9)
    assert wheel.measured_speed == pytest.approx(expected, rel=1e-9)
    assert force == pytest.approx(0.2 * 0.5 * kf * 11.1 / R, rel=1e-15)


def test_voltage_is_clipped_to_the_supply():
    linear = linear_wheel_model()
    clipped, exact = SampledWheel(linear, T, v_supply=11.1), SampledWheel(linear, T, v_supply=1e9)
    for _ in range(500):
        clipped.step(50.0)
        exact.step(11.1)
    assert clipped.rim_speed == exact.rim_speed


def test_encoder_counts_the_floor_of_the_travel():
    linear = linear_wheel_model()
    wheel = SampledWheel(linear, T, counts_per_revolution=728)
    count = 2 * math.pi * 0.06 / 728
    total = 0.0
    for _ in range(300):
        total += wheel.step(2.0) * T
        # the summed window speeds are the count of the whole travel, to one count
        assert math.floor(wheel.distance / count) * count == pytest.approx(total, abs=1e-12)
    quantum = count / T
    assert wheel.measured_speed / quantum == pytest.approx(round(wheel.measured_speed / quantum),
                                                           abs=1e-9)
