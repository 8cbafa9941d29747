"""The largest stable plant-DC-gain factor against independent references.

References: numeric roots of the characteristic polynomial of a loop model rebuilt from
scratch (ZOH, encoder window) at the found factor -+ 1e-6; python-control's gain
margin (at time constant x1 a plant-gain factor is the whole controller scaled); and two
closed forms derived here for a first-order wheel under pure P control.
"""

import math
from dataclasses import replace

import numpy as np
import pytest

from components.control import DEFAULTS
from components.plant import PlantParameters
from orchestrator.verify import WheelLoopModel, analyse_gains
from orchestrator.verify import measure
from orchestrator.verify.robustness import (
    GAIN_FACTOR_SEARCH, largest_stable_gain_factor, plant_gain_edges,
)

SETS = measure.gain_sets(dict(DEFAULTS))
GAIN_SETS = [(name, *g) for name, sets in SETS.items() for g in sets]
IDS = [f"{name}-kp{kp:g}-kd{kd:g}" for name, kp, kd, _ in GAIN_SETS]


@pytest.fixture(scope="module")
def model():
    return WheelLoopModel()


def _radius(model, gain_factor, tau, kp, kd, ki):
    # A model rebuilt from the plant parameters at this factor: not base + G per_gain.
    wheel = replace(model, gain_factor=gain_factor, time_constant_factor=tau)
    return float(np.max(np.abs(np.roots(wheel.characteristic_polynomial(kp, kd, ki)))))


def test_characteristic_is_affine_in_the_gain_factor(model):
    base, per_gain = model.characteristic_in_gain_factor(4.0, 2.0, 0.5)
    for g in (0.25, 2.0, 4.0):
        direct = replace(model, gain_factor=g).characteristic_polynomial(4.0, 2.0, 0.5)
        np.testing.assert_allclose(base + g * per_gain, direct, rtol=1e-12, atol=1e-14)
    # Relative to RobotPlant, whatever the model's own factor.
    shifted = replace(model, gain_factor=3.0).characteristic_in_gain_factor(4.0, 2.0, 0.5)
    np.testing.assert_allclose(shifted[1], per_gain, rtol=1e-9)


@pytest.mark.parametrize("tau", [0.5, 1.0, 2.0])
@pytest.mark.parametrize("name,kp,kd,ki", GAIN_SETS, ids=IDS)
def test_edge_is_where_the_roots_leave_the_unit_circle(model, name, kp, kd, ki, tau):
    edge = largest_stable_gain_factor(model, kp, kd, ki, tau)
    assert edge["nominal_stable"] and edge["upper_found"]
    g = edge["upper"]
    assert _radius(model, g - 1e-6, tau, kp, kd, ki) < 1.0
    assert _radius(model, g + 1e-6, tau, kp, kd, ki) > 1.0
    assert edge["upper_relative_difference"] < 1e-9  # Routh (w-plane) agrees
    # No lower edge: the loop only gets slower as the plant's gain falls.
    assert not edge["lower_found"] and edge["lower"] == pytest.approx(GAIN_FACTOR_SEARCH[0])


@pytest.mark.parametrize("name,kp,kd,ki", GAIN_SETS, ids=IDS)
def test_edge_at_nominal_time_constant_is_the_gain_margin(model, name, kp, kd, ki):
    edge = largest_stable_gain_factor(model, kp, kd, ki, 1.0)
    assert edge["upper"] == pytest.approx(analyse_gains(model, kp, kd, ki).gain_margin,
                                          rel=1e-6)


def test_no_unstable_window_below_the_edge_on_a_16x_finer_scan(model):
    kp, kd, ki = SETS["fgs_pd"][3]
    for tau in (0.5, 2.0):
        edge = largest_stable_gain_factor(model, kp, kd, ki, tau)["upper"]
        base, per_gain = replace(model, time_constant_factor=tau).characteristic_in_gain_factor(
            kp, kd, ki)
        factors = 2.0 ** np.arange(math.log2(GAIN_FACTOR_SEARCH[0]), math.log2(edge), 1 / 128)
        radii = [np.max(np.abs(np.roots(base + g * per_gain))) for g in factors]
        assert max(radii) < 1.0


def test_first_order_wheel_under_p_control_edge_in_closed_form():
    # v_k+1 = a v_k + K (1 - a) u_k with a = exp(-T/tau) (ZOH), u_k = -G k v_k: the one pole
    # z = a - G k (1 - a) leaves the unit circle at z = -1, G = (1 + a) / (k (1 - a))
    # = coth(T / (2 tau)) / k.
    T, tau, k = 0.02, 0.39, 4.0
    a = math.exp(-T / tau)
    edges = plant_gain_edges([1.0, -a], [0.0, k * (1 - a)])
    assert edges["upper"] == pytest.approx(1 / (k * math.tanh(T / (2 * tau))), rel=1e-12)
    assert edges["upper_routh"] == pytest.approx(edges["upper"], rel=1e-11)
    assert edges["upper_crossing"] == pytest.approx(math.pi)
    # A loop unstable at the nominal factor has no range.
    assert plant_gain_edges([1.0, -a], [0.0, 100.0 * k * (1 - a)])["upper"] is None


def test_loop_model_on_a_first_order_wheel_matches_the_jury_closed_form():
    """The real loop model with the armature inductance made negligible (1e-8 H) and kd = ki = 0.

    The wheel is then first order: tau = M R / (R B + K_f K_e), K0 = K_f / (R B + K_f K_e).
    With a = exp(-T/tau) the ZOH state is x_k+1 = a x_k + K0 (1 - a) u_k; the encoder reports
    the window average over [t_k, t_k+1], c1 x_k + K0 (1 - c1) u_k with c1 = (tau/T)(1 - a),
    one sample late. P control u = -G k y, k = g kp. Characteristic polynomial:
    z^2 + (G q1 - a) z + G q0, q1 = k K0 (1 - c1), q0 = k K0 (c1 - a). Jury: |G q0| < 1,
    1 - a + G (q1 + q0) > 0 (always), 1 + a - G (q1 - q0) > 0; here c1 > a, so the edge is
    G = min(1 / q0, (1 + a) / (q1 - q0)), and at G = 1/q0 the pair crosses at
    cos(theta) = (a - G q1) / 2.
    """
    model = WheelLoopModel(plant=PlantParameters(motor_inductance=1e-8))
    lin, T, kp = model.linear, model.period, 4.0
    denominator = lin.resistance * lin.damping + lin.force_per_current * lin.emf_per_speed
    tau = lin.effective_mass * lin.resistance / denominator
    k0 = lin.force_per_current / denominator
    a = math.exp(-T / tau)
    c1 = tau / T * (1 - a)
    k = model.volts_per_speed * kp * k0
    q1, q0 = k * (1 - c1), k * (c1 - a)
    assert c1 > a
    expected = min(1 / q0, (1 + a) / (q1 - q0))
    edge = largest_stable_gain_factor(model, kp, 0.0, 0.0, 1.0)
    # What remains is the inductance's own effect, O(L / (R tau)) ~ 1e-7 relative.
    assert edge["upper"] == pytest.approx(expected, rel=2e-6)
    theta = math.acos((a - expected * q1) / 2)
    assert edge["crossing_hz"] == pytest.approx(theta / (2 * math.pi * T), rel=1e-5)
