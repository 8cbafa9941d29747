"""What the three microphones record: delayed, spread, noisy and quantised bursts.

For each microphone ``i`` at range ``R_i`` the record is
``x_i[n] = A_ref * (r_ref / R_i) * s(t_n - R_i / c) + w_i[n]``, clipped to the ADC's full
scale [-1, 1) and rounded to ``2**adc_bits`` levels. The burst ``s`` is evaluated at the exact
continuous delay, so delays are fractional, never rounded to samples. The noise ``w`` is white
Gaussian over the full sampling band with variance set by ``snr_db`` (see :func:`noise_std`).

A multiplexed ADC samples its channels one after another: channel ``i`` takes sample ``n`` at
``t_n + skew_i``. Sampling ``s(t - tau_i)`` at ``t_n + skew_i`` is sampling
``s(t - (tau_i - skew_i))`` at ``t_n``, an identity for any waveform, so a skew is rendered
exactly by evaluating the burst at ``t_n + skew_i - tau_i`` (``adc_skews``); the record still
starts on the grid set by the true arrivals. The noise is white, so its samples at the skewed
instants are independent draws of the same law.
The geometry is frozen for the burst: the source (<= 0.2 m/s) moves 0.2 mm during a 1 ms burst
and the Doppler stretch (6e-4) is common to the three microphones, both far below the delay
resolution, so motion within a burst is not modelled.
"""

import functools
import math

import numpy as np

from ._rows import row_offsets

__all__ = ["REFERENCE_DISTANCE", "REFERENCE_AMPLITUDE", "noise_std", "quantisation_step",
           "synthesise_records", "skewed_arrivals", "record_length", "quantise"]

# The SNR is defined at 1 m from the source, where the burst's peak is half the ADC full scale
# (a preamplifier gain set so that a source at 0.5 m just reaches full scale).
REFERENCE_DISTANCE = 1.0
REFERENCE_AMPLITUDE = 0.5


def noise_std(burst, snr_db, sample_rate):
    """Return the noise standard deviation for ``snr_db``.

    ``snr_db`` is the burst's mean power over its duration at the reference distance (1 m),
    divided by the noise variance over the full band 0..fs/2, in dB.
    """
    power = REFERENCE_AMPLITUDE**2 * burst.mean_power(sample_rate)
    return float(np.sqrt(power / 10.0 ** (snr_db / 10.0)))


def quantisation_step(adc_bits):
    """Return the ADC step for ``adc_bits`` over the full scale [-1, 1)."""
    return 2.0 / 2**adc_bits


def record_length(pre_roll, window, mic_spacing, speed_of_sound, sample_rate):
    """Return the samples recorded per burst: pre-roll, the largest adjacent delay, the window, slack."""
    return int(np.ceil((2.0 * pre_roll + mic_spacing / speed_of_sound + window) * sample_rate))


def synthesise_records(burst, ranges, *, sample_rate, speed_of_sound, snr_db, adc_bits,
                       pre_roll, n_samples, rng, adc_skews=None):
    """Synthesise the three microphone records of one burst, for one or many geometries.

    Parameters
    ----------
    burst : ChirpBurst
        The emitted waveform.
    ranges : array_like
        Shape (..., 3): ranges R1, R2, R3 [m] from the source to M1, M2, M3.
    sample_rate, speed_of_sound, snr_db : float
        fs [Hz], c [m/s] and the SNR at the reference distance [dB].
    adc_bits : int
        ADC resolution.
    pre_roll : float
        Time recorded before the earliest arrival [s] (noise only; the onset detector
        estimates the noise floor from it).
    n_samples : int
        Samples per record.
    rng : numpy.random.Generator
        Source of the noise; the only randomness.
    adc_skews : sequence of float, optional
        Per channel M1, M2, M3: its sampling instants' lag behind the nominal grid [s].

    Returns
    -------
    numpy.ndarray
        Shape (..., 3, n_samples): quantised samples in [-1, 1).
    """
    return _synthesise(burst, np.asarray(ranges, dtype=float), sample_rate=sample_rate,
                       speed_of_sound=speed_of_sound,
                       noise_std=noise_std(burst, snr_db, sample_rate), adc_bits=adc_bits,
                       pre_roll=pre_roll, n_samples=n_samples, rng=rng, adc_skews=adc_skews)


def _synthesise(burst, ranges, *, sample_rate, speed_of_sound, noise_std, adc_bits, pre_roll,
                n_samples, rng, adc_skews=None):
    """:func:`synthesise_records` for an array of ranges and the noise's standard deviation."""
    arrivals = ranges / speed_of_sound
    # Start on the sample grid so that the fractional part of each arrival varies with geometry.
    start = np.floor((arrivals.min(axis=-1) - pre_roll) * sample_rate) / sample_rate
    gains = REFERENCE_AMPLITUDE * REFERENCE_DISTANCE / ranges
    clean = _delayed_bursts(burst, gains, skewed_arrivals(arrivals, adc_skews), start,
                            sample_rate, n_samples)
    return _quantise(clean + noise_std * rng.standard_normal(clean.shape), adc_bits)


def skewed_arrivals(arrivals, adc_skews):
    """Arrivals (..., 3) as the skewed channels sample them: ``arrival - skew`` (see above).

    ``adc_skews`` None (or all zero) leaves ``arrivals`` as they are, bit for bit.
    """
    if adc_skews is None or not any(adc_skews):
        return arrivals
    return arrivals - np.asarray(adc_skews, dtype=float)


def _synthesise_one(burst, ranges, *, sample_rate, speed_of_sound, noise_std, adc_bits,
                    pre_roll, n_samples, rng, adc_skews=None):
    """:func:`synthesise_records` for one geometry: the same record, with fewer numpy calls.

    ``ranges`` are three floats and ``noise_std`` the value :func:`noise_std` gives for the
    SNR. The geometry's scalars are computed in Python and the burst added to the noise
    only on its span; the draws and every sample's arithmetic are those of
    :func:`synthesise_records`.
    """
    span = math.ceil(burst.duration * sample_rate) + 4
    if span >= n_samples:
        return _synthesise(burst, np.asarray(ranges, dtype=float), sample_rate=sample_rate,
                           speed_of_sound=speed_of_sound, noise_std=noise_std,
                           adc_bits=adc_bits, pre_roll=pre_roll, n_samples=n_samples, rng=rng,
                           adc_skews=adc_skews)
    arrivals = [distance / speed_of_sound for distance in ranges]
    # As in _synthesise: the start on the sample grid, each burst on a span around its arrival.
    start = math.floor((min(arrivals) - pre_roll) * sample_rate) / sample_rate
    if adc_skews is not None and any(adc_skews):
        arrivals = [arrival - skew for arrival, skew in zip(arrivals, adc_skews)]
    first = [min(max(math.floor((arrival - start) * sample_rate) - 1, 0), n_samples - span)
             for arrival in arrivals]
    # The microphones' scalars in one small array: numpy's per-call cost, not the work, counts.
    columns = np.array([[offset, arrival, REFERENCE_AMPLITUDE * REFERENCE_DISTANCE / distance]
                        for offset, arrival, distance in zip(first, arrivals, ranges)])
    # (first + j) / fs is exactly _sample_times(...)[first + j]: integers are exact floats.
    times = columns[:, :1] + _span(span)
    times /= sample_rate
    times += start
    times -= columns[:, 1:2]
    clean = burst.waveform(times)
    np.multiply(columns[:, 2:], clean, out=clean)
    records = rng.standard_normal((len(ranges), n_samples))
    records *= noise_std
    # The clean signal is zero off the spans: adding it only on them changes no sample.
    for row, offset in enumerate(first):
        span_samples = records[row, offset:offset + span]
        np.add(span_samples, clean[row], out=span_samples)
    return _quantise(records, adc_bits)


def quantise(records, adc_bits):
    """Clip ``records`` to the ADC's full scale [-1, 1) and round them to its levels, in place.

    Returns
    -------
    numpy.ndarray
        ``records``.
    """
    return _quantise(records, adc_bits)


def _quantise(records, adc_bits):
    """Clip ``records`` to the ADC's full scale and round them to its levels, in place."""
    step = quantisation_step(adc_bits)
    half = 2 ** (adc_bits - 1)
    records /= step
    np.rint(records, out=records)  # np.round without its Python wrapper
    np.maximum(records, -half, out=records)
    np.minimum(records, half - 1, out=records)
    records *= step
    return records


def _delayed_bursts(burst, gains, arrivals, start, sample_rate, n_samples):
    """``gains * burst(t_n - arrival)`` on the grid ``t_n = start + n / fs``, shape (..., 3, n).

    The burst is evaluated only on a span of samples around each arrival (its support plus
    rounding slack; zero elsewhere): the sines dominate the synthesis cost otherwise.
    """
    sample_times = _sample_times(n_samples, float(sample_rate))
    span = int(np.ceil(burst.duration * sample_rate)) + 4
    if span >= n_samples:
        times = start[..., None, None] + sample_times - arrivals[..., None]
        return gains[..., None] * burst.waveform(times)
    first = np.floor((arrivals - start[..., None]) * sample_rate).astype(int) - 1
    index = np.minimum(np.maximum(first, 0), n_samples - span)[..., None] + np.arange(span)
    times = start[..., None, None] + sample_times[index] - arrivals[..., None]
    clean = np.zeros(arrivals.shape + (n_samples,))
    # A fresh C-contiguous array: reshape(-1) is a view, so this writes into it.
    clean.reshape(-1)[row_offsets(clean.shape) + index] = gains[..., None] * burst.waveform(times)
    return clean


@functools.lru_cache(maxsize=32)
def _span(span):
    offsets = np.arange(span, dtype=float)
    offsets.setflags(write=False)
    return offsets


@functools.lru_cache(maxsize=32)
def _sample_times(n_samples, sample_rate):
    times = np.arange(n_samples) / sample_rate
    times.setflags(write=False)
    return times
