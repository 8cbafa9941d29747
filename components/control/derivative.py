"""First-order filtered derivative of a sampled signal."""

import math

from ..common.errors import ParameterError

__all__ = ["FilteredDerivative"]


class FilteredDerivative:
    """Derivative through a first-order low-pass, ``D(s) = s / (tau s + 1)``.

    Discretised with backward Euler, ``d_k = (tau d_{k-1} + x_k - x_{k-1}) / (tau + h)``, which
    is stable for any step ``h``. The wheel speed comes from encoder counts over a window and
    moves in steps of one count per window (26 mm/s at 0.52 mm per count and 20 ms), so an
    unfiltered difference would turn each step into a spike of ~1.3 m/s^2.

    Parameters
    ----------
    time_constant : float
        Filter time constant ``tau`` [s], >= 0 (0: plain backward difference).

    Attributes
    ----------
    previous : float
        Last input sample.
    value : float
        Last filtered derivative.
    started : bool
        False until the first sample; the first sample gives a zero derivative (no kick).
    """

    def __init__(self, time_constant):
        if not (math.isfinite(time_constant) and time_constant >= 0.0):
            raise ParameterError(
                f"derivative filter time_constant = {time_constant!r} must be finite and >= 0")
        self.time_constant = float(time_constant)
        self.previous = 0.0
        self.value = 0.0
        self.started = False

    def update(self, x, h):
        """Take sample ``x`` after a step of ``h`` seconds and return the filtered derivative."""
        if not self.started:
            self.started = True
            self.previous = x
            self.value = 0.0
            return 0.0
        self.value = (self.time_constant * self.value + x - self.previous) / (self.time_constant + h)
        self.previous = x
        return self.value

    def reset(self):
        """Forget the history; the next sample gives a zero derivative."""
        self.previous = 0.0
        self.value = 0.0
        self.started = False
