"""Robustness: the loop on wheels whose gain and time constant differ from RobotPlant's.

The controller keeps every constant tuned for RobotPlant (its feedforward ``volts_per_speed``
above all); the wheel it drives has its DC gain (rim speed per volt) multiplied by
``gain_factor`` and its mechanical time constant by ``time_constant_factor``
(:meth:`.loop_model.LinearWheelModel.scaled`). A gain factor 0.25 is a wheel needing four
times RobotPlant's voltage per m/s (another motor and gearbox, or a battery at a quarter of
its effect); a time-constant factor 2 a robot twice as heavy.

The steady-state error is the final value theorem on the sampled closed loop,
``1 - T(1)`` with ``T`` reference -> rim speed, exact and independent of any simulation.

How far the gain factor may go is found exactly rather than read off the grid: the
characteristic polynomial is affine in the factor ``G`` (it multiplies the plant's numerator
only, :meth:`.loop_model.WheelLoopModel.characteristic_in_gain_factor`), so the stable
range of ``G`` around the nominal 1 has edges where a root crosses the unit circle.
:func:`plant_gain_edges` finds them twice, by Brent's method on ``max|z| - 1`` and by
bisection on our Routh test of the w-plane image, as :func:`.analysis.stability_boundary`
does for kp.
"""

import math
from dataclasses import dataclass, replace

import numpy as np

from components.control.routh import is_schur

from .analysis import filter_through, final_value, step_figures

__all__ = ["PlantVariant", "RobustnessPoint", "plant_grid", "robustness_point",
           "steady_state_error", "plant_gain_edges", "largest_stable_gain_factor",
           "GAIN_FACTOR_SEARCH"]

# The scan for the edges of the stable gain-factor range: from the nominal 1 up to 1024 and
# down to 1/64 (four times below the smallest factor any requirement names), in steps of
# 2^(1/8) (9 %), each crossing then refined to 1e-12. A root that leaves and re-enters the
# unit circle within one step would be missed by both methods alike; the tests scan 16 times
# finer and find no such window.
GAIN_FACTOR_SEARCH = (1.0 / 64.0, 1024.0, 8)


@dataclass(frozen=True)
class PlantVariant:
    """A wheel relative to RobotPlant's: DC gain and time constant multiplied by the factors.

    (Both factors multiply RobotPlant's values.)
    """

    gain_factor: float
    time_constant_factor: float


@dataclass
class RobustnessPoint:
    """One controller on one plant variant.

    Attributes
    ----------
    controller : str
        ``fgs_pd``, ``pd`` or ``pid`` (and the form, e.g. ``fgs_pd``).
    gain_factor, time_constant_factor : float
    gains : list of [kp, kd, ki]
        The frozen gain sets tried (the FGS-PD surface's corners; one set for PD and PID).
    spectral_radius : float
        Largest closed-loop |z| over those gain sets (stable when < 1).
    steady_state_error : float
        Worst ``|1 - T(1)|`` over the gain sets, as a fraction of the reference.
    settling_time_s : float
        Worst time to enter and stay within +-5 % of the final value after a reference step
        (NaN when unstable).
    """

    controller: str
    gain_factor: float
    time_constant_factor: float
    gains: list
    spectral_radius: float
    steady_state_error: float
    settling_time_s: float


def plant_grid(gain_factors, time_constant_factors):
    """Every combination of the factors, as :class:`PlantVariant` (gain outer, tau inner)."""
    return [PlantVariant(float(g), float(t)) for g in gain_factors for t in time_constant_factors]


def steady_state_error(model, kp, kd, ki=0.0):
    """``1 - T(1)``: final-value error of a unit reference step, fraction of the reference.

    Parameters
    ----------
    model : WheelLoopModel
    kp, kd, ki : float

    Returns
    -------
    float
        Meaningful only when the loop is stable.
    """
    return 1.0 - final_value(model.closed_loop_tf(kp, kd, ki, "rim"))


def robustness_point(model, variant, controller, gains, duration=60.0):
    """Stability, steady-state error and settling of ``controller`` on one plant variant.

    Parameters
    ----------
    model : WheelLoopModel
        The nominal loop (controller constants, period); the variant scales its plant.
    variant : PlantVariant
    controller : str
        Label for the report.
    gains : sequence of (kp, kd, ki)
    duration : float, optional
        Length of the step response for the settling time [s].

    Returns
    -------
    RobustnessPoint
    """
    scaled = replace(model, gain_factor=variant.gain_factor,
                     time_constant_factor=variant.time_constant_factor)
    radius, error, settling = 0.0, 0.0, 0.0
    times = np.arange(int(round(duration / scaled.period)) + 1) * scaled.period
    for kp, kd, ki in gains:
        r = float(np.max(np.abs(np.roots(scaled.characteristic_polynomial(kp, kd, ki)))))
        radius = max(radius, r)
        if r >= 1.0:
            error = settling = math.nan
            continue
        error = max(error, abs(steady_state_error(scaled, kp, kd, ki)))
        tf = scaled.closed_loop_tf(kp, kd, ki, "rim")
        # filtering a unit step is the TF's step response (python-control's is 20x slower)
        response = filter_through(tf, np.ones(times.size))
        _, _, settle = step_figures(response, times, final_value(tf), 0.05)
        settling = max(settling, settle)
    return RobustnessPoint(controller=controller, gain_factor=variant.gain_factor,
                           time_constant_factor=variant.time_constant_factor,
                           gains=[list(map(float, g)) for g in gains],
                           spectral_radius=radius, steady_state_error=float(error),
                           settling_time_s=float(settling))


def _spectral_radius(polynomial):
    return float(np.max(np.abs(np.roots(polynomial))))


def _refine(stable, inside, outside, rtol=1e-12):
    """Bisect between a stable ``inside`` and an unstable ``outside`` point (either order)."""
    while abs(outside - inside) > rtol * max(abs(inside), abs(outside)):
        middle = 0.5 * (inside + outside)
        if middle in (inside, outside):
            break
        if stable(middle):
            inside = middle
        else:
            outside = middle
    return 0.5 * (inside + outside)


def _edge(excess, schur, scan):
    """First crossing along ``scan`` (from the nominal outward): (roots edge, Routh edge)."""
    from scipy.optimize import brentq

    edge_roots = edge_routh = None
    for inner, outer in zip(scan[:-1], scan[1:]):
        if edge_roots is None and excess(outer) >= 0.0:
            lo, hi = sorted((inner, outer))
            edge_roots = float(brentq(excess, lo, hi, xtol=1e-15, rtol=1e-14))
        if edge_routh is None and not schur(outer):
            edge_routh = float(_refine(schur, inner, outer))
        if edge_roots is not None and edge_routh is not None:
            break
    return edge_roots, edge_routh


def plant_gain_edges(base, per_gain, nominal=1.0, search=GAIN_FACTOR_SEARCH):
    """The stable range of ``G`` around ``nominal`` for ``base + G * per_gain`` (in z).

    Parameters
    ----------
    base, per_gain : array_like
        Polynomials in z, highest power first, of equal length.
    nominal : float, optional
        A factor inside the range (RobotPlant: 1).
    search : (float, float, int), optional
        Smallest and largest factor searched and scan steps per octave
        (:data:`GAIN_FACTOR_SEARCH`).

    Returns
    -------
    dict
        ``upper`` and ``lower``: the edges by numeric roots (Brent on ``max|z| - 1``,
        to 1e-14 relative); ``upper_routh`` / ``lower_routh``: the same by bisection on
        the Routh verdict of the w-plane polynomial (1e-12); ``upper_relative_difference``;
        ``upper_crossing``: the angle [rad/sample] at which the critical root leaves the
        unit circle (pi: z = -1). An edge not found inside the search is the search's end
        and flagged by ``upper_found`` / ``lower_found`` False. None everywhere when the
        nominal factor itself is unstable (``nominal_stable`` False).
    """
    base = np.asarray(base, dtype=float)
    per_gain = np.asarray(per_gain, dtype=float)

    def polynomial(g):
        return base + g * per_gain

    def excess(g):
        return _spectral_radius(polynomial(g)) - 1.0

    def schur(g):
        return is_schur(polynomial(g))

    low, high, per_octave = search
    result = {"nominal": float(nominal), "search": [float(low), float(high)],
              "nominal_spectral_radius": excess(nominal) + 1.0,
              "nominal_stable": bool(excess(nominal) < 0.0 and schur(nominal))}
    if not result["nominal_stable"]:
        return dict(result, upper=None, lower=None, upper_routh=None, lower_routh=None,
                    upper_found=False, lower_found=False, upper_relative_difference=None,
                    upper_crossing=None)
    steps_up = int(math.ceil(per_octave * math.log2(high / nominal)))
    steps_down = int(math.ceil(per_octave * math.log2(nominal / low)))
    up = nominal * 2.0 ** (np.arange(steps_up + 1) / per_octave)
    down = nominal * 2.0 ** (-np.arange(steps_down + 1) / per_octave)
    upper, upper_routh = _edge(excess, schur, up)
    lower, lower_routh = _edge(excess, schur, down)
    crossing = None
    if upper is not None:
        roots = np.roots(polynomial(upper))
        crossing = abs(float(np.angle(roots[np.argmax(np.abs(roots))])))
    both = upper is not None and upper_routh is not None
    return dict(result,
                upper=upper if upper is not None else float(up[-1]),
                upper_routh=upper_routh if upper_routh is not None else float(up[-1]),
                upper_found=upper is not None,
                lower=lower if lower is not None else float(down[-1]),
                lower_routh=lower_routh if lower_routh is not None else float(down[-1]),
                lower_found=lower is not None,
                upper_relative_difference=(abs(upper - upper_routh) / upper) if both else None,
                upper_crossing=crossing)


def largest_stable_gain_factor(model, kp, kd, ki=0.0, time_constant_factor=1.0):
    """Stable plant-DC-gain factors of one frozen gain set at one time-constant factor.

    The wheel is RobotPlant's with its mechanical time constant multiplied by
    ``time_constant_factor``; the controller keeps ``model``'s constants. The same sampled
    loop as every other check (ZOH, window-averaged encoder, ``model.period``).

    Parameters
    ----------
    model : WheelLoopModel
    kp, kd, ki : float
    time_constant_factor : float, optional

    Returns
    -------
    dict
        :func:`plant_gain_edges` plus ``kp``, ``kd``, ``ki``, ``time_constant_factor`` and
        ``crossing_hz`` (frequency of the oscillation at the upper edge).
    """
    wheel = replace(model, gain_factor=1.0, time_constant_factor=float(time_constant_factor))
    edges = plant_gain_edges(*wheel.characteristic_in_gain_factor(kp, kd, ki))
    angle = edges["upper_crossing"]
    return dict(edges, kp=float(kp), kd=float(kd), ki=float(ki),
                time_constant_factor=float(time_constant_factor),
                crossing_hz=None if angle is None else angle / (2 * math.pi * model.period))
