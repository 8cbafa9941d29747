"""Band-limited GCC against known fractional delays made by an independent FFT phase shift."""

import numpy as np
import pytest

from components.acoustics import estimate_delays

FS = 100e3
BAND = (2500.0, 14500.0)  # inside the test signal's 2-15 kHz band


def band_noise_pair(delay_samples, n=250, seed=3):
    """A band-limited noise burst ``v`` and ``u``, the same burst delayed by ``delay_samples``.

    The burst is band-limited after tapering, so the FFT phase shift is an exact delay of it.
    """
    rng = np.random.default_rng(seed)
    n_fft = 4096
    freqs = np.fft.rfftfreq(n_fft, 1.0 / FS)
    burst = np.zeros(n_fft)
    burst[1000:1120] = rng.standard_normal(120) * np.hanning(120)
    spectrum = np.fft.rfft(burst) * ((freqs > 2000) & (freqs < 15000))
    base = np.fft.irfft(spectrum, n_fft)
    shifted = np.fft.irfft(spectrum * np.exp(-2j * np.pi * freqs * delay_samples / FS), n_fft)
    # Both windows start 10 samples before the earlier copy, as after onset detection.
    start = 1000 + min(0, int(np.floor(delay_samples))) - 10
    return shifted[start:start + n], base[start:start + n]


@pytest.mark.parametrize("delay", [0.0, 0.25, -0.5, 3.37, -11.81, 42.5, -97.04],
                         ids=["zero", "quarter", "minus_half", "3.37", "-11.81", "42.5", "-97.04"])
@pytest.mark.parametrize("weighting", ["band", "phat"])
def test_recovers_known_fractional_delay(delay, weighting):
    u, v = band_noise_pair(delay)
    estimate = estimate_delays(u, v, FS, BAND, 0.4 / 340.0, weighting)
    # Only the band-limited burst's far tails are cut by the window: 0.01 sample bounds that.
    assert float(estimate.delay) * FS == pytest.approx(delay, abs=0.01)
    assert not bool(estimate.at_bound)
    assert float(estimate.quality) > 0.95


def test_batched_matches_single():
    pairs = [band_noise_pair(d, seed=s) for d, s in ((1.3, 1), (-7.7, 2), (20.2, 4))]
    u = np.stack([p[0] for p in pairs])
    v = np.stack([p[1] for p in pairs])
    batched = estimate_delays(u, v, FS, BAND, 0.4 / 340.0).delay * FS
    np.testing.assert_allclose(batched, [1.3, -7.7, 20.2], atol=0.01)


def test_delay_beyond_bound_is_flagged():
    # The main lobe's top lies 0.4 sample outside the +-20 sample bound: the integer peak
    # lands on the bound and the refined delay is clamped to it.
    u, v = band_noise_pair(20.4)
    estimate = estimate_delays(u, v, FS, BAND, 20.0 / FS)
    assert bool(estimate.at_bound)
    assert abs(float(estimate.delay)) <= 20.0 / FS


def test_unknown_weighting_lists_choices():
    u, v = band_noise_pair(1.0)
    with pytest.raises(ValueError, match="valid choices: band, phat"):
        estimate_delays(u, v, FS, BAND, 1e-3, "scot")
