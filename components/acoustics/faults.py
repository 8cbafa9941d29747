"""Acoustic faults on the microphone records, and the checks that catch the untrustworthy ones.

:func:`faulted_records` synthesises one burst's three records as
:func:`~.synthesis.synthesise_records` does, with the faults active at the fix applied where
they happen physically: a reflecting wall adds the burst from the image source (mirrored in
the wall, amplitude times :data:`~..common.faults.REFLECTION_COEFFICIENT`, its own 1/r) before
the microphones; ``low_snr`` raises the noise; impulsive noise adds clicks; a gain error scales
a channel in its preamplifier; clipping flattens it at a level below the ADC's full scale; a
dead microphone gives a record of zeros. It is used only while a fault is active, so a run
without faults keeps the fast path's numbers bit for bit.

:func:`channel_fault` is the localizer's own check of each record (it does not know the
schedule): a record that never leaves zero by two ADC steps is a dead channel; one whose
largest magnitude, below the ADC's full scale, is held by :data:`CLIP_RUN` or more samples is
clipped. Neither can give a trusted delay, so the fix is refused.
"""

import math

import numpy as np

from ..common.faults import IMPULSES_PER_RECORD, MICROPHONES, REFLECTION_COEFFICIENT
from .synthesis import (REFERENCE_AMPLITUDE, REFERENCE_DISTANCE, _delayed_bursts, _quantise,
                        noise_std, quantisation_step, skewed_arrivals)

__all__ = ["faulted_records", "apply_record_faults", "channel_fault", "drops_fix", "mirror_in_wall", "CLIP_RUN",
           "CLIP_MIN_STEPS", "DEAD_SPAN_STEPS", "CLICK_DECAY_SAMPLES"]

# Samples held at one extreme that mark a clipped record: a Hann-windowed chirp sampled at
# 100 kHz has at most 2-3 samples within half an ADC step of its peak.
CLIP_RUN = 8
# Flat tops mean something only with this many ADC steps under the peak (a coarse ADC's
# levels are flat everywhere).
CLIP_MIN_STEPS = 16
# A live microphone's record spans at least its self-noise; fewer ADC steps than this: dead.
DEAD_SPAN_STEPS = 2
# A click decays by 1/e over this many samples (a 50 us broadband pulse at 100 kHz).
CLICK_DECAY_SAMPLES = 5.0


def mirror_in_wall(x, y, wall_x):
    """The image of the point (x, y) in a wall along the line ``x = wall_x``."""
    return 2.0 * wall_x - x, y


def drops_fix(index, fraction):
    """Whether fix attempt ``index`` is lost when ``fraction`` of them are (0.5: every other).

    Deterministic: exactly ``floor((index + 1) f) - floor(index f)`` attempts of each are lost,
    so any ``index`` stretch loses ``fraction`` of its attempts up to one.
    """
    return math.floor((index + 1) * fraction) > math.floor(index * fraction)


def faulted_records(settings, ranges, image_ranges, faults, rng, clean=None):
    """Three microphone records of one burst with the active faults applied.

    Parameters
    ----------
    settings : LocalizerSettings
    ranges : sequence of float
        True ranges R1, R2, R3 [m] from the source.
    image_ranges : sequence of float or None
        Ranges from the image source in a reflecting wall, or None without a wall.
    faults : sequence of Fault
        The acoustic faults active at this fix (``lost_fixes`` is handled by the caller).
    rng : numpy.random.Generator
    clean : numpy.ndarray, optional
        Shape (3, n): the noise-free records without the wall (a room's, sampled with the
        settings' ``adc_skews`` already); by default the free field's direct sound from
        ``ranges``. The wall's image and the free field's sound are sampled with the skews.

    Returns
    -------
    numpy.ndarray
        Shape (3, n): quantised samples in [-1, 1).
    """
    s = settings
    n = s.record_samples
    ranges = np.asarray(ranges, dtype=float)
    arrivals = ranges / s.speed_of_sound
    start = np.asarray(np.floor((arrivals.min() - s.pre_roll) * s.sample_rate) / s.sample_rate)
    if clean is None:
        gains = REFERENCE_AMPLITUDE * REFERENCE_DISTANCE / ranges
        clean = _delayed_bursts(s.burst, gains, skewed_arrivals(arrivals, s.adc_skews), start,
                                s.sample_rate, n)
    if image_ranges is not None:
        image = np.asarray(image_ranges, dtype=float)
        image_gains = REFLECTION_COEFFICIENT * REFERENCE_AMPLITUDE * REFERENCE_DISTANCE / image
        clean = clean + _delayed_bursts(
            s.burst, image_gains, skewed_arrivals(image / s.speed_of_sound, s.adc_skews), start,
            s.sample_rate, n)
    return apply_record_faults(settings, clean, faults, rng)


def apply_record_faults(settings, clean, faults, rng):
    """Noise (raised by ``low_snr``), clicks, gain errors, clipping, the ADC, dead channels.

    Parameters
    ----------
    settings : LocalizerSettings
    clean : numpy.ndarray
        Shape (3, n): noise-free records.
    faults : sequence of Fault
    rng : numpy.random.Generator

    Returns
    -------
    numpy.ndarray
        Shape (3, n): quantised samples in [-1, 1).
    """
    s = settings
    n = clean.shape[-1]
    sigma = s.noise_std
    for fault in faults:
        if fault.kind == "low_snr":
            sigma = max(sigma, noise_std(s.burst, fault.magnitude, s.sample_rate))
    records = clean + sigma * rng.standard_normal((3, n))
    for fault in faults:
        if fault.kind == "impulsive_noise":
            positions = rng.integers(0, n, size=(3, IMPULSES_PER_RECORD))
            signs = rng.choice((-1.0, 1.0), size=(3, IMPULSES_PER_RECORD))
            tail = np.exp(-np.arange(n) / CLICK_DECAY_SAMPLES)
            for mic in range(3):
                for position, sign in zip(positions[mic], signs[mic]):
                    records[mic, position:] += sign * fault.magnitude * tail[:n - position]
        elif fault.kind == "mic_gain":
            records[MICROPHONES.index(fault.channel)] *= fault.magnitude
    for fault in faults:
        if fault.kind == "mic_clipping":
            row = records[MICROPHONES.index(fault.channel)]
            np.clip(row, -fault.magnitude, fault.magnitude, out=row)
    records = _quantise(records, s.adc_bits)
    for fault in faults:
        if fault.kind == "mic_dead":
            records[MICROPHONES.index(fault.channel)] = 0.0
    return records


def channel_fault(records, adc_bits):
    """The localizer's check of each record: ``(dead, clipped)`` microphone indices or None.

    Parameters
    ----------
    records : numpy.ndarray
        Shape (3, n), quantised.
    adc_bits : int

    Returns
    -------
    tuple
        ``(first dead channel or None, first clipped channel or None)``, 0-based.
    """
    step = quantisation_step(adc_bits)
    full_scale = 1.0 - 2.0 * step
    dead = clipped = None
    for mic in range(records.shape[0]):
        row = records[mic]
        high, low = row.max(), row.min()
        if high - low < DEAD_SPAN_STEPS * step:
            dead = mic if dead is None else dead
            continue
        peak = max(high, -low)
        if (CLIP_MIN_STEPS * step <= peak < full_scale
                and np.count_nonzero(np.abs(row) >= peak - 0.5 * step) >= CLIP_RUN):
            clipped = mic if clipped is None else clipped
    return dead, clipped
