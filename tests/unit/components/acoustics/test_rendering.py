"""Rendering many arrivals through delayed templates, against the chirp at each exact delay."""

import math

import numpy as np
import pytest

from components.acoustics import ChirpBurst
from components.acoustics.rendering import PHASES, ArrivalRenderer

FS = 100e3
BURST = ChirpBurst(1000.0, 16000.0, 1e-3)


def exact(microphone, delay, gain, start, n_samples):
    """The sum of chirps evaluated at every sample for every arrival (the slow reference)."""
    times = start + np.arange(n_samples) / FS
    records = np.zeros((3, n_samples))
    for mic, tau, g in zip(microphone, delay, gain):
        records[mic] += g * BURST.waveform(times - tau)
    return records


def bound(phases):
    """The linear split's error at the band's top (16 kHz plus the window's 1/T)."""
    top = BURST.band_high + 1.0 / BURST.duration
    return (2.0 * math.pi * top / (phases * FS)) ** 2 / 8.0


@pytest.mark.parametrize("phases", [PHASES, 4], ids=["default", "coarse"])
def test_one_arrival_at_any_fraction_is_within_the_split_error(phases):
    renderer = ArrivalRenderer(BURST, FS, phases)
    worst = 0.0
    for fraction in np.linspace(0.0, 1.0, 97):
        delay = np.array([0.002 + fraction / FS])
        rendered = renderer.render(np.array([0]), delay, np.array([1.0]), 0.001, 400)
        worst = max(worst, np.abs(rendered - exact([0], delay, [1.0], 0.001, 400)).max())
    # Within the bound, and not far below it: the bound is the error's size.
    assert 0.3 * bound(phases) <= worst <= bound(phases)


def test_many_arrivals_add_up_within_their_bounds():
    rng = np.random.default_rng(7)
    count, n_samples, start = 400, 600, 0.0123
    microphone = rng.integers(0, 3, count)
    # Arrivals before, inside and after the record, at any fraction of a sample.
    delay = start + rng.uniform(-1.2e-3, 6.2e-3, count)
    gain = rng.uniform(-1.0, 1.0, count) / math.sqrt(count)
    rendered = ArrivalRenderer(BURST, FS).render(microphone, delay, gain, start, n_samples)
    reference = exact(microphone, delay, gain, start, n_samples)
    worst = bound(PHASES) * np.bincount(microphone, np.abs(gain), minlength=3).max()
    assert np.abs(rendered - reference).max() <= worst
    assert np.abs(reference).max() > 100.0 * worst


def test_one_arrival_on_a_sample_is_the_burst_itself():
    rendered = ArrivalRenderer(BURST, FS).render(np.array([1]), np.array([0.005]),
                                                 np.array([0.5]), 0.004, 300)
    reference = exact([1], [0.005], [0.5], 0.004, 300)
    np.testing.assert_allclose(rendered, reference, atol=1e-12)
    assert not rendered[0].any() and not rendered[2].any()


def templates_added(renderer, microphone, delay, gain, start, n_samples):
    """Each arrival's two bracketing templates added sample by sample (the slow reference)."""
    phases, offsets = renderer.phases, np.arange(renderer.span)
    templates = BURST.waveform((offsets[None, :] - np.arange(phases + 1)[:, None] / phases) / FS)
    records = np.zeros((3, n_samples))
    for mic, tau, g in zip(microphone, delay, gain):
        position = (tau - start) * FS
        whole = math.floor(position)
        fraction = (position - whole) * phases
        phase = math.floor(fraction)
        weight = fraction - phase
        shape = (1.0 - weight) * templates[phase] + weight * templates[phase + 1]
        samples = whole + offsets
        inside = (samples >= 0) & (samples < n_samples)
        records[mic, samples[inside]] += g * shape[inside]
    return records


@pytest.mark.parametrize("phases", [PHASES, 4], ids=["default", "coarse"])
def test_the_transforms_add_the_templates_exactly(phases):
    # The same split as the reference, so the two agree to rounding: arrivals before, inside
    # and after the record, on and between samples and sub-sample delays.
    rng = np.random.default_rng(5)
    count, n_samples, start = 3000, 568, 0.0041
    microphone = rng.integers(0, 3, count)
    delay = start + rng.uniform(-1.3e-3, 6.0e-3, count)
    whole = rng.integers(-110, 580, 200) / FS
    delay[:200] = start + whole + np.repeat([0.0, 1.0], 100) * rng.integers(0, 16, 200) / (16 * FS)
    gain = rng.uniform(-1.0, 1.0, count)
    renderer = ArrivalRenderer(BURST, FS, phases)
    rendered = renderer.render(microphone, delay, gain, start, n_samples)
    reference = templates_added(renderer, microphone, delay, gain, start, n_samples)
    assert np.abs(rendered - reference).max() <= 1e-12 * np.abs(reference).max()
