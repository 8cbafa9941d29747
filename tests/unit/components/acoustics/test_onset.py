"""Synthesised records, burst onsets and delays against the signal model and exact geometry."""

import math

import numpy as np
import pytest

from components.acoustics import (REFERENCE_AMPLITUDE, REFERENCE_DISTANCE, ChirpBurst,
                                  LocalizerSettings, detect_onsets, exact_tdoas,
                                  measure_tdoas, quantisation_step, synthesise_records)
from components.acoustics.onset import _median

FS = 100e3
SOUND = 340.0
BURST = ChirpBurst(1000.0, 16000.0, 1.0e-3)
RANGES = np.array([[2.19317122, 2.06155281, 2.00249844],    # 2 m, about 14 deg to the left
                   [1.30, 1.00, 1.25]])


def synthesise(n_samples, snr_db=300.0, seed=0, ranges=RANGES):
    return synthesise_records(BURST, ranges, sample_rate=FS, speed_of_sound=SOUND,
                              snr_db=snr_db, adc_bits=10, pre_roll=1.0e-3,
                              n_samples=n_samples, rng=np.random.default_rng(seed))


def model_records(n_samples, ranges=RANGES):
    """The module docstring's model, noise-free, evaluated on every sample of the record."""
    arrivals = ranges / SOUND
    start = np.floor((arrivals.min(axis=-1) - 1.0e-3) * FS) / FS
    times = start[:, None, None] + np.arange(n_samples) / FS - arrivals[..., None]
    clean = (REFERENCE_AMPLITUDE * REFERENCE_DISTANCE / ranges)[..., None] * BURST.waveform(times)
    step = quantisation_step(10)
    return np.clip(np.round(clean / step), -512, 511) * step


# 568: the localizer's record; 150: the burst runs past the record's end; 60: the record is
# shorter than the burst (the synthesis then evaluates the burst on every sample).
@pytest.mark.parametrize("n_samples", [568, 150, 60],
                         ids=["full", "burst_cut", "shorter_than_burst"])
def test_noise_free_records_follow_the_model(n_samples):
    # At 300 dB the noise (~1e-16) is far below half an ADC step: the records are the model's.
    np.testing.assert_array_equal(synthesise(n_samples), model_records(n_samples))


def test_noise_takes_one_normal_per_sample_in_order():
    # Same-seed runs must repeat bit for bit: the synthesis draws exactly one standard normal
    # per sample, in C order, and nothing else.
    rng = np.random.default_rng(11)
    records = synthesise_records(BURST, RANGES, sample_rate=FS, speed_of_sound=SOUND,
                                 snr_db=20.0, adc_bits=10, pre_roll=1.0e-3, n_samples=568,
                                 rng=rng)
    reference = np.random.default_rng(11)
    reference.standard_normal(records.shape)
    assert rng.standard_normal() == reference.standard_normal()


@pytest.mark.parametrize("n_samples", [568, 569], ids=["odd_envelope", "even_envelope"])
def test_onsets_at_the_burst_starts(n_samples):
    records = synthesise(n_samples, snr_db=30.0, seed=4)
    onsets, detected = detect_onsets(records, BURST.waveform(np.arange(100) / FS), 13.0)
    arrivals = RANGES / SOUND
    start = np.floor((arrivals.min(axis=-1) - 1.0e-3) * FS) / FS
    first_sample = np.ceil((arrivals - start[:, None]) * FS)
    assert detected.all()
    np.testing.assert_allclose(onsets, first_sample, atol=1)


def test_noise_alone_is_not_detected():
    records = np.random.default_rng(5).standard_normal((20, 568)) * 0.01
    _, detected = detect_onsets(records, BURST.waveform(np.arange(100) / FS), 13.0)
    assert not detected.any()


@pytest.mark.parametrize("size", [7, 8, 469], ids=["odd", "even", "record"])
def test_median_matches_numpy(size):
    values = np.random.default_rng(size).exponential(size=(2, 3, size))
    np.testing.assert_array_equal(_median(values), np.median(values, axis=-1))


def test_one_burst_measures_as_in_a_batch_and_near_the_exact_delays():
    # A single burst (records (3, n)) takes the sliced window path, a batch the indexed one.
    # 85 deg at 1 m puts M3's gate past its pair's window end (the gate is cut there).
    settings = LocalizerSettings(snr_db=30.0)
    geometry = [(1.0, 0.0), (2.0, 30.0), (3.0, -60.0), (1.0, 85.0), (4.5, -20.0)]
    mics = np.array([[0.0, 0.4], [0.0, 0.0], [0.0, -0.4]])    # (forward, left) of M1, M2, M3
    sources = np.array([[d * math.cos(math.radians(b)), d * math.sin(math.radians(b))]
                        for d, b in geometry])
    ranges = np.hypot(sources[:, None, 0] - mics[:, 0], sources[:, None, 1] - mics[:, 1])
    records = synthesise_records(
        settings.burst, ranges, sample_rate=settings.sample_rate,
        speed_of_sound=settings.speed_of_sound, snr_db=settings.snr_db,
        adc_bits=settings.adc_bits, pre_roll=settings.pre_roll,
        n_samples=settings.record_samples, rng=np.random.default_rng(2))
    batch = measure_tdoas(records, settings)
    for i, (distance, bearing) in enumerate(geometry):
        one = measure_tdoas(records[i], settings)
        assert float(one.tdoa_12) == pytest.approx(batch.tdoa_12[i], rel=1e-12, abs=1e-18)
        assert float(one.tdoa_23) == pytest.approx(batch.tdoa_23[i], rel=1e-12, abs=1e-18)
        np.testing.assert_allclose(one.quality, batch.quality[i], rtol=1e-12)
        assert bool(one.at_bound) == batch.at_bound[i]
        assert bool(one.detected) and batch.detected[i]
        true_12, true_23 = exact_tdoas(distance, math.radians(bearing), 0.4, 340.0)
        # 0.1 sample: several times the 30 dB error here (<= 0.035 sample).
        assert float(one.tdoa_12) == pytest.approx(true_12, abs=1e-6)
        assert float(one.tdoa_23) == pytest.approx(true_23, abs=1e-6)
