"""Commissioning: a wheel's two constants from its response to a voltage step.

The default form's model of the wheel is first order: steady voltage per rim speed ``g``
(``volts_per_speed``) and mechanical time constant ``tau`` (``acceleration_feedforward``, also
the speed observer's model). A wheel unlike RobotPlant's (another motor, gearbox, battery or
mass) needs its own; a drive is commissioned by measuring them.

The experiment: from rest, a constant voltage ``V`` for a few time constants, the encoder's
position sampled every period. The rim position of a first-order wheel is
``x(t) = (V / g) (t - tau (1 - exp(-t / tau)))`` (the armature's millisecond lag adds a delay
of about L/R, which the fit absorbs into ``tau``); the encoder reports ``floor(x / q) q``, on
average ``q / 2`` low once it has moved. The fit: for each ``tau`` the least-squares ``1 / g``
and offset are linear, and ``tau`` minimises the residual (golden-section search on
``log tau``, bracketed by the samples' span). Pure Python floats.
"""

import math

from ..common.errors import InputError

__all__ = ["fit_step_response", "StepFit"]

_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


class StepFit:
    """A fitted first-order wheel.

    Attributes
    ----------
    volts_per_speed : float
        ``g`` [V s/m].
    time_constant : float
        ``tau`` [s].
    offset : float
        The fitted position offset [m] (about minus half a count).
    rms_residual : float
        RMS of the fit's position residual [m].
    """

    def __init__(self, volts_per_speed, time_constant, offset, rms_residual):
        self.volts_per_speed = volts_per_speed
        self.time_constant = time_constant
        self.offset = offset
        self.rms_residual = rms_residual

    def controller_parameters(self):
        """The WheelController parameters this wheel needs."""
        return {"volts_per_speed": self.volts_per_speed,
                "acceleration_feedforward": self.time_constant}


def _linear_fit(times, positions, voltage, tau):
    """``(speed_per_volt, offset, squared residual)`` for one ``tau``."""
    shape = [t - tau * -math.expm1(-t / tau) for t in times]
    n = len(times)
    sx, sy = sum(shape), sum(positions)
    sxx = sum(s * s for s in shape)
    sxy = sum(s * y for s, y in zip(shape, positions))
    det = n * sxx - sx * sx
    slope = (n * sxy - sx * sy) / det
    offset = (sy - slope * sx) / n
    residual = sum((y - slope * s - offset) ** 2 for s, y in zip(shape, positions))
    return slope / voltage, offset, residual


def fit_step_response(times, positions, voltage):
    """Fit ``g`` and ``tau`` to a voltage step's encoder positions.

    Parameters
    ----------
    times : sequence of float
        Sample instants after the step [s], > 0, increasing.
    positions : sequence of float
        Rim positions the encoder reported at them [m] (counts times their distance).
    voltage : float
        The voltage held from t = 0 [V], nonzero.

    Returns
    -------
    StepFit

    Raises
    ------
    InputError
        If the samples are too few, not increasing, or the wheel did not move.
    """
    times = [float(t) for t in times]
    positions = [float(x) for x in positions]
    if len(times) < 4 or len(times) != len(positions):
        raise InputError(f"step fit: {len(times)} times and {len(positions)} positions; "
                         "need at least 4 of each, as many of one as of the other")
    if not all(b > a for a, b in zip(times, times[1:])) or times[0] <= 0.0:
        raise InputError("step fit: times must be > 0 and increasing")
    if not (math.isfinite(voltage) and voltage != 0.0):
        raise InputError(f"step fit: voltage = {voltage!r} must be finite and nonzero")
    if max(positions) == min(positions):
        raise InputError("step fit: the wheel did not move (every position equal): raise the "
                         "voltage or the duration")
    low, high = math.log(times[0] / 10.0), math.log(times[-1] * 10.0)

    def cost(log_tau):
        return _linear_fit(times, positions, voltage, math.exp(log_tau))[2]

    a, b = low, high
    c, d = b - _GOLDEN * (b - a), a + _GOLDEN * (b - a)
    fc, fd = cost(c), cost(d)
    while b - a > 1e-9:
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - _GOLDEN * (b - a)
            fc = cost(c)
        else:
            a, c, fc = c, d, fd
            d = a + _GOLDEN * (b - a)
            fd = cost(d)
    tau = math.exp(0.5 * (a + b))
    speed_per_volt, offset, residual = _linear_fit(times, positions, voltage, tau)
    if not speed_per_volt > 0.0:
        raise InputError(f"step fit: the wheel moved against the voltage ({speed_per_volt:g} "
                         "m/s per V)")
    return StepFit(1.0 / speed_per_volt, tau, offset, math.sqrt(residual / len(times)))
