"""The sampled wheel-loop model of the verification report against independent references."""

import argparse

import control
import numpy as np
import pytest

from components.control import DEFAULTS
from components.plant import PlantParameters, steady_wheel_speed
from orchestrator.verify import (
    WheelLoopModel, analyse_gains, continuous_gain_bound, controller_cross_check,
    linear_wheel_model, register_cli, stability_boundary,
)


@pytest.fixture(scope="module")
def model():
    return WheelLoopModel()


def test_dc_gain_equals_the_plant_cores_steady_state(model):
    p = PlantParameters()
    per_volt = steady_wheel_speed(1.0, p) * p.wheel_radius  # rim speed per volt
    linear = linear_wheel_model(p)
    assert linear.dc_gain == pytest.approx(per_volt, rel=1e-12)
    assert control.dcgain(linear.transfer_function()) == pytest.approx(per_volt, rel=1e-12)
    # Sampling and window averaging keep the DC gain.
    for num, den in ((model.rim_num, model.rim_den), (model.meas_num, model.meas_den)):
        assert np.polyval(num, 1.0) / np.polyval(den, 1.0) == pytest.approx(per_volt, rel=1e-9)
    # ... and the controller's feedforward constant is its inverse (zero steady-state error).
    assert DEFAULTS["volts_per_speed"] * per_volt == pytest.approx(1.0, rel=1e-12)


def test_documented_linear_model_figures():
    # docs/plant.md: M_eff = 2.436 kg, K_f = 3.375 N/A, K_e = 4.219 V s/m, tau = 0.39 s.
    linear = linear_wheel_model()
    assert linear.effective_mass == pytest.approx(2.436, abs=1e-3)
    assert linear.force_per_current == pytest.approx(3.375, abs=1e-3)
    assert linear.emf_per_speed == pytest.approx(4.219, abs=1e-3)
    electrical, mechanical = linear.time_constants
    assert mechanical == pytest.approx(0.39, abs=0.005)
    assert electrical == pytest.approx(1.0e-3, rel=0.01)


def test_rim_sampling_matches_python_control_zoh(model):
    sampled = control.sample_system(model.linear.transfer_function(), model.period, "zoh")
    ours = control.tf(model.rim_num, model.rim_den, model.period)
    w = np.linspace(0.1, np.pi / model.period * 0.99, 50)
    np.testing.assert_allclose(ours(np.exp(1j * w * model.period)),
                               sampled(np.exp(1j * w * model.period)), rtol=1e-8)


def test_measured_speed_is_the_window_average_of_the_rim_speed(model):
    # Independent reference: integrate the continuous step response numerically.
    fine = np.linspace(0.0, 0.4, 40001)
    rim = control.step_response(model.linear.transfer_function(), fine).outputs
    steps = int(round(0.4 / model.period))
    per = (fine.size - 1) // steps
    windows = [slice(k * per, (k + 1) * per + 1) for k in range(steps)]
    averages = [0.0] + [np.trapezoid(rim[w], fine[w]) / model.period for w in windows]
    times = np.arange(steps + 1) * model.period
    measured = control.step_response(control.tf(model.meas_num, model.meas_den, model.period),
                                     times).outputs
    np.testing.assert_allclose(measured, averages, atol=1e-8)


@pytest.mark.parametrize("kd,ki", [(0.3, 0.0), (2.0, 0.0), (1.0, 0.5)],
                         ids=["kd_min", "kd_max", "pid"])
def test_routh_boundary_equals_numeric_roots(model, kd, ki):
    edge = stability_boundary(model, kd, ki, samples=300)
    assert edge["kp_routh"] is not None and edge["kp_roots"] is not None
    assert edge["kp_routh"] == pytest.approx(edge["kp_roots"], rel=1e-6)
    # Independent of both searches: just inside the edge stable, just outside not.
    base, per_kp = model.characteristic_in_kp(kd, ki)
    for factor, stable in ((1 - 1e-4, True), (1 + 1e-4, False)):
        roots = np.roots(np.polyadd(base, factor * edge["kp_roots"] * per_kp))
        assert (np.max(np.abs(roots)) < 1.0) == stable


@pytest.mark.parametrize("kp,kd,stable", [(3.5, 1.15, True), (4.0, 2.0, True), (60.0, 1.0, False),
                                          (3.0, 60.0, False)],
                         ids=["paper-middle", "paper-corner", "kp-too-high", "kd-too-high"])
def test_known_gains_are_classified_right(model, kp, kd, stable):
    result = analyse_gains(model, kp, kd)
    assert result.stable_routh == stable
    assert result.stable_roots == stable


def test_margins_agree_with_the_boundary(model):
    # The gain margin scales the whole controller; with kd scaled too the edge must match.
    result = analyse_gains(model, 3.0, 0.3)
    scaled = model.characteristic_polynomial(3.0 * result.gain_margin, 0.3 * result.gain_margin)
    assert np.max(np.abs(np.roots(scaled))) == pytest.approx(1.0, abs=1e-6)


def test_transfer_function_is_the_implemented_controller(model):
    # The real WheelSpeedController on the sampled plant gives the TF's step response.
    assert controller_cross_check(model, 3.5, 1.15) < 1e-12
    assert controller_cross_check(model, 3.0, 1.0, 0.5) < 1e-12


def test_continuous_pd_has_no_finite_routh_bound(model):
    bound = continuous_gain_bound(model, kd=1.0, kp_max=1e5)
    assert bound["intervals"] == [(0.0, 1e5)]
    assert all(v > 0 for v in bound["routh_first_column_at_kp_max"])


def test_jacobi_delay_lowers_the_bound(model):
    jacobi = WheelLoopModel(extra_delay=1)
    assert (stability_boundary(jacobi, 1.0, samples=300)["kp_routh"]
            < stability_boundary(model, 1.0, samples=300)["kp_routh"])


def test_register_cli_adds_verify_with_default_out_dir():
    parser = argparse.ArgumentParser(prog="sonotrack")
    register_cli(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["verify"])
    assert args.out == "runs/verify" and args.grid == 11 and callable(args.func)
    assert not args.strict and parser.parse_args(["verify", "--strict"]).strict
    assert parser.parse_args(["verify", "--out", "x"]).out == "x"


@pytest.mark.parametrize("kp,kd", [(4.0, 0.3), (3.5, 1.15)], ids=["corner", "middle"])
def test_incremental_form_poles_match_a_simulation_of_the_incremental_law(model, kp, kd):
    # V_k = V_k-1 + g e_range (kp e_n + kd de_n), run on the sampled plant with the
    # window-averaged measurement: the error's envelope grows or decays as |z|^k.
    from components.control import FilteredDerivative
    from orchestrator.verify.analysis import incremental_form
    from orchestrator.verify.loop_model import zoh_with_average

    result = incremental_form(model, kp, kd)
    ad, bd, c = model.discrete
    _, _, average_c, average_d = zoh_with_average(*model.linear.state_space(), model.period)
    derivative = FilteredDerivative(model.derivative_time_constant)
    state, voltage, measured, errors = np.zeros((2, 1)), 0.0, 0.0, []
    for _ in range(1500):
        error = 0.1 - measured
        rate = derivative.update(error, model.period)
        voltage += model.volts_per_speed * model.e_range * (
            kp * error / model.e_range + kd * rate / model.de_range)
        measured = (average_c @ state).item() + average_d * voltage
        state = ad @ state + bd * voltage
        errors.append(abs(error))
    late, early = max(errors[1000:1500]), max(errors[500:1000])
    assert (late / early) ** (1 / 500) == pytest.approx(result["spectral_radius"], abs=2e-4)


def test_step_figures_use_the_exact_final_value_not_the_last_sample(model):
    # With the integral trim the slow integrator mode still moves at the end of the 1.5 s
    # window: overshoot must be measured against T(1) = 1, found here from the samples of a
    # 200 s response (independent of the final value theorem).
    import control

    result = analyse_gains(model, 3.0, 0.3, 0.5)
    times = np.arange(10001) * model.period
    long = control.step_response(model.closed_loop_tf(3.0, 0.3, 0.5), times).outputs
    assert long[-1] == pytest.approx(1.0, abs=1e-6)
    peak = np.max(long[: int(1.5 / model.period) + 1])
    assert result.overshoot_pct == pytest.approx(100 * (peak - 1.0), abs=1e-6)
    assert result.overshoot_pct > 1.0  # the last-sample reading said 0.08 %


@pytest.mark.parametrize("kp,kd,ki", [(3.0, 0.3, 0.0), (4.0, 2.0, 0.0), (3.0, 1.0, 0.5)],
                         ids=["pd-min", "pd-max", "pid"])
def test_step_figures_equal_python_controls_step_info(model, kp, kd, ki):
    import control

    from orchestrator.verify.analysis import final_value, step_figures

    times = np.arange(76) * model.period
    tf = model.closed_loop_tf(kp, kd, ki)
    y = control.step_response(tf, times).outputs
    info = control.step_info(y, times, final_output=final_value(tf), SettlingTimeThreshold=0.05)
    assert step_figures(y, times, final_value(tf)) == pytest.approx(
        (info["Overshoot"], info["RiseTime"], info["SettlingTime"]), abs=1e-12)
    # Never settling inside the window is inf, not the window's end.
    assert step_figures(y[:5], times[:5], final_value(tf))[2] == float("inf")


def test_filter_through_is_the_tfs_response_and_plain_lfilter_is_early():
    import control
    from scipy.signal import lfilter

    from orchestrator.verify.analysis import filter_through

    model = WheelLoopModel()
    tf = model.closed_loop_tf(3.5, 1.15, 0.5)
    times = np.arange(60) * model.period
    expected = control.step_response(tf, times).outputs
    assert np.max(np.abs(filter_through(tf, np.ones(60)) - expected)) < 1e-10
    # the broken input: lfilter on the unpadded coefficients runs ahead of the TF
    early = lfilter(tf.num[0][0], tf.den[0][0], np.ones(60))
    assert np.max(np.abs(early - expected)) > 1e-3


def test_python_controls_fallback_notice_does_not_reach_the_user(model, monkeypatch):
    # python-control's "best" margins fall back from polynomial roots to the frequency
    # response on the observer's loops and print a UserWarning (with a source line) into
    # `sonotrack verify`'s output at every call; that notice is dropped, nothing else is
    import warnings

    original = control.stability_margins

    def noisy(*args, **kwargs):
        warnings.warn("stability_margins: Falling back to 'frd' method because of chance of "
                      "numerical inaccuracy in 'poly' method.", UserWarning, stacklevel=2)
        return original(*args, **kwargs)

    quiet = analyse_gains(model, 3.0, 0.3)
    monkeypatch.setattr(control, "stability_margins", noisy)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = analyse_gains(model, 3.0, 0.3)
    assert [str(w.message) for w in caught] == []
    assert (result.gain_margin, result.phase_margin_deg) == (quiet.gain_margin,
                                                             quiet.phase_margin_deg)

    def other(*args, **kwargs):
        warnings.warn("some other notice", UserWarning, stacklevel=2)
        return original(*args, **kwargs)

    monkeypatch.setattr(control, "stability_margins", other)
    with pytest.warns(UserWarning, match="some other notice"):
        analyse_gains(model, 3.0, 0.3)
