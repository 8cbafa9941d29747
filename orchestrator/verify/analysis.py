"""Analyses of the sampled wheel loop: poles, margins, steps, stability edges, Routh findings.

Each function takes a :class:`.loop_model.WheelLoopModel` and returns plain figures; the
verdicts are made in :mod:`.checks`, the plots in :mod:`.figures`.
"""

import math
import warnings
from dataclasses import dataclass

import numpy as np

from components.control.routh import is_hurwitz, is_schur, routh_table, stable_gain_intervals

from .loop_model import zoh_with_average

__all__ = ["GainAnalysis", "analyse_gains", "stability_boundary", "continuous_gain_bound",
           "controller_cross_check", "kp_edge", "routh_bounds", "spectral_radii",
           "incremental_form", "final_value", "filter_through", "step_figures",
           "KP_SEARCH_MAX"]

# Beyond this kp the search for the stability edge stops. With the defaults the edge is near
# kp = 35, ten times the paper's range; 500 leaves room for other plants and periods.
KP_SEARCH_MAX = 500.0


@dataclass
class GainAnalysis:
    """Figures of the sampled loop at one gain set."""

    kp: float
    kd: float
    ki: float
    stable_routh: bool
    stable_roots: bool
    spectral_radius: float
    poles: list
    gain_margin: float
    phase_margin_deg: float
    gain_crossover_rad_s: float
    phase_crossover_rad_s: float
    overshoot_pct: float
    rise_time_s: float
    settling_time_s: float
    peak_voltage_per_speed: float
    linear_step_limit_m_s: float


def analyse_gains(model, kp, kd, ki=0.0, duration=1.5, settling_threshold=0.05):
    """Poles, margins and step figures of the sampled loop at one gain set.

    Parameters
    ----------
    model : WheelLoopModel
    kp, kd, ki : float
        Controller gains (``ki`` in 1/s; 0 for PD).
    duration : float, optional
        Length of the step response [s].
    settling_threshold : float, optional
        Settling band as a fraction of the final value (0.05, as in docs/control.md).

    Returns
    -------
    GainAnalysis
        Margins are those of ``C H`` (python-control ``stability_margins``; gain margin as a
        factor, inf when the phase never crosses -180 deg). Step figures are for the true
        rim speed after a reference step (``step_info`` against the exact final value); ``peak_voltage_per_speed`` is the
        largest voltage per m/s of reference step, and ``linear_step_limit_m_s`` the largest
        step from rest that stays below ``v_supply`` (the analysis is linear below it).
    """
    import control

    characteristic = model.characteristic_polynomial(kp, kd, ki)
    poles = np.roots(characteristic)
    radius = float(np.max(np.abs(poles)))
    loop = model.loop_tf(kp, kd, ki)
    with warnings.catch_warnings():
        # python-control's "best" method falls back from polynomial roots to the frequency
        # response where the roots are ill-conditioned (the observer's high-order loops) and
        # says so on stderr at every call; the fallback is the accurate answer, not a fault
        warnings.filterwarnings("ignore", message="stability_margins: Falling back to 'frd'",
                                category=UserWarning)
        gm, pm, _, wpc, wgc, _ = control.stability_margins(loop)
    steps = int(round(duration / model.period))
    times = np.arange(steps + 1) * model.period
    rim_tf = model.closed_loop_tf(kp, kd, ki, "rim")
    rim = control.step_response(rim_tf, times)
    voltage = control.step_response(model.closed_loop_tf(kp, kd, ki, "voltage"), times)
    stable = radius < 1.0
    if stable:
        # Judge against the true final value (final value theorem), not the last sample: with
        # an integrator the slow mode is still moving at the end of the window.
        overshoot, rise, settle = step_figures(rim.outputs, times, final_value(rim_tf),
                                               settling_threshold)
    else:
        overshoot = rise = settle = float("nan")
    peak = float(np.max(np.abs(voltage.outputs)))
    return GainAnalysis(
        kp=float(kp), kd=float(kd), ki=float(ki),
        stable_routh=bool(is_schur(characteristic)), stable_roots=stable,
        spectral_radius=radius,
        poles=[[float(p.real), float(p.imag)] for p in poles],
        gain_margin=float(gm), phase_margin_deg=float(pm),
        gain_crossover_rad_s=float(wgc), phase_crossover_rad_s=float(wpc),
        overshoot_pct=float(overshoot), rise_time_s=float(rise), settling_time_s=float(settle),
        peak_voltage_per_speed=peak,
        linear_step_limit_m_s=float(model.plant.v_supply / peak) if peak > 0 else float("inf"),
    )


def spectral_radii(polynomials):
    """Largest root magnitude of each polynomial (rows, highest power first), vectorised.

    The roots are the eigenvalues of the companion matrices, all taken in one call.

    Parameters
    ----------
    polynomials : array_like, shape (m, n + 1)
        Leading coefficients non-zero.

    Returns
    -------
    numpy.ndarray, shape (m,)
    """
    p = np.atleast_2d(np.asarray(polynomials, dtype=float))
    n = p.shape[1] - 1
    companion = np.zeros((p.shape[0], n, n))
    companion[:, 0, :] = -p[:, 1:] / p[:, :1]
    companion[:, np.arange(1, n), np.arange(n - 1)] = 1.0
    return np.max(np.abs(np.linalg.eigvals(companion)), axis=1)


def step_figures(response, times, final, threshold=0.05):
    """Overshoot [%], 10-90 % rise time [s] and settling time [s] of a sampled step response.

    The same definitions as python-control's ``step_info``, against a given ``final`` value
    (its ``step_info`` fails when the response never reaches 90 % in the window). A time that
    is never reached is ``inf``; settling is the first sample after which the response stays
    within ``threshold * |final|``.
    """
    y = np.asarray(response, dtype=float)
    t = np.asarray(times, dtype=float)
    overshoot = max(0.0, 100.0 * (np.max(y) - final) / abs(final)) if final else math.nan

    def first(level):
        index = np.flatnonzero(y >= level) if final > 0 else np.flatnonzero(y <= level)
        return t[index[0]] if index.size else math.inf

    rise = first(0.9 * final) - first(0.1 * final)
    outside = np.flatnonzero(np.abs(y - final) > threshold * abs(final))
    if outside.size == 0:
        settle = float(t[0])
    elif outside[-1] + 1 < t.size:
        settle = float(t[outside[-1] + 1])
    else:
        settle = math.inf
    return float(overshoot), float(rise), settle


def filter_through(tf, inputs):
    """A discrete TF's response to the input sequence ``inputs`` (one value per sample).

    ``scipy.signal.lfilter`` reads both coefficient lists as powers of ``z^-1`` from
    ``z^0``, so the numerator is first padded to the denominator's length: unpadded, a TF of
    relative degree d would come out d samples early.
    """
    from scipy.signal import lfilter

    num, den = np.asarray(tf.num[0][0], dtype=float), np.asarray(tf.den[0][0], dtype=float)
    num = np.concatenate([np.zeros(den.size - num.size), num])
    return lfilter(num, den, np.asarray(inputs, dtype=float))


def final_value(tf):
    """``T(1)``: the final value of a stable discrete TF's unit step (final value theorem)."""
    num, den = np.asarray(tf.num[0][0]), np.asarray(tf.den[0][0])
    return float(np.polyval(num, 1.0) / np.polyval(den, 1.0))


def _spectral_radius(polynomial):
    return float(np.max(np.abs(np.roots(polynomial))))


def stability_boundary(model, kd, ki=0.0, kp_max=KP_SEARCH_MAX, samples=500):
    """Largest kp (at fixed kd, ki) for which the sampled loop stays stable, found twice.

    1. Routh-Hurwitz: the characteristic polynomial ``base + kp per_kp`` is mapped to the
       w-plane (``z = (1 + w)/(1 - w)``) and tested with our Routh table
       (:func:`components.control.routh.stable_gain_intervals` with ``is_schur``); the edge
       is bisected on the Routh verdict to 1e-12 relative.
    2. Numeric roots: the same scan on the largest root magnitude, the edge found by Brent's
       method on ``max|z| - 1``.

    Parameters
    ----------
    model : WheelLoopModel
    kd, ki : float
    kp_max : float, optional
        Upper end of the search.
    samples : int, optional
        Scan points on ``[0, kp_max]``.

    Returns
    -------
    dict
        ``kp_routh``, ``kp_roots`` (None when kp = 0 is already unstable; ``kp_max`` when no
        edge was found), ``relative_difference``, ``intervals_routh`` (all stable kp
        intervals in the range), and ``crossing`` (where the critical root leaves the unit
        circle: angle in rad/sample and frequency in Hz; 0 rad means z = +1, pi means -1).
    """
    from scipy.optimize import brentq

    base, per_kp = model.characteristic_in_kp(kd, ki)
    intervals = stable_gain_intervals(base, per_kp, kp_max, test=is_schur, samples=samples)
    kp_routh = intervals[0][1] if intervals and intervals[0][0] == 0.0 else None

    def excess(kp):
        return _spectral_radius(np.polyadd(base, kp * per_kp)) - 1.0

    grid = np.linspace(0.0, kp_max, samples)
    values = np.array([excess(k) for k in grid])
    kp_roots = None
    if values[0] < 0.0:
        above = np.flatnonzero(values >= 0.0)
        if above.size == 0:
            kp_roots = float(kp_max)
        else:
            i = above[0]
            kp_roots = float(brentq(excess, grid[i - 1], grid[i], xtol=1e-14, rtol=1e-14))
    relative = None
    crossing = None
    if kp_routh is not None and kp_roots is not None:
        relative = abs(kp_routh - kp_roots) / max(abs(kp_roots), 1e-300)
        if kp_roots < kp_max:
            roots = np.roots(np.polyadd(base, kp_roots * per_kp))
            critical = roots[np.argmax(np.abs(roots))]
            angle = abs(float(np.angle(critical)))
            crossing = {"angle_rad_per_sample": angle,
                        "frequency_hz": angle / (2 * math.pi * model.period)}
    return {"kd": float(kd), "ki": float(ki), "kp_routh": kp_routh, "kp_roots": kp_roots,
            "relative_difference": relative, "intervals_routh": intervals,
            "crossing": crossing}


def continuous_gain_bound(model, kd, kp_max=1.0e4):
    """Routh on the continuous PD loop (no sampling, no delay): the stable kp intervals.

    Returns
    -------
    dict
        ``intervals`` in ``[0, kp_max]`` and the Routh first column at ``kp_max``, whose
        signs show why no finite bound appears.
    """
    base, per_kp = model.continuous_characteristic_in_kp(kd)
    intervals = stable_gain_intervals(base, per_kp, kp_max, test=is_hurwitz, samples=200)
    column = routh_table(np.polyadd(base, kp_max * per_kp))[:, 0]
    return {"kd": float(kd), "kp_max_searched": float(kp_max), "intervals": intervals,
            "routh_first_column_at_kp_max": [float(v) for v in column]}


def controller_cross_check(model, kp, kd, ki=0.0, step=0.05, samples=40, mode="pd",
                           controller_overrides=None, controller=None):
    """Run the real :class:`WheelSpeedController` on the sampled linear plant; compare to the TF.

    The controller's derivative starts at zero on its first sample (no kick), so the loop
    runs one sample at zero reference before the step, as it does after any start-up.
    ``mode="pd"`` runs the paper form's fixed PD with ``ki`` as its integral trim, ``"pid"``
    the PID; ``controller`` gives the controller's parameters instead (any form, whose
    gains ``kp``, ``kd``, ``ki`` on the model are then the caller's mapping of them);
    ``controller_overrides`` change the controller only (a deliberately different one).

    Returns
    -------
    float
        Largest difference [m/s] between the simulated rim speed and the closed-loop
        transfer function's step response (both at the sampling instants).
    """
    import control

    from components.control.controller import WheelSpeedController

    parameters = dict(
        mode=mode, pd_kp=kp, pd_kd=kd, pid_kp=kp, pid_ki=ki, pid_kd=kd, trim_ki=ki,
        form="paper", e_range=model.e_range, de_range=model.de_range,
        derivative_time_constant=model.derivative_time_constant,
        volts_per_speed=model.volts_per_speed, feedforward=model.feedforward,
        v_supply=1e9) if controller is None else dict(controller)  # linear: no clipping
    parameters.update(controller_overrides or {})
    controller = WheelSpeedController(**parameters)
    ad, bd, c = model.discrete
    _, _, average_c, average_d = zoh_with_average(*model.linear.state_space(), model.period)
    state = np.zeros((ad.shape[0], 1))
    delayed = [0.0] * (1 + int(model.extra_delay))  # measurement pipeline
    rim = []
    for k in range(samples + 1):
        reference = step if k >= 1 else 0.0
        measured = delayed[0]
        voltage = controller.step(reference, measured, model.period)
        if k >= 1:
            rim.append((c @ state).item())
        window = (average_c @ state).item() + average_d * voltage
        state = ad @ state + bd * voltage
        delayed = delayed[1:] + [window]
    times = np.arange(samples) * model.period
    reference_tf = control.step_response(model.closed_loop_tf(kp, kd, ki, "rim"), times)
    return float(np.max(np.abs(np.asarray(rim) - step * reference_tf.outputs)))




def kp_edge(model, kd, ki=0.0, kp_max=KP_SEARCH_MAX, samples=80):
    """Smallest kp > 0 at which the sampled loop (fixed kd, ki) becomes unstable, by roots.

    A coarse scan of ``max|z|`` on ``[0, kp_max]`` then Brent's method on ``max|z| - 1``:
    the fast form of :func:`stability_boundary` (which also runs Routh) for many kd values.

    Returns
    -------
    float
        0 when kp = 0 is already unstable, ``inf`` when no edge is found below ``kp_max``.
    """
    from scipy.optimize import brentq

    base, per_kp = model.characteristic_in_kp(kd, ki)

    def excess(kp):
        return _spectral_radius(np.polyadd(base, kp * per_kp)) - 1.0

    if excess(0.0) >= 0.0:
        return 0.0
    grid = np.linspace(0.0, kp_max, samples)
    for lo, hi in zip(grid[:-1], grid[1:]):
        if excess(hi) >= 0.0:
            return float(brentq(excess, lo, hi, xtol=1e-12, rtol=1e-12))
    return math.inf


def routh_bounds(model, kp_probe, kd_probe, ki=0.0, limit=1.0e4):
    """What Routh-Hurwitz bounds for this plant: continuous PD loop and sampled loop.

    Parameters
    ----------
    model : WheelLoopModel
    kp_probe, kd_probe : sequence of float
        kd values at which the kp interval is found, kp values at which the kd interval is.
    ki : float
        Integral gain of the sampled loop (the continuous one is the paper's pure PD).
    limit : float
        Search range ``[-limit, limit]`` for each gain.

    Returns
    -------
    dict
        ``continuous_kp`` / ``sampled_kp``: per kd, the stable kp intervals (Routh on
        ``s``, resp. on the w-plane image of ``z``); ``sampled_kd``: per kp, the stable kd
        intervals. Negative gains are searched too (the paper's signs).
    """
    def intervals(base, per_gain, test):
        # Fine near zero, where the sampled bounds are; coarse out to +-limit.
        edges = [-limit, -100.0, 100.0, limit]
        merged = []
        for lo, hi in zip(edges[:-1], edges[1:]):
            for a, b in stable_gain_intervals(base, per_gain, hi, test=test, samples=300,
                                              gain_min=lo):
                if merged and abs(merged[-1][1] - a) <= 1e-9 * max(1.0, abs(a)):
                    merged[-1] = (merged[-1][0], b)
                else:
                    merged.append((a, b))
        return [(float(a), float(b)) for a, b in merged]

    continuous = [{"kd": float(kd), "intervals": intervals(
        *model.continuous_characteristic_in_kp(kd), is_hurwitz)} for kd in kd_probe]
    sampled = [{"kd": float(kd), "intervals": intervals(
        *model.characteristic_in_kp(kd, ki), is_schur)} for kd in kd_probe]
    sampled_kd = [{"kp": float(kp), "intervals": intervals(
        *model.characteristic_in_kd(kp, ki), is_schur)} for kp in kp_probe]
    return {"limit": float(limit), "ki": float(ki), "continuous_kp": continuous,
            "sampled_kp": sampled, "sampled_kd": sampled_kd}


def incremental_form(model, kp, kd):
    """The PD law read as a voltage *change* per sample (incremental / velocity form).

    ``V_k = V_k-1 + g e_range (kp e_n + kd de_n)``: the controller is the PD's ``C(z)`` times
    ``z / (z - 1)``, so the paper's kp becomes an integral gain per sample. Used in
    docs/control.md to weigh this form against the integral trim.

    Returns
    -------
    dict
        ``spectral_radius``, and the dominant pole's ``frequency_hz`` and ``damping_ratio``
        (of the equivalent continuous pole ``ln(z) / T``).
    """
    nc, dc = model.controller_poly(kp, kd)
    characteristic = np.polyadd(np.polymul(np.polymul(dc, [1.0, -1.0]), model.meas_den),
                                np.polymul(np.polymul(nc, [1.0, 0.0]), model.meas_num))
    roots = np.roots(characteristic)
    dominant = roots[np.argmax(np.abs(roots))]
    s = np.log(complex(dominant)) / model.period
    return {"kp": float(kp), "kd": float(kd), "spectral_radius": float(abs(dominant)),
            "frequency_hz": float(abs(s.imag) / (2 * math.pi)),
            "damping_ratio": float(-s.real / abs(s)) if abs(s) > 0 else 1.0}
