"""From three microphone records to the two delays: onsets, pair windows, band-limited GCC."""

import numpy as np

from .gcc import estimate_delays
from .onset import detect_onsets

__all__ = ["TdoaMeasurement", "measure_tdoas"]


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


def _gated_segments(records, starts, onsets, length, burst_samples, margin):
    """Cut ``length`` samples from ``starts``, zeroed outside this record's own burst.

    Samples outside ``[onset - margin, onset + burst + margin)`` hold only noise; left in,
    their noise-times-noise products blur the correlation (the dominant error below ~10 dB).
    """
    index = starts[..., None] + np.arange(length)
    segment = np.take_along_axis(records, index, axis=-1)
    gate = (index >= (onsets - margin)[..., None]) & (index < (onsets + burst_samples + margin)[..., None])
    return segment * gate


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
    n = records.shape[-1]
    onsets, detected = detect_onsets(records, settings.template, settings.onset_threshold_db)
    length = settings.window_samples
    latest = n - length
    start_12 = np.clip(np.minimum(onsets[..., 0], onsets[..., 1]) - settings.pre_trigger_samples,
                       0, latest)
    start_32 = np.clip(np.minimum(onsets[..., 2], onsets[..., 1]) - settings.pre_trigger_samples,
                       0, latest)
    burst, margin = settings.template.size, settings.gate_margin_samples
    u = np.stack([
        _gated_segments(records[..., 0, :], start_12, onsets[..., 0], length, burst, margin),
        _gated_segments(records[..., 2, :], start_32, onsets[..., 2], length, burst, margin)],
        axis=-2)
    centre = [_gated_segments(records[..., 1, :], start, onsets[..., 1], length, burst, margin)
              for start in (start_12, start_32)]
    v = np.stack(centre, axis=-2)
    estimate = estimate_delays(u, v, settings.sample_rate, settings.passband, settings.max_lag,
                               settings.weighting)
    return TdoaMeasurement(estimate.delay[..., 0], estimate.delay[..., 1], estimate.quality,
                           detected.all(axis=-1), estimate.at_bound.any(axis=-1))
