"""Control laws of the wheel controller against analytic results.

The paper form's laws (the PD of Eq. 46, its integral trim, the CPID); the default form's are
in test_default_form.py.
"""

import math

import numpy as np
import pytest

from components.common.errors import InputError, ParameterError
from components.control import (
    DEFAULTS, PAPER_TO_OURS, FilteredDerivative, PidLaw, WheelSpeedController, scheduled_gain,
)

TAU_MOTOR = 0.4   # first-order wheel-speed model of the tests [s]
H = 0.02


def _first_order_loop(controller, v_ref, volts_per_speed_true, steps):
    # Exact ZOH discretisation of tau dv/dt = V / g - v; the controller sees v at each step.
    decay = math.exp(-H / TAU_MOTOR)
    v = 0.0
    for _ in range(steps):
        voltage = controller.step(v_ref, v, H)
        v = decay * v + (1.0 - decay) * voltage / volts_per_speed_true
    return v


@pytest.mark.parametrize("tau,h", [(0.0, 0.01), (0.04, 0.02), (0.1, 0.005)],
                         ids=["unfiltered", "tau=2h", "tau=20h"])
def test_filtered_derivative_of_ramp_is_geometric(tau, h):
    slope = 0.7
    d = FilteredDerivative(tau)
    rho = tau / (tau + h)
    assert d.update(0.0, h) == 0.0  # no kick on the first sample
    for k in range(1, 60):
        assert d.update(slope * k * h, h) == pytest.approx(slope * (1 - rho ** k), rel=1e-12)


def test_pid_integrates_exactly_when_unsaturated():
    law = PidLaw(kp=3.0, ki=0.5, kd=1.0, integral_limit=10.0)
    for _ in range(50):
        law.output(0.1, 0.0, H, to_voltage=1.0, offset=0.0, limit=100.0)
    assert law.integral == pytest.approx(50 * H * 0.1, rel=1e-12)


def test_pid_cannot_wind_up_past_the_voltage_limit():
    ctl = WheelSpeedController(mode="pid", feedforward=False)
    limit = ctl.v_supply
    outputs = [ctl.step(0.4, 0.0, H) for _ in range(50_000)]  # 1000 s, wheel blocked
    # Conditional integration stops the integrator within one increment of the limit.
    increment = ctl.to_voltage * ctl.pid.ki * H * 1.0
    assert outputs[0] < limit and limit - increment <= outputs[-1] <= limit
    integral_volts = ctl.to_voltage * ctl.pid.ki * ctl.pid.integral
    assert integral_volts <= limit + 1e-9
    # Without anti-windup the integral alone would be ki * 1000 s * e_n * to_voltage volts:
    assert 0.5 * 1000.0 * 1.0 * ctl.to_voltage > 50 * limit
    # The error reverses: the output must leave saturation at once, not after unwinding.
    assert ctl.step(0.4, 0.45, H) < limit


def test_pid_integral_reaches_limit_only_through_integration():
    ctl = WheelSpeedController(mode="pid", feedforward=False)
    ctl.step(0.1, 0.0, H)  # far from saturation: 1.78 V * 3 * 0.25
    assert ctl.pid.integral == pytest.approx(H * 0.1 / ctl.e_range, rel=1e-12)


@pytest.mark.parametrize("delta", [0.0, 0.1, -0.2, 0.5], ids=["exact", "+10%", "-20%", "+50%"])
def test_pd_feedforward_steady_state_error_matches_analysis(delta):
    # g_ctrl = g_true (1 + delta): e_ss = -delta v_ref / (1 + (1 + delta) kp).
    # The pure PD of Eq. (46) (integral trim off).
    kp = DEFAULTS["pd_kp"]
    g_ctrl = DEFAULTS["volts_per_speed"]
    ctl = WheelSpeedController(mode="pd", form="paper", trim_ki=0.0)
    v_ref = 0.3
    v = _first_order_loop(ctl, v_ref, g_ctrl / (1.0 + delta), 2000)
    expected = -delta * v_ref / (1.0 + (1.0 + delta) * kp)
    assert v_ref - v == pytest.approx(expected, abs=1e-9)


@pytest.mark.parametrize("mode", ["pd", "fgs_pd"])
@pytest.mark.parametrize("delta", [-0.75, -0.5, 0.0, 1.0, 3.0],
                         ids=["needs-4x-voltage", "needs-2x", "exact", "needs-half",
                              "needs-quarter"])
def test_integral_trim_removes_the_steady_state_error_for_any_motor_constant(mode, delta):
    # Final value theorem: with the trim's integrator in the loop the error's final value is
    # 0 for every g_true the loop is stable with; the pure PD's would be the formula above.
    g_ctrl = DEFAULTS["volts_per_speed"]
    v_ref = 0.3
    ctl = WheelSpeedController(mode=mode, form="paper")
    assert ctl.trim_ki == DEFAULTS["trim_ki"] > 0.0
    # The slowest mode (needs-4x) decays with ~7.5 s: 400 s leave e^-50 of the start error.
    v = _first_order_loop(ctl, v_ref, g_ctrl / (1.0 + delta), 20_000)
    assert abs(v_ref - v) < 1e-6 * v_ref
    pure = _first_order_loop(WheelSpeedController(mode="pd", form="paper", trim_ki=0.0), v_ref,
                             g_ctrl / (1.0 + delta), 3000)
    kp = DEFAULTS["pd_kp"]
    assert v_ref - pure == pytest.approx(-delta * v_ref / (1.0 + (1.0 + delta) * kp), abs=1e-9)


def test_integral_trim_is_the_pid_integrator_with_the_pd_gains():
    trimmed = WheelSpeedController(mode="pd", form="paper", trim_ki=0.7, feedforward=False)
    pid = WheelSpeedController(mode="pid", pid_kp=DEFAULTS["pd_kp"], pid_kd=DEFAULTS["pd_kd"],
                               pid_ki=0.7, feedforward=False)
    rng = np.random.default_rng(3)
    for v_ref, v_meas in rng.uniform(-0.6, 0.6, size=(300, 2)):  # saturates at times
        assert trimmed.step(v_ref, v_meas, H) == pid.step(v_ref, v_meas, H)
    trimmed.reset()
    assert trimmed.trim.integral == 0.0


def test_pd_without_feedforward_keeps_proportional_error():
    ctl = WheelSpeedController(mode="pd", form="paper", feedforward=False, trim_ki=0.0)
    v_ref = 0.3
    v = _first_order_loop(ctl, v_ref, DEFAULTS["volts_per_speed"], 2000)
    assert v_ref - v == pytest.approx(v_ref / (1.0 + DEFAULTS["pd_kp"]), rel=1e-9)


@pytest.mark.parametrize("method", ["weighted", "mamdani"], ids=["weighted", "mamdani"])
def test_fgs_pd_with_matched_feedforward_has_no_steady_state_error(method):
    ctl = WheelSpeedController(mode="fgs_pd", form="paper", fuzzy_method=method)
    v = _first_order_loop(ctl, 0.342, DEFAULTS["volts_per_speed"], 20_000)  # trim tail: ~5 s
    assert abs(0.342 - v) < 1e-9
    # At rest on the reference (e = de = 0, rule Z/Z) both Kp' and Kd' are Big.
    big = 1.0 if method == "weighted" else 2.0 / 3.0
    assert ctl.kp == pytest.approx(scheduled_gain(big, 3.0, 4.0), abs=1e-6)


def test_pid_without_feedforward_removes_steady_state_error():
    ctl = WheelSpeedController(mode="pid", feedforward=False)
    v = _first_order_loop(ctl, 0.3, DEFAULTS["volts_per_speed"], 200_000 // 20 * 10)
    assert abs(0.3 - v) < 1e-6


def test_voltage_limited_to_supply():
    ctl = WheelSpeedController(mode="fgs_pd", form="paper")
    assert ctl.step(5.0, 0.0, H) == pytest.approx(11.1)
    assert ctl.step(-5.0, 0.0, H) == pytest.approx(-11.1)


def test_paper_ranges_map_to_positive_gains():
    # Paper: Kp in [-4, -3], Kd in [-2, -0.3] on y - r; here the magnitudes on r - y.
    assert PAPER_TO_OURS == {"kp_min": 3.0, "kp_max": 4.0, "kd_min": 0.3, "kd_max": 2.0}
    for name in PAPER_TO_OURS:
        assert DEFAULTS[name] == PAPER_TO_OURS[name]


@pytest.mark.parametrize("port,args", [("v_ref", (float("nan"), 0.1)),
                                       ("v_meas", (0.1, float("inf")))], ids=["v_ref", "v_meas"])
def test_non_finite_input_names_port_and_keeps_state(port, args):
    ctl = WheelSpeedController()
    ctl.step(0.2, 0.1, H)
    before = (ctl.derivative.previous, ctl.derivative.value, ctl.voltage)
    with pytest.raises(InputError, match=port):
        ctl.step(*args, H)
    assert (ctl.derivative.previous, ctl.derivative.value, ctl.voltage) == before


@pytest.mark.parametrize("kwargs,words", [
    ({"mode": "fuzzy"}, ["mode", "'fuzzy'", "fgs_pd", "pid", "pd"]),
    ({"kp_min": -4.0, "kp_max": -3.0}, ["kp_min", "-4.0", "kp_max"]),
    ({"v_supply": float("nan")}, ["v_supply", "nan"]),
    ({"gain": 1.0}, ["gain", "kp_min"]),
], ids=["mode", "negative-paper-gains", "nan-supply", "unknown"])
def test_bad_parameters_are_named(kwargs, words):
    with pytest.raises(ParameterError) as info:
        WheelSpeedController(**kwargs)
    for word in words:
        assert word in str(info.value)


def test_reset_restores_construction_state():
    fresh = WheelSpeedController(mode="pid")
    used = WheelSpeedController(mode="pid")
    for k in range(20):
        used.step(0.3, 0.01 * k, H)
    used.reset()
    for k in range(5):
        assert used.step(0.2, 0.02 * k, H) == fresh.step(0.2, 0.02 * k, H)
    assert np.isfinite(used.voltage)


def _sagging_supply_loop(measured, sag=1.0, v_ref=0.3):
    """Exact first-order wheel whose driver clips at a supply that sags from 5 s to 10 s."""
    controller = WheelSpeedController(form="paper")   # fgs_pd with the paper form's trim
    g, nominal = DEFAULTS["volts_per_speed"], DEFAULTS["v_supply"]
    decay = math.exp(-H / TAU_MOTOR)
    v, speeds, integrals = 0.0, [], []
    for k in range(int(20.0 / H)):
        supply = sag if 5.0 <= k * H < 10.0 else nominal
        voltage = controller.step(v_ref, v, H, supply if measured else None)
        applied = min(supply, max(-supply, voltage))   # the driver cannot give more
        v = decay * v + (1.0 - decay) * applied / g
        speeds.append(v)
        integrals.append(controller.trim.integral)
    return np.array(speeds), np.array(integrals)


def test_paper_trim_does_not_wind_up_while_a_measured_supply_sag_saturates_the_driver():
    speeds, integrals = _sagging_supply_loop(measured=True)
    sag_start, sag_end = int(5.0 / H), int(10.0 / H)
    # analytic reference: held at 1 V from the step before the sag, the wheel decays to
    # 1 V / g (0.225 m/s) as v_k = v_inf + (v_0 - v_inf) exp(-k H / tau)
    v_inf, v_0 = 1.0 / DEFAULTS["volts_per_speed"], speeds[sag_start - 1]
    steps = sag_end - sag_start
    assert speeds[sag_end - 1] == pytest.approx(
        v_inf + (v_0 - v_inf) * math.exp(-steps * H / TAU_MOTOR), rel=1e-9)
    # conditional integration at the measured limit: the integral stops when the driver
    # saturates and stays put for the rest of the sag
    saturated = integrals[sag_start + 1:sag_end]
    assert np.ptp(saturated) == 0.0
    # after the sag, no more overshoot than the start-up from rest at 0 s
    assert speeds[sag_end:].max() <= max(speeds[:sag_start].max(), 0.3 * 1.01)


def test_without_the_supply_measurement_the_paper_trim_winds_up_and_overshoots():
    # the broken input: the controller limits at its nominal 11.1 V, never saturates, and
    # integrates the sag's whole speed deficit: with 1 V applied throughout, the error is
    # e_k = (v_0 - v_inf)(1 - d^k), d = exp(-H / tau), summed over the sag's steps
    speeds, integrals = _sagging_supply_loop(measured=False)
    sag_start, sag_end = int(5.0 / H), int(10.0 / H)
    v_inf, v_0 = 1.0 / DEFAULTS["volts_per_speed"], speeds[sag_start - 1]
    decay, steps = math.exp(-H / TAU_MOTOR), sag_end - sag_start
    expected = sum((0.3 - v_inf - (v_0 - v_inf) * decay ** k) * H for k in range(steps))
    assert (integrals[sag_end - 1] - integrals[sag_start - 1]
            == pytest.approx(expected / DEFAULTS["e_range"], rel=1e-9))
    assert speeds[sag_end:].max() > 0.3 * 1.05


def test_supply_input_is_checked_and_limits_the_output():
    controller = WheelSpeedController()
    assert controller.step(0.3, 0.0, H, 2.0) == 2.0
    with pytest.raises(InputError, match="supply_voltage"):
        controller.step(0.3, 0.0, H, -1.0)
    with pytest.raises(InputError, match="supply_voltage"):
        controller.step(0.3, 0.0, H, math.nan)
