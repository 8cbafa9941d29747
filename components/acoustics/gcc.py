"""Generalised cross-correlation restricted to the source band, with sub-sample peak refinement.

The correlation is evaluated only at physically possible lags (``|lag| <= max_lag``). The
integer peak is refined by a parabola through its neighbours and then by Newton steps on the
band-limited correlation written as a Fourier series over the weighted bins, which is the exact
(sinc) interpolation of the sampled correlation: no interpolation bias, whatever the fraction.
"""

import functools

import numpy as np

from ..common.errors import ParameterError

__all__ = ["WEIGHTINGS", "DelayEstimate", "estimate_delays"]

WEIGHTINGS = ("band", "phat")

# PHAT whitening divides by |G|; the floor (relative to the largest in-band |G|) keeps bins
# with no signal from being amplified without bound.
_PHAT_EPSILON = 1e-3
_NEWTON_STEPS = 3


class DelayEstimate:
    """Delays of ``u`` relative to ``v`` found by :func:`estimate_delays` (arrays of one shape).

    Attributes
    ----------
    delay : numpy.ndarray
        Refined delay [s]; positive when ``u`` lags ``v``.
    quality : numpy.ndarray
        Peak height normalised to [-1, 1]: the in-band correlation coefficient for ``band``
        weighting, the peak over its noise-free maximum for ``phat``.
    at_bound : numpy.ndarray of bool
        The integer peak sits on the lag bound, so the true peak may lie outside it.
    """

    def __init__(self, delay, quality, at_bound):
        self.delay = delay
        self.quality = quality
        self.at_bound = at_bound


@functools.lru_cache(maxsize=32)
def _grid(n, sample_rate, low, high):
    """FFT size, bin frequencies, in-band bins, their one-sided weights and angular steps.

    Cached: a localizer calls this with the same window every fix. The arrays are read-only.
    """
    n_fft = 1 << int(np.ceil(np.log2(2 * n)))
    freqs = np.fft.rfftfreq(n_fft, 1.0 / sample_rate)
    bins = np.flatnonzero((freqs >= low) & (freqs <= high))
    # One-sided spectrum of a real signal: interior bins count twice.
    fold = np.where((freqs[bins] == 0.0) | (bins == n_fft // 2), 1.0, 2.0)
    omega = 2.0 * np.pi * freqs[bins] / sample_rate
    for array in (freqs, bins, fold, omega):
        array.setflags(write=False)
    return n_fft, freqs, bins, fold, omega


def estimate_delays(u, v, sample_rate, passband, max_lag, weighting="band"):
    """Estimate the delay of ``u`` relative to ``v`` along the last axis.

    Parameters
    ----------
    u, v : numpy.ndarray
        Shape (..., n): equal-length windows of two microphone records.
    sample_rate : float
        fs [Hz].
    passband : tuple of float
        ``(low, high)`` [Hz]: only these bins are weighted.
    max_lag : float
        Largest physically possible delay [s] (``l / c`` for adjacent microphones).
    weighting : {"band", "phat"}
        ``band``: plain cross-correlation of the band (efficient at high SNR for white noise);
        ``phat``: phase transform (whitened) over the same band.

    Returns
    -------
    DelayEstimate
    """
    if weighting not in WEIGHTINGS:
        raise ParameterError(f"weighting = {weighting!r}; valid choices: {', '.join(WEIGHTINGS)}")
    n = u.shape[-1]
    n_fft, freqs, bins, fold, omega = _grid(n, float(sample_rate), float(passband[0]),
                                            float(passband[1]))
    spectrum_u = np.fft.rfft(u, n_fft, axis=-1)[..., bins]
    spectrum_v = np.fft.rfft(v, n_fft, axis=-1)[..., bins]
    cross = spectrum_u * np.conj(spectrum_v)
    if weighting == "phat":
        magnitude = np.abs(cross)
        floor = _PHAT_EPSILON * magnitude.max(axis=-1, keepdims=True)
        weighted = fold * cross / np.maximum(magnitude, np.maximum(floor, np.finfo(float).tiny))
        norm = np.sum(fold) * np.ones(cross.shape[:-1])
    else:
        weighted = fold * cross
        energy_u = np.sum(fold * np.abs(spectrum_u) ** 2, axis=-1)
        energy_v = np.sum(fold * np.abs(spectrum_v) ** 2, axis=-1)
        norm = np.sqrt(energy_u * energy_v)
    norm = np.maximum(norm, np.finfo(float).tiny)

    max_samples = max_lag * sample_rate
    limit = int(np.floor(max_samples))
    lags = np.arange(-limit, limit + 1)
    # Correlation at integer lags, r(k) = sum_f Re(W G e^{+j 2 pi f k / fs}), by one inverse
    # FFT (which folds the one-sided spectrum itself, hence the division by ``fold``).
    full = np.zeros(cross.shape[:-1] + (freqs.size,), dtype=complex)
    full[..., bins] = weighted / fold
    correlation = n_fft * np.fft.irfft(full, n_fft, axis=-1)[..., lags % n_fft]
    peak = np.argmax(correlation, axis=-1)
    at_bound = (peak == 0) | (peak == lags.size - 1)

    # Parabola through the peak and its neighbours (clamped at the bound) as Newton's start.
    inner = np.clip(peak, 1, lags.size - 2)
    left = np.take_along_axis(correlation, (inner - 1)[..., None], -1)[..., 0]
    centre = np.take_along_axis(correlation, inner[..., None], -1)[..., 0]
    right = np.take_along_axis(correlation, (inner + 1)[..., None], -1)[..., 0]
    curvature = left - 2.0 * centre + right
    offset = np.where(curvature < 0.0, 0.5 * (left - right) / np.where(curvature < 0, curvature, -1.0), 0.0)
    lag = lags[peak] + np.where(at_bound, 0.0, np.clip(offset, -0.5, 0.5))
    for _ in range(_NEWTON_STEPS):
        rotated = weighted * np.exp(1j * omega * lag[..., None])
        slope = -np.sum(omega * np.imag(rotated), axis=-1)
        bend = -np.sum(omega**2 * np.real(rotated), axis=-1)
        step = np.where(bend < 0.0, -slope / np.where(bend < 0.0, bend, -1.0), 0.0)
        lag = np.clip(lag + np.clip(step, -0.5, 0.5), lags[peak] - 1.0, lags[peak] + 1.0)
    lag = np.clip(lag, -max_samples, max_samples)
    height = np.sum(np.real(weighted * np.exp(1j * omega * lag[..., None])), axis=-1)
    return DelayEstimate(lag / sample_rate, height / norm, at_bound)
