"""Robustness: the loop on wheels whose gain and time constant differ from RobotPlant's.

The controller keeps every constant tuned for RobotPlant (its feedforward ``volts_per_speed``
above all); the wheel it drives has its DC gain (rim speed per volt) multiplied by
``gain_factor`` and its mechanical time constant by ``time_constant_factor``
(:meth:`.loop_model.LinearWheelModel.scaled`). A gain factor 0.25 is a wheel needing four
times RobotPlant's voltage per m/s (another motor and gearbox, or a battery at a quarter of
its effect); a time-constant factor 2 a robot twice as heavy.

The steady-state error is the final value theorem on the sampled closed loop,
``1 - T(1)`` with ``T`` reference -> rim speed, exact and independent of any simulation.
"""

import math
from dataclasses import dataclass, replace

import numpy as np

from .analysis import final_value, step_figures

__all__ = ["PlantVariant", "RobustnessPoint", "plant_grid", "robustness_point",
           "steady_state_error"]


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
    from scipy.signal import lfilter

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
        # lfilter on a unit step is the TF's step response (python-control's is 20x slower).
        response = lfilter(tf.num[0][0], tf.den[0][0], np.ones(times.size))
        _, _, settle = step_figures(response, times, final_value(tf), 0.05)
        settling = max(settling, settle)
    return RobustnessPoint(controller=controller, gain_factor=variant.gain_factor,
                           time_constant_factor=variant.time_constant_factor,
                           gains=[list(map(float, g)) for g in gains],
                           spectral_radius=radius, steady_state_error=float(error),
                           settling_time_s=float(settling))
