"""Cramer-Rao bounds against closed forms, and the estimator's accuracy against the bounds."""

import math

import numpy as np
import pytest

from components.acoustics import (ChirpBurst, LocalizerSettings, band_derivative_energy,
                                  exact_tdoas, geometry_jacobian, locate_bursts, make_estimator,
                                  range_bearing_covariance_bound, tdoa_covariance_bound)

FS = 100e3


def test_derivative_energy_matches_integral():
    # With the band wide open, sum_n s'(nT)^2 = fs * integral s'(t)^2 dt for a smooth burst.
    burst = ChirpBurst(1000.0, 16000.0, 1e-3)
    t = np.linspace(0.0, 1e-3, 200001)
    integral = np.trapezoid(burst.derivative(t) ** 2, t)
    assert band_derivative_energy(burst, FS, (0.0, FS / 2)) == pytest.approx(FS * integral, rel=1e-4)


def test_derivative_is_derivative_of_waveform():
    burst = ChirpBurst(1000.0, 16000.0, 1e-3)
    t = np.linspace(1e-5, 0.99e-3, 57)
    h = 1e-9
    numeric = (burst.waveform(t + h) - burst.waveform(t - h)) / (2 * h)
    np.testing.assert_allclose(burst.derivative(t), numeric, rtol=1e-5, atol=1e-3)


def test_equal_gains_give_shared_centre_covariance():
    # Three equal gains g, information J = g^2 E / sigma^2 per arrival time:
    # cov(tdoa_12, tdoa_23) = [[2, 1], [1, 2]] / J.
    energy, variance = 3.0e10, 2.0e-4
    covariance = tdoa_covariance_bound(np.full(3, 1.0), energy, variance)
    information = 0.5**2 * energy / variance
    np.testing.assert_allclose(covariance, np.array([[2.0, 1.0], [1.0, 2.0]]) / information,
                               rtol=1e-12)


@pytest.mark.parametrize("distance, bearing", [(2.0, 0.0), (1.0, 0.5), (3.0, -1.0)],
                         ids=["2m_0", "1m_0.5rad", "3m_-1rad"])
def test_jacobian_matches_finite_differences(distance, bearing):
    tdoa_12, tdoa_23 = exact_tdoas(distance, bearing, 0.4, 340.0)
    jacobian = geometry_jacobian(tdoa_12, tdoa_23, 0.4, 340.0)
    estimator = make_estimator("exact", 0.4, 340.0)
    h = 1e-9
    for column, (d12, d23) in enumerate(((h, 0.0), (0.0, h))):
        plus = estimator.locate(tdoa_12 + d12, tdoa_23 + d23)
        minus = estimator.locate(tdoa_12 - d12, tdoa_23 - d23)
        numeric = [(plus.distance - minus.distance) / (2 * h),
                   (plus.bearing - minus.bearing) / (2 * h)]
        np.testing.assert_allclose(jacobian[:, column], np.ravel(numeric), rtol=1e-5)


@pytest.mark.parametrize("snr_db, distance, bearing_deg", [(20.0, 2.0, 0.0), (10.0, 1.0, 30.0)],
                         ids=["20dB_2m_broadside", "10dB_1m_30deg"])
def test_monte_carlo_sits_at_the_bound(snr_db, distance, bearing_deg):
    settings = LocalizerSettings(snr_db=snr_db)
    bearing = math.radians(bearing_deg)
    mics = np.array([[0.0, 0.4], [0.0, 0.0], [0.0, -0.4]])  # (forward, left) of M2
    source = distance * np.array([math.cos(bearing), math.sin(bearing)])
    ranges = np.hypot(*(source - mics).T)
    trials = 300
    fixes = locate_bursts(settings, make_estimator("exact", 0.4, 340.0),
                          np.tile(ranges, (trials, 1)), np.random.default_rng(11))
    assert fixes.valid.all()
    true_12, true_23 = exact_tdoas(distance, bearing, 0.4, 340.0)
    energy = band_derivative_energy(settings.burst, FS, settings.passband)
    tdoa_cov = tdoa_covariance_bound(ranges, energy, settings.noise_variance)
    rmse_12 = np.sqrt(np.mean((fixes.tdoa_12 - true_12) ** 2))
    rmse_23 = np.sqrt(np.mean((fixes.tdoa_23 - true_23) ** 2))
    # An unbiased estimator cannot beat the bound; 300 trials resolve the RMSE to ~+-8 %.
    assert 0.85 * math.sqrt(tdoa_cov[0, 0]) < rmse_12 < 1.3 * math.sqrt(tdoa_cov[0, 0])
    assert 0.85 * math.sqrt(tdoa_cov[1, 1]) < rmse_23 < 1.3 * math.sqrt(tdoa_cov[1, 1])
    bound = range_bearing_covariance_bound(tdoa_cov, true_12, true_23, 0.4, 340.0)
    range_rmse = np.sqrt(np.mean((fixes.distance - distance) ** 2))
    bearing_rmse = np.sqrt(np.mean((fixes.bearing - bearing) ** 2))
    assert range_rmse < 1.3 * math.sqrt(bound[0, 0])
    assert bearing_rmse < 1.3 * math.sqrt(bound[1, 1])
