"""From three microphone records to the two delays: onsets, pair windows, band-limited GCC."""

import numpy as np

from ._rows import row_offsets
from .gcc import _estimate_pair_delays_one, estimate_pair_delays
from .onset import _detect_onsets_one, detect_onsets

__all__ = ["TdoaMeasurement", "measure_tdoas"]

# Window rows, as the pairs (u, v) = (M1, M2) and (M3, M2): the microphone of each row, the
# pair it belongs to, and the pairs' outer microphones.
_ROW_MICS = np.array([0, 1, 2, 1])
_PAIR_OF_ROW = np.array([0, 0, 1, 1])
_OUTER_MICS = np.array([0, 2])


class TdoaMeasurement:
    """Delays measured from records (arrays over the leading batch shape).

    Attributes
    ----------
    tdoa_12, tdoa_23 : numpy.ndarray
        ``t1 - t2`` and ``t3 - t2`` [s].
    quality : numpy.ndarray
        Shape (..., 2): peak quality of pairs M1-M2 and M3-M2.
    detected : numpy.ndarray of bool
        A burst onset was found on all three microphones.
    at_bound : numpy.ndarray of bool
        A pair's correlation peak sits on the +-l/c lag bound.
    """

    def __init__(self, tdoa_12, tdoa_23, quality, detected, at_bound):
        self.tdoa_12 = tdoa_12
        self.tdoa_23 = tdoa_23
        self.quality = quality
        self.detected = detected
        self.at_bound = at_bound


def measure_tdoas(records, settings):
    """Measure ``(tdoa_12, tdoa_23)`` from records of shape (..., 3, n).

    Each adjacent pair gets its own window of ``settings.window``, starting
    ``PRE_TRIGGER`` before the pair's earlier onset, so that it holds the burst at both
    microphones for any bearing (the window is checked against ``l/c`` plus the burst length).
    Within the window each record is gated to its own burst (plus a margin for onset jitter).

    Parameters
    ----------
    records : numpy.ndarray
        Shape (..., 3, n): M1, M2, M3.
    settings : LocalizerSettings

    Returns
    -------
    TdoaMeasurement
    """
    onsets, detected = detect_onsets(records, settings.template, settings.onset_threshold_db)
    if records.ndim == 2 and records.shape[-1] >= settings.window_samples:
        pairs = _pair_windows_single(records, onsets.tolist(), settings)
    else:
        pairs = _pair_windows(records, onsets, settings)
    estimate = estimate_pair_delays(pairs, settings.sample_rate, settings.passband,
                                    settings.max_lag, settings.weighting)
    return TdoaMeasurement(estimate.delay[..., 0], estimate.delay[..., 1], estimate.quality,
                           detected.all(axis=-1), estimate.at_bound.any(axis=-1))


def _measure_tdoas_one(records, settings):
    """:func:`measure_tdoas` for the records (3, n) of one burst, as Python scalars.

    The same numbers as :func:`measure_tdoas` on a (3, n) array; :attr:`TdoaMeasurement.quality`
    is a list of the two pairs' qualities.
    """
    if records.shape[-1] < settings.window_samples:
        measurement = measure_tdoas(records, settings)
        return TdoaMeasurement(float(measurement.tdoa_12), float(measurement.tdoa_23),
                               measurement.quality.tolist(), bool(measurement.detected),
                               bool(measurement.at_bound))
    onsets, detected = _detect_onsets_one(records, settings.template, settings.onset_threshold_db)
    pairs = _pair_windows_single(records, onsets, settings)
    delays, qualities, at_bound = _estimate_pair_delays_one(
        pairs, settings.sample_rate, settings.passband, settings.max_lag, settings.weighting)
    return TdoaMeasurement(delays[0], delays[1], qualities, detected, at_bound)


def _pair_windows(records, onsets, settings):
    """Return the gated windows ``[[M1, M2], [M3, M2]]`` of each burst, shape (..., 2, 2, length).

    Each pair's window starts ``pre_trigger`` before its earlier onset, clamped into the
    record. Each record is zeroed outside its own burst's ``[onset - margin, onset + burst +
    margin)``: those samples hold only noise, and left in, their noise-times-noise products
    blur the correlation (the dominant error below ~10 dB).
    """
    n, length = records.shape[-1], settings.window_samples
    first = np.minimum(onsets[..., _OUTER_MICS], onsets[..., 1:2])
    pair_starts = np.minimum(np.maximum(first - settings.pre_trigger_samples, 0), n - length)
    index = pair_starts[..., _PAIR_OF_ROW, None] + np.arange(length)
    records = np.ascontiguousarray(records)
    windows = records.reshape(-1)[row_offsets(records.shape)[..., _ROW_MICS, :] + index]
    own_onset = onsets[..., _ROW_MICS, None]
    margin = settings.gate_margin_samples
    gate = (index >= own_onset - margin) & (index < own_onset + (settings.template.size + margin))
    return (windows * gate).reshape(windows.shape[:-2] + (2, 2, length))


def _pair_windows_single(records, onsets, settings):
    """:func:`_pair_windows` for one burst (records (3, n), onsets a list of 3 ints), by slicing.

    The same windows without the index arithmetic: a fix's arrays are so small that numpy's
    per-call overhead, not the work, sets the cost.
    """
    length, margin = settings.window_samples, settings.gate_margin_samples
    pre_trigger, latest = settings.pre_trigger_samples, records.shape[-1] - length
    gates = [(onset - margin, onset + settings.template.size + margin) for onset in onsets]
    pairs = np.zeros((2, 2, length))
    for pair, outer in enumerate((0, 2)):
        start = min(max(min(onsets[outer], onsets[1]) - pre_trigger, 0), latest)
        for side, mic in enumerate((outer, 1)):
            low, high = max(start, gates[mic][0]), min(start + length, gates[mic][1])
            if high > low:
                pairs[pair, side, low - start:high - start] = records[mic, low:high]
    return pairs
