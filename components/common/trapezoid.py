"""Trapezoidal speed profiles: the analytic rest-to-rest profile and its sampled counterpart.

Both the sound source and the planner move along a path of known length with bounded speed and
acceleration, from rest to rest. The source uses the continuous profile of
:class:`TrapezoidProfile`. The planner holds each speed for one step and measures its progress
only afterwards, so it needs a sampled profile whose braking ends exactly at the end of the
path: :func:`braking_speed` and :func:`next_speed`.
"""

import math

from .errors import ParameterError

__all__ = ["TrapezoidProfile", "braking_speed", "next_speed"]


class TrapezoidProfile:
    """Rest-to-rest trapezoidal speed profile over a path of given length.

    Accelerate at ``a_max``, cruise at ``v_max``, decelerate at ``a_max`` to stop at ``length``.
    If the path is too short to reach ``v_max``, the profile is a triangle with peak speed
    ``sqrt(a_max * length)``.

    Parameters
    ----------
    length : float
        Path length to cover [m], >= 0.
    v_max : float
        Cruise speed [m/s], > 0.
    a_max : float
        Acceleration and deceleration [m/s^2], > 0.

    Examples
    --------
    >>> p = TrapezoidProfile(1.0, 0.2, 0.2)
    >>> p.duration
    6.0
    >>> p.distance(p.duration)
    1.0
    """

    def __init__(self, length, v_max, a_max):
        for name, value in (("v_max", v_max), ("a_max", a_max)):
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"{name} = {value!r}: must be a finite number > 0")
        if not (math.isfinite(length) and length >= 0.0):
            raise ParameterError(f"path length = {length!r}: must be a finite number >= 0")
        self.length = float(length)
        self.a_max = float(a_max)
        self.v_peak = min(float(v_max), math.sqrt(self.a_max * self.length))
        self.t_ramp = self.v_peak / self.a_max
        self.d_ramp = 0.5 * self.v_peak * self.t_ramp
        cruise_length = max(self.length - 2.0 * self.d_ramp, 0.0)
        self.t_cruise = cruise_length / self.v_peak if self.v_peak > 0.0 else 0.0
        self.duration = 2.0 * self.t_ramp + self.t_cruise

    def distance(self, t):
        """Distance covered [m] at time ``t`` [s] after the start (0 before, ``length`` after)."""
        return self.distance_and_speed(t)[0]

    def speed(self, t):
        """Speed [m/s] at time ``t`` [s] after the start."""
        return self.distance_and_speed(t)[1]

    def distance_and_speed(self, t):
        """:meth:`distance` [m] and :meth:`speed` [m/s] at time ``t`` [s], in one evaluation.

        Examples
        --------
        >>> TrapezoidProfile(1.0, 0.2, 0.2).distance_and_speed(0.5)
        (0.025, 0.1)
        """
        if t <= 0.0:
            return 0.0, 0.0
        if t >= self.duration:
            return self.length, 0.0
        if t < self.t_ramp:
            return 0.5 * self.a_max * t * t, self.a_max * t
        if t < self.t_ramp + self.t_cruise:
            return self.d_ramp + self.v_peak * (t - self.t_ramp), self.v_peak
        to_go = self.duration - t
        return self.length - 0.5 * self.a_max * to_go * to_go, self.a_max * to_go

    def acceleration(self, t):
        """Acceleration [m/s^2] at time ``t`` [s] after the start."""
        if t <= 0.0 or t >= self.duration:
            return 0.0
        if t < self.t_ramp:
            return self.a_max
        if t < self.t_ramp + self.t_cruise:
            return 0.0
        return -self.a_max


def braking_speed(remaining, a_max, step):
    """Highest speed that, held for one step, still lets the motion stop exactly at the end.

    The speed is held for ``step`` and then lowered by ``a_max * step`` every step down to zero;
    the distance this staircase covers, counting the current step, is
    ``D(v) = step * ((n + 1) v - a_max step n (n + 1) / 2)`` with ``n = floor(v / (a_max step))``.
    This returns the ``v`` with ``D(v) = remaining``, so a braking sampled profile lands on the
    end point instead of overshooting it by up to one step.

    Parameters
    ----------
    remaining : float
        Distance left to the end point [m]; values <= 0 give 0.
    a_max : float
        Deceleration [m/s^2], > 0.
    step : float
        Hold time of each speed [s], > 0.

    Returns
    -------
    float
        Speed [m/s].

    Examples
    --------
    >>> round(braking_speed(0.001, 0.4, 0.1), 12)   # less than one step of braking left
    0.01
    """
    if remaining <= 0.0:
        return 0.0
    quantum = a_max * step * step
    n = int((math.sqrt(1.0 + 8.0 * remaining / quantum) - 1.0) / 2.0)
    # The square root can be off by one ulp around integer n; settle n on the exact test.
    while n > 0 and 0.5 * quantum * n * (n + 1) > remaining:
        n -= 1
    while 0.5 * quantum * (n + 1) * (n + 2) <= remaining:
        n += 1
    return (remaining / step + 0.5 * a_max * step * n * (n + 1)) / (n + 1)


def next_speed(current, cruise, remaining, a_max, step):
    """Next held speed of a sampled trapezoid: accelerate, cruise, brake onto the end point.

    Parameters
    ----------
    current : float
        Speed held during the previous step [m/s].
    cruise : float
        Cruise speed [m/s].
    remaining : float
        Distance left to the end point [m].
    a_max : float
        Acceleration bound [m/s^2].
    step : float
        Hold time of the next speed [s].

    Returns
    -------
    float
        Speed to hold for the next step [m/s], >= 0, within ``a_max * step`` of ``current``.
    """
    change = a_max * step
    # min() and max() of three written as comparisons (the planner calls this every step):
    # the same picks, the first of equal values, without the calls.
    target = cruise
    if current + change < target:
        target = current + change
    # Far from the end the braking speed exceeds target and is not worth its square root:
    # braking from target covers D(target) <= (target + a_max step / 2)^2 / (2 a_max) (the
    # staircase of braking_speed), and D is increasing, so D(target) < remaining means
    # braking_speed(remaining) > target. The margin of 1e-6 dwarfs any rounding; a NaN or
    # infinite remaining still goes to braking_speed, which rejects it.
    reach = target + 0.5 * change
    if not reach * reach < 2.0 * a_max * remaining * (1.0 - 1e-6) < math.inf:
        braking = braking_speed(remaining, a_max, step)
        if braking < target:
            target = braking
    # If the end was overshot (remaining < 0) or the cruise speed dropped, brake as hard as
    # allowed rather than stepping the speed.
    if current - change > target:
        target = current - change
    return 0.0 if target < 0.0 else target
