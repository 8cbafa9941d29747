"""The fastest any controller can settle a wheel: the bound the supply voltage sets.

The wheel of :class:`.loop_model.LinearWheelModel` (armature and mechanical poles, both real)
has a non-negative impulse response, so from rest under any voltage ``|V| <= v_supply`` its
rim speed never exceeds the speed it reaches under ``v_supply`` held from the start. A speed
step to ``r`` therefore cannot enter the band ``r (1 - band)`` before the full-voltage
response reaches it, whatever the controller knows or computes: that instant is a lower bound
on the settling time of every controller. Settling is judged at the loop's samples
(:func:`.wheel_experiments.settling_after`), so the bound on the sampled loop is that instant
rounded up to the next sample. For a first-order wheel (DC gain ``K``, time constant ``tau``)
it is ``-tau ln(1 - r (1 - band) / (K v_supply))``; the 1 ms armature adds about 1 ms.

The bound is reached by a controller that knows the wheel's two constants: full voltage,
then the steady voltage (the default form with ``volts_per_speed`` and
``acceleration_feedforward`` set to the wheel's own, measured in benchmarks/wheel_loop.py).
"""

import math

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq

__all__ = ["minimum_settling_time"]


def minimum_settling_time(model, speed, band_fraction, v_supply, period=None):
    """Earliest time [s] any controller can bring ``model`` from rest into the band.

    Parameters
    ----------
    model : LinearWheelModel
        The wheel (scaled as wanted).
    speed : float
        The step's target [m/s], > 0.
    band_fraction : float
        Half-width of the band as a fraction of ``speed``.
    v_supply : float
        The largest voltage magnitude [V].
    period : float, optional
        Sampling period [s]: the bound is then rounded up to a whole number of periods.

    Returns
    -------
    float
        ``inf`` when even the full supply cannot reach the band (``K v_supply`` below it).
    """
    a, b, c = model.state_space()
    target = speed * (1.0 - band_fraction)
    if model.dc_gain * v_supply <= target:
        return math.inf

    def full_voltage_speed(t):
        # x(t) = A^-1 (e^{At} - I) B V from rest
        return float((c @ np.linalg.solve(a, (expm(a * t) - np.eye(2)) @ b))[0, 0] * v_supply)

    upper = 1e-3
    while full_voltage_speed(upper) < target:
        upper *= 2.0
    reach = brentq(lambda t: full_voltage_speed(t) - target, 0.0, upper, xtol=1e-12)
    if period is None:
        return reach
    return math.ceil(reach / period - 1e-9) * period
