"""Generalised cross-correlation restricted to the source band, with sub-sample peak refinement.

The correlation is evaluated only at physically possible lags (``|lag| <= max_lag``). The
integer peak is refined by a parabola through its neighbours and then by Newton steps on the
band-limited correlation written as a Fourier series over the weighted bins, which is the exact
(sinc) interpolation of the sampled correlation: no interpolation bias, whatever the fraction.
"""

import functools
import math

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
_TINY = float(np.finfo(float).tiny)


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


def _integer_lag_correlation(whitened, grid):
    """Correlation at the integer lags, ``r(k) = sum_f Re(W G e^{+j 2 pi f k / fs})``, shape (..., lags).

    One inverse FFT of the unfolded spectrum (the inverse real FFT folds the one-sided
    spectrum itself). ``norm="forward"`` leaves the inverse unscaled, which is the sum
    itself: the same numbers as scaling by ``1 / n_fft`` and back (a power of two, exact),
    without the scaling pass, which costs as much as a third of the transform here.
    """
    if grid.band.start == 0 < grid.band.stop:
        # The inverse pads the missing top bins with zeros itself.
        spectrum = whitened
    else:
        spectrum = np.zeros(whitened.shape[:-1] + (grid.n_freqs,), dtype=complex)
        spectrum[..., grid.band] = whitened
    # take(): the same gather as fancy indexing at a third of its cost.
    return np.fft.irfft(spectrum, grid.n_fft, axis=-1, norm="forward").take(grid.lag_index,
                                                                            axis=-1)


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
    tiny = _TINY
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
    correlation = _integer_lag_correlation(whitened, grid)
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


def _estimate_pair_delays_one(pairs, sample_rate, passband, max_lag, weighting):
    """:func:`estimate_pair_delays` for a few pairs (shape (p, 2, n)), as Python scalars.

    The same numbers by the same operations; only the per-pair scalar steps (the parabola,
    the Newton updates, the clamps) run in Python, where a fix's two pairs cost less than
    numpy's per-call overhead.

    Returns
    -------
    delays, qualities : list of float
        Per pair, as :attr:`DelayEstimate.delay` and :attr:`DelayEstimate.quality`.
    at_bound : bool
        Some pair's integer peak sits on the lag bound.
    """
    if weighting not in WEIGHTINGS:
        raise ParameterError(f"weighting = {weighting!r}; valid choices: {', '.join(WEIGHTINGS)}")
    grid = _grid(pairs.shape[-1], float(sample_rate), float(passband[0]), float(passband[1]),
                 float(max_lag))
    spectra = np.fft.rfft(pairs, grid.n_fft, axis=-1)[..., grid.band]
    cross = spectra[:, 0] * np.conj(spectra[:, 1])
    if weighting == "phat":
        magnitude = np.abs(cross)
        floor = _PHAT_EPSILON * magnitude.max(axis=-1, keepdims=True)
        whitened = cross / np.maximum(magnitude, np.maximum(floor, _TINY))
        norms = [max(grid.fold_total, _TINY)] * len(cross)
    else:
        whitened = cross
        energy = (np.abs(spectra) ** 2 @ grid.fold).tolist()
        norms = [max(math.sqrt(energy_u * energy_v), _TINY) for energy_u, energy_v in energy]
    weighted = grid.fold * whitened

    correlation = _integer_lag_correlation(whitened, grid)
    size = correlation.shape[-1]
    peaks = correlation.argmax(axis=-1).tolist()
    # Parabola through each peak and its neighbours (clamped at the bound) as Newton's start.
    inners = [min(max(peak, 1), size - 2) for peak in peaks]
    neighbours = correlation.take([row * size + inner + offset for row, inner in enumerate(inners)
                                   for offset in (-1, 0, 1)]).tolist()
    limit = size // 2
    lags, bounds = [], []
    for pair, (peak, inner) in enumerate(zip(peaks, inners)):
        left, centre, right = neighbours[3 * pair:3 * pair + 3]
        curvature = left - 2.0 * centre + right
        offset = 0.5 * (left - right) / curvature if curvature < 0.0 else 0.0
        peak_lag = peak - limit
        lags.append(peak_lag + (0.0 if inner != peak else min(max(offset, -0.5), 0.5)))
        bounds.append((peak_lag - 1.0, peak_lag + 1.0))
    at_bound = inners != peaks

    # exp(j omega lag) from a phase whose real part stays zero and whose imaginary part is the
    # real product omega * lag: cheaper than the complex product j_omega * lag, whose real part
    # is zero too (at most its sign differs, and exp(+-0) = 1), so the same rotations.
    phase = np.zeros(weighted.shape, dtype=complex)
    phase_imag = phase.imag

    def rotated_at(lags):
        """``weighted * exp(j_omega * lag)`` for each pair's lag."""
        np.multiply.outer(lags, grid.omega, out=phase_imag)
        rotated = np.exp(phase)
        return np.multiply(weighted, rotated, out=rotated)

    for _ in range(_NEWTON_STEPS):
        derivatives = (rotated_at(lags).view(float) @ grid.slope_and_curvature).tolist()
        for pair, ((slope, curving), (lowest, highest)) in enumerate(zip(derivatives, bounds)):
            step = slope / curving if curving > 0.0 else 0.0
            lags[pair] = min(max(lags[pair] + min(max(step, -0.5), 0.5), lowest), highest)
    lags = [min(max(lag, -grid.max_samples), grid.max_samples) for lag in lags]
    # np.add.reduce is ndarray.sum without its Python wrapper.
    heights = np.add.reduce(rotated_at(lags).real, axis=-1).tolist()
    return ([lag / sample_rate for lag in lags],
            [height / norm for height, norm in zip(heights, norms)], at_bound)
