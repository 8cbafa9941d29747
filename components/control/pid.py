"""PID law with a clamped, conditionally integrating integrator (the paper's CPID baseline)."""

from ..common.errors import ParameterError

__all__ = ["PidLaw"]


class PidLaw:
    """``u = kp e_n + ki I + kd de_n`` on normalised error ``e_n``, with ``I = integral of e_n``.

    Anti-windup, two measures: (1) conditional integration -- the integrator does not move
    while the output is saturated and the error would push it further into saturation;
    (2) the integral term ``ki I`` is clamped to ``+-integral_limit`` (in the same normalised
    units as ``u``), so it alone can never ask for more than the supply.

    Parameters
    ----------
    kp : float
        Proportional gain [1].
    ki : float
        Integral gain [1/s].
    kd : float
        Derivative gain [1].
    integral_limit : float
        Largest magnitude of ``ki I`` [1], > 0.

    Attributes
    ----------
    integral : float
        ``I`` [s] (normalised error times seconds).
    """

    def __init__(self, kp, ki, kd, integral_limit):
        if not integral_limit > 0.0:
            raise ParameterError(f"integral_limit = {integral_limit!r} must be > 0")
        if ki < 0.0:
            raise ParameterError(f"pid_ki = {ki!r} must be >= 0")
        self.kp = float(kp)
        self.ki = float(ki)
        self.kd = float(kd)
        self.integral_limit = float(integral_limit)
        self.integral = 0.0

    def output(self, e_n, de_n, h, to_voltage, offset, limit):
        """Advance the integrator by ``h`` and return the unclamped and clamped voltages.

        Parameters
        ----------
        e_n, de_n : float
            Normalised error and error rate.
        h : float
            Step [s].
        to_voltage : float
            Volts per unit of ``u`` [V].
        offset : float
            Feedforward voltage added to the law [V].
        limit : float
            Output limit, +-``limit`` [V].

        Returns
        -------
        float
            The voltage after clamping to +-``limit``.
        """
        candidate = self.integral + e_n * h
        term = self.ki * candidate
        if term > self.integral_limit:
            candidate = self.integral_limit / self.ki
        elif term < -self.integral_limit:
            candidate = -self.integral_limit / self.ki
        raw = offset + to_voltage * (self.kp * e_n + self.ki * candidate + self.kd * de_n)
        pushing_out = (raw > limit and e_n > 0.0) or (raw < -limit and e_n < 0.0)
        if not pushing_out:
            self.integral = candidate
        raw = offset + to_voltage * (self.kp * e_n + self.ki * self.integral + self.kd * de_n)
        return limit if raw > limit else (-limit if raw < -limit else raw)

    def reset(self):
        """Empty the integrator."""
        self.integral = 0.0
