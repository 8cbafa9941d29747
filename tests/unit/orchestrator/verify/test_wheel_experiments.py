"""The off-nominal experiments' wheels, references and metrics against closed forms."""

import math

import numpy as np
import pytest

from components.plant import PlantParameters
from orchestrator.verify import wheel_experiments as X
from orchestrator.verify.loop_model import linear_wheel_model


@pytest.mark.parametrize("gain,tau", [(0.25, 0.2), (0.5, 2.0), (4.0, 0.5), (1.0, 1.0)])
def test_scaled_robotplant_is_the_linear_models_scaled_wheel(gain, tau):
    scaled = linear_wheel_model(X.plant_variant_parameters(gain, tau))
    expected = linear_wheel_model().scaled(gain, tau)
    # same transfer function u/V: numerator and denominator up to one common factor
    factor = expected.denominator[0] / scaled.denominator[0]
    assert np.allclose(scaled.denominator * factor, expected.denominator, rtol=1e-12)
    assert np.allclose(scaled.numerator * factor, expected.numerator, rtol=1e-12)
    assert scaled.dc_gain == pytest.approx(gain * linear_wheel_model().dc_gain, rel=1e-12)
    assert scaled.time_constants[1] == pytest.approx(
        expected.time_constants[1], rel=1e-12)


def test_scaling_only_the_resistance_is_not_the_scaled_wheel():
    # the broken input for the test above: R alone changes the time constant too
    from dataclasses import replace

    p = PlantParameters()
    wrong = linear_wheel_model(replace(p, motor_resistance=p.motor_resistance / 2))
    expected = linear_wheel_model().scaled(2.0, 1.0)
    assert abs(wrong.dc_gain - expected.dc_gain) / expected.dc_gain > 0.05


def test_judged_cells_keep_gain_tau_and_their_ratio_within_the_span():
    grid = {"gain_factors": [0.25, 0.5, 1, 2, 4], "time_constant_factors": [0.2, 0.5, 1, 2],
            "judged_factor_span": 2.0}
    assert X.judged_cells(grid) == [(0.5, 0.5), (0.5, 1.0), (1.0, 0.5), (1.0, 1.0), (1.0, 2.0),
                                    (2.0, 1.0), (2.0, 2.0)]
    assert len(X.grid_cells(grid)) == 20


def test_settling_time_is_the_first_sample_after_the_last_one_outside():
    t = np.arange(10) * 0.1
    y = np.array([0, 0.5, 0.9, 1.05, 0.97, 1.01, 0.99, 1.0, 1.0, 1.0])
    assert X.settling_after(t, y, 1.0, 0.02, 0.0) == pytest.approx(0.5)
    assert X.settling_after(t, y, 1.0, 0.06, 0.0) == pytest.approx(0.3)
    assert X.settling_after(t, np.r_[y[:-1], 2.0], 1.0, 0.02, 0.0) == math.inf
    assert X.settling_after(t, np.ones(10), 1.0, 0.02, 0.0) == 0.0


def test_slide_entries_count_with_hysteresis_and_the_worst_second():
    t = np.arange(12) * 0.25
    slip = [0, 0.03, 0.015, 0.0, 0.03, 0.0, -0.03, 0.0, 0.015, 0.0, 0.03, 0.0]
    # enter above 0.02, leave below 0.01: 0.015 while sliding does not end the slide, and
    # outside one does not start one. Entries at 0.25, 1.0, 1.5, 2.5 s; at most two in any
    # one second ([0.25, 1.25) and [1.0, 2.0)).
    assert X.slide_entries(t, slip, 0.02, 0.01) == (4, 2)


def test_creep_and_overrun_split_at_the_allowance():
    t = np.arange(0, 10.01, 0.01)
    distance = np.where(t < 2.0, 0.0, 0.001 * (t - 2.0))   # 1 mm/s from t = 2 s on
    creep, overrun = X.creep(t, distance, stopped_at=1.0, allowance=1.0, hold=5.0)
    assert creep == pytest.approx(0.005, abs=1e-12) and overrun == pytest.approx(0.0)


def test_trapezoid_reaches_exactly_zero_and_stays():
    r = X.trapezoid(0.3, 0.4, 2.0)
    end = X.trapezoid_end(0.3, 0.4, 2.0)
    assert end == pytest.approx(3.5)
    assert r(0.5) == pytest.approx(0.2) and r(1.0) == pytest.approx(0.3)
    assert r(end) == 0.0 and r(end + 3.0) == 0.0
    assert X.speed_quantum(PlantParameters()) == pytest.approx(2 * math.pi * 0.06 / 728 / 0.02)
