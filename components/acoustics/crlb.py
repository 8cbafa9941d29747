"""Cramer-Rao bounds: the delays for the source band, then range and bearing through the geometry.

Model: microphone ``i`` records ``g_i s(t - t_i)`` plus white Gaussian noise of variance
``sigma^2`` (the additive noise plus the ADC's ``step^2 / 12``); the waveform ``s`` is treated
as unknown (the estimator does not use it), so only differences of arrival times are
identifiable. With ``E = sum_n s'(nT)^2`` over the source band, the Fisher information on
``(t1, t2, t3)`` is ``(E / sigma^2) (diag(g^2) - g^2 g^2^T / sum g^2)``. Writing
``t1 = t2 + tdoa_12`` and ``t3 = t2 + tdoa_23``, the information on the two delays is the
(1, 3) block of that matrix; its inverse is their covariance bound. Both delays share M2, so
they are correlated (for equal gains the bound is ``[[2, 1], [1, 2]] / (g^2 E / sigma^2)``).
Range and bearing bounds carry that covariance through the exact geometry's Jacobian.
"""

import numpy as np

from .synthesis import REFERENCE_AMPLITUDE, REFERENCE_DISTANCE

__all__ = ["band_derivative_energy", "tdoa_covariance_bound", "geometry_jacobian",
           "range_bearing_covariance_bound"]


def band_derivative_energy(burst, sample_rate, passband):
    """Return ``sum_n s'(nT)^2`` of the unit burst, counting only the ``passband`` [1/s^2 * samples].

    Computed from the sampled burst's spectrum (Parseval), so it is the information an
    estimator that weights only the band can use.
    """
    n_fft = 1 << int(np.ceil(np.log2(8 * burst.duration * sample_rate + 64)))
    t = np.arange(n_fft) / sample_rate
    spectrum = np.fft.rfft(burst.waveform(t))
    freqs = np.fft.rfftfreq(n_fft, 1.0 / sample_rate)
    inside = (freqs >= passband[0]) & (freqs <= passband[1])
    fold = np.where((freqs == 0.0) | (np.arange(freqs.size) == n_fft // 2), 1.0, 2.0)
    return float(np.sum((fold * (2.0 * np.pi * freqs) ** 2 * np.abs(spectrum) ** 2)[inside]) / n_fft)


def tdoa_covariance_bound(ranges, derivative_energy, noise_variance):
    """Return the Cramer-Rao covariance of ``(tdoa_12, tdoa_23)`` [s^2].

    Parameters
    ----------
    ranges : array_like
        Shape (..., 3): R1, R2, R3 [m]; the gains follow 1/r spreading from the reference.
    derivative_energy : float
        :func:`band_derivative_energy` of the unit burst.
    noise_variance : float
        Per-sample noise variance, additive plus quantisation.

    Returns
    -------
    numpy.ndarray
        Shape (..., 2, 2).
    """
    gains = REFERENCE_AMPLITUDE * REFERENCE_DISTANCE / np.asarray(ranges, dtype=float)
    weights = gains**2
    fisher = (derivative_energy / noise_variance) * (
        weights[..., :, None] * np.eye(3)
        - weights[..., :, None] * weights[..., None, :] / weights.sum(axis=-1)[..., None, None])
    delays = fisher[..., [0, 2], :][..., :, [0, 2]]
    return np.linalg.inv(delays)


def _exact(tdoa_12, tdoa_23, spacing, speed_of_sound):
    a = speed_of_sound * tdoa_12
    b = speed_of_sound * tdoa_23
    distance = (2.0 * spacing**2 - a * a - b * b) / (2.0 * (a + b))
    bearing = np.arcsin((b - a) * (2.0 * distance + a + b) / (4.0 * spacing * distance))
    return distance, bearing


def geometry_jacobian(tdoa_12, tdoa_23, spacing, speed_of_sound):
    """Return d(distance, bearing)/d(tdoa_12, tdoa_23) of the exact geometry, shape (..., 2, 2).

    Complex-step differentiation: exact to rounding, no step-size trade-off.
    """
    tdoa_12 = np.asarray(tdoa_12, dtype=complex)
    tdoa_23 = np.asarray(tdoa_23, dtype=complex)
    step = 1e-30
    columns = []
    for d12, d23 in ((1j * step, 0.0), (0.0, 1j * step)):
        distance, bearing = _exact(tdoa_12 + d12, tdoa_23 + d23, spacing, speed_of_sound)
        columns.append(np.stack([distance.imag, bearing.imag], axis=-1) / step)
    return np.stack(columns, axis=-1)


def range_bearing_covariance_bound(tdoa_covariance, tdoa_12, tdoa_23, spacing, speed_of_sound):
    """Return the covariance bound of ``(distance, bearing)`` [m^2, rad^2], shape (..., 2, 2)."""
    jacobian = geometry_jacobian(tdoa_12, tdoa_23, spacing, speed_of_sound)
    return jacobian @ tdoa_covariance @ np.swapaxes(jacobian, -1, -2)
