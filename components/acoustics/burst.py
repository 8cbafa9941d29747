"""The band-limited burst the source sounds: a Hann-windowed linear chirp.

A chirp sweeping the whole source band has a sharp, unambiguous correlation peak (no cycle
skipping, unlike a tone) and a flat band. It is evaluated analytically at any continuous time,
so propagation delays are applied exactly, without rounding or interpolation. The Hann window
makes the waveform and its derivative continuous, so it is band-limited in practice (side lobes
below -31 dB) and its sampled derivative energy gives the Cramer-Rao bound directly.
"""

import functools

import numpy as np

from ..common.errors import ParameterError

__all__ = ["ChirpBurst"]


class ChirpBurst:
    """A Hann-windowed linear chirp from ``band_low`` to ``band_high`` lasting ``duration``.

    Parameters
    ----------
    band_low, band_high : float
        Start and end frequencies of the sweep [Hz].
    duration : float
        Burst length [s].

    Examples
    --------
    >>> burst = ChirpBurst(2000.0, 10000.0, 0.8e-3)
    >>> float(burst.waveform(np.array([0.0, 0.8e-3]))[0])
    0.0
    """

    def __init__(self, band_low, band_high, duration):
        problems = []
        if not band_low > 0.0:
            problems.append(f"band_low = {band_low!r} Hz must be > 0")
        if not band_high > band_low:
            problems.append(f"band_high = {band_high!r} Hz must exceed band_low = {band_low!r} Hz")
        if not duration > 0.0:
            problems.append(f"burst_duration = {duration!r} s must be > 0")
        if problems:
            raise ParameterError("ChirpBurst: " + "; ".join(problems))
        self.band_low = float(band_low)
        self.band_high = float(band_high)
        self.duration = float(duration)

    def _sweep(self):
        return (self.band_high - self.band_low) / self.duration

    def _phase_terms(self, t):
        t = np.asarray(t, dtype=float)
        inside = (t >= 0.0) & (t <= self.duration)
        phase = 2.0 * np.pi * (self.band_low * t + 0.5 * self._sweep() * t * t)
        angle = 2.0 * np.pi * t / self.duration
        return inside, phase, angle

    def waveform(self, t):
        """Return the unit-amplitude burst at times ``t`` [s] (zero outside the burst)."""
        inside, phase, angle = self._phase_terms(t)
        return np.where(inside, 0.5 * (1.0 - np.cos(angle)) * np.sin(phase), 0.0)

    def derivative(self, t):
        """Return the time derivative of :meth:`waveform` at ``t`` [1/s], analytically."""
        inside, phase, angle = self._phase_terms(t)
        rate = 2.0 * np.pi * (self.band_low + self._sweep() * np.asarray(t, dtype=float))
        envelope = 0.5 * (1.0 - np.cos(angle))
        envelope_rate = np.pi / self.duration * np.sin(angle)
        value = envelope_rate * np.sin(phase) + envelope * rate * np.cos(phase)
        return np.where(inside, value, 0.0)

    def mean_power(self, sample_rate):
        """Return the mean square of the unit burst over its duration, from samples at ``sample_rate``."""
        # Cached: the synthesis asks for it every burst.
        return _mean_power(self.band_low, self.band_high, self.duration, float(sample_rate))

    def passband(self):
        """Return the band ``(low, high)`` [Hz] the estimator weights.

        The sweep limits widened by ``1/duration``, where the Hann window's spectrum of each
        instantaneous frequency has fallen by about 6 dB.
        """
        margin = 1.0 / self.duration
        return max(self.band_low - margin, 0.0), self.band_high + margin


@functools.lru_cache(maxsize=32)
def _mean_power(band_low, band_high, duration, sample_rate):
    burst = ChirpBurst(band_low, band_high, duration)
    t = np.arange(int(np.ceil(duration * sample_rate)) + 1) / sample_rate
    return float(np.sum(burst.waveform(t) ** 2) / (duration * sample_rate))
