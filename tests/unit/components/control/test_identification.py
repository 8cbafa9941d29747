"""Commissioning's step fit against the analytic response of a first-order wheel."""

import math

import pytest

from components.common.errors import InputError
from components.control.identification import fit_step_response

H = 0.02


def _positions(volts_per_speed, tau, voltage, steps, delay=0.0):
    times = [k * H for k in range(1, steps + 1)]
    positions = []
    for t in times:
        s = max(t - delay, 0.0)
        positions.append(voltage / volts_per_speed * (s - tau * -math.expm1(-s / tau)))
    return times, positions


@pytest.mark.parametrize("g, tau", [(4.44, 0.39), (1.11, 0.078), (17.8, 0.78)])
def test_exact_positions_give_the_constants_back(g, tau):
    fit = fit_step_response(*_positions(g, tau, 1.0, 75), 1.0)
    assert fit.volts_per_speed == pytest.approx(g, rel=1e-6)
    assert fit.time_constant == pytest.approx(tau, rel=1e-6)
    assert fit.rms_residual < 1e-9
    assert fit.controller_parameters() == {"volts_per_speed": fit.volts_per_speed,
                                           "acceleration_feedforward": fit.time_constant}


def test_whole_counts_cost_under_a_percent():
    # RobotPlant's encoder: 0.518 mm per count, reported as floor
    quantum = 2.0 * math.pi * 0.06 / 728
    times, positions = _positions(4.44, 0.39, 1.0, 75)
    counted = [math.floor(x / quantum) * quantum for x in positions]
    fit = fit_step_response(times, counted, 1.0)
    assert fit.volts_per_speed == pytest.approx(4.44, rel=0.01)
    assert fit.time_constant == pytest.approx(0.39, rel=0.02)
    assert fit.offset == pytest.approx(-quantum / 2, abs=quantum / 2)
    # broken input: a voltage twice the one applied halves the gain found
    assert fit_step_response(times, counted, 2.0).volts_per_speed == pytest.approx(
        2 * fit.volts_per_speed, rel=1e-9)


@pytest.mark.parametrize("times, positions, voltage, match", [
    ([0.02, 0.04], [0.0, 1e-3], 1.0, "need at least 4"),
    ([0.02, 0.04, 0.04, 0.06], [0.0, 1e-3, 2e-3, 3e-3], 1.0, "increasing"),
    ([0.02, 0.04, 0.06, 0.08], [0.0, 0.0, 0.0, 0.0], 1.0, "did not move"),
    ([0.02, 0.04, 0.06, 0.08], [0.0, 1e-3, 2e-3, 3e-3], 0.0, "nonzero"),
    ([0.02, 0.04, 0.06, 0.08], [0.0, -1e-3, -2e-3, -3e-3], 1.0, "against the voltage"),
])
def test_bad_experiments_are_refused_with_the_reason(times, positions, voltage, match):
    with pytest.raises(InputError, match=match):
        fit_step_response(times, positions, voltage)
