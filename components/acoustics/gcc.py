"""Generalised cross-correlation restricted to the source band, with sub-sample peak refinement.

The correlation is evaluated only at physically possible lags (``|lag| <= max_lag``). The
integer peak is refined by a parabola through its neighbours and then by Newton steps on the
band-limited correlation written as a Fourier series over the weighted bins, which is the exact
(sinc) interpolation of the sampled correlation: no interpolation bias, whatever the fraction.
"""

import functools

import numpy as np

from ..common.errors import ParameterError
from ._rows import row_offsets

__all__ = ["WEIGHTINGS", "DelayEstimate", "estimate_delays", "estimate_pair_delays"]

WEIGHTINGS = ("band", "phat")

# PHAT whitening divides by |G|; the floor (relative to the largest in-band |G|) keeps bins
# with no signal from being amplified without bound.
_PHAT_EPSILON = 1e-3
_NEWTON_STEPS = 3
_NEIGHBOURS = np.array([-1, 0, 1])


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


class _Grid:
    """Constants of one GCC set-up (window length, rate, band, lag bound); read-only arrays."""

    def __init__(self, n, sample_rate, low, high, max_lag):
        self.n_fft = 1 << int(np.ceil(np.log2(2 * n)))
        freqs = np.fft.rfftfreq(self.n_fft, 1.0 / sample_rate)
        self.n_freqs = freqs.size
        bins = np.flatnonzero((freqs >= low) & (freqs <= high))
        # The band is one run of bins: a slice is cheaper than fancy indexing.
        self.band = slice(int(bins[0]), int(bins[-1]) + 1) if bins.size else slice(0, 0)
        # One-sided spectrum of a real signal: interior bins count twice.
        self.fold = np.where((freqs[bins] == 0.0) | (bins == self.n_fft // 2), 1.0, 2.0)
        self.fold_total = float(np.sum(self.fold))
        self.omega = 2.0 * np.pi * freqs[bins] / sample_rate
        self.j_omega = 1j * self.omega
        # The Newton step's slope and negated bend of r(lag) = sum_f Re(W e^{j omega lag}),
        # -sum_f omega Im(...) and sum_f omega^2 Re(...), as one product with the (Re, Im)
        # pairs of W e^{j omega lag} viewed as reals.
        self.slope_and_curvature = np.zeros((2 * bins.size, 2))
        self.slope_and_curvature[1::2, 0] = -self.omega
        self.slope_and_curvature[0::2, 1] = self.omega**2
        self.max_samples = max_lag * sample_rate
        limit = int(np.floor(self.max_samples))
        self.lags = np.arange(-limit, limit + 1)
        self.lag_index = self.lags % self.n_fft
        for array in (self.fold, self.omega, self.j_omega, self.slope_and_curvature, self.lags,
                      self.lag_index):
            array.setflags(write=False)


@functools.lru_cache(maxsize=32)
def _grid(n, sample_rate, low, high, max_lag):
    """Cached: a localizer calls this with the same window every fix."""
    return _Grid(n, sample_rate, low, high, max_lag)


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
    pairs = np.stack(np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float)),
                     axis=-2)
    return estimate_pair_delays(pairs, sample_rate, passband, max_lag, weighting)


def estimate_pair_delays(pairs, sample_rate, passband, max_lag, weighting="band"):
    """Estimate the delay of ``pairs[..., 0, :]`` relative to ``pairs[..., 1, :]``.

    :func:`estimate_delays` on windows already stacked: both go through one FFT call (each
    call has a fixed cost comparable to its work at these sizes).

    Parameters
    ----------
    pairs : numpy.ndarray
        Shape (..., 2, n).
    sample_rate, passband, max_lag, weighting
        As for :func:`estimate_delays`.

    Returns
    -------
    DelayEstimate
        Arrays of shape (...,).
    """
    if weighting not in WEIGHTINGS:
        raise ParameterError(f"weighting = {weighting!r}; valid choices: {', '.join(WEIGHTINGS)}")
    grid = _grid(pairs.shape[-1], float(sample_rate), float(passband[0]), float(passband[1]),
                 float(max_lag))
    spectra = np.fft.rfft(pairs, grid.n_fft, axis=-1)[..., grid.band]
    spectrum_u, spectrum_v = spectra[..., 0, :], spectra[..., 1, :]
    cross = spectrum_u * np.conj(spectrum_v)
    tiny = np.finfo(float).tiny
    if weighting == "phat":
        magnitude = np.abs(cross)
        floor = _PHAT_EPSILON * magnitude.max(axis=-1, keepdims=True)
        whitened = cross / np.maximum(magnitude, np.maximum(floor, tiny))
        norm = np.full(cross.shape[:-1], grid.fold_total)
    else:
        whitened = cross
        energy = np.abs(spectra) ** 2 @ grid.fold
        norm = np.sqrt(energy[..., 0] * energy[..., 1])
    weighted = grid.fold * whitened
    norm = np.maximum(norm, tiny)

    lags = grid.lags
    # Correlation at integer lags, r(k) = sum_f Re(W G e^{+j 2 pi f k / fs}), by one inverse
    # FFT of the unfolded spectrum (the inverse real FFT folds the one-sided spectrum itself).
    full = np.zeros(cross.shape[:-1] + (grid.n_freqs,), dtype=complex)
    full[..., grid.band] = whitened
    correlation = np.fft.irfft(full, grid.n_fft, axis=-1)[..., grid.lag_index] * grid.n_fft
    peak = correlation.argmax(axis=-1)
    # Parabola through the peak and its neighbours (clamped at the bound) as Newton's start.
    inner = np.minimum(np.maximum(peak, 1), lags.size - 2)
    at_bound = inner != peak
    index = row_offsets(correlation.shape) + inner[..., None] + _NEIGHBOURS
    neighbours = correlation.reshape(-1)[index]
    left, centre, right = neighbours[..., 0], neighbours[..., 1], neighbours[..., 2]
    curvature = left - 2.0 * centre + right
    offset = np.divide(0.5 * (left - right), curvature, out=np.zeros_like(curvature),
                       where=curvature < 0.0)
    peak_lag = lags[peak]
    lag = peak_lag + np.where(at_bound, 0.0, np.minimum(np.maximum(offset, -0.5), 0.5))
    lowest, highest = peak_lag - 1.0, peak_lag + 1.0
    for _ in range(_NEWTON_STEPS):
        rotated = weighted * np.exp(grid.j_omega * lag[..., None])
        derivatives = rotated.view(float) @ grid.slope_and_curvature
        slope, curving = derivatives[..., 0], derivatives[..., 1]
        step = np.divide(slope, curving, out=np.zeros_like(slope), where=curving > 0.0)
        lag = np.minimum(np.maximum(lag + np.minimum(np.maximum(step, -0.5), 0.5), lowest),
                         highest)
    lag = np.minimum(np.maximum(lag, -grid.max_samples), grid.max_samples)
    height = (weighted * np.exp(grid.j_omega * lag[..., None])).real.sum(axis=-1)
    return DelayEstimate(lag / sample_rate, height / norm, at_bound)
