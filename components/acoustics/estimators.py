"""Range and bearing from the two delays: one base class, a registry by name.

Each estimator validates the delays (finite, physically possible), then computes
``(distance, bearing)`` from the array centre M2. Three are registered:

``exact``
    The exact near-field geometry (docs/errata.md, Eqs. 4-5):
    ``D = (2 l^2 - a^2 - b^2) / (2 (a + b))``, ``sin(bearing) = (b - a)(2D + a + b) / (4 l D)``,
    with ``a = c tdoa_12``, ``b = c tdoa_23``.
``paper``
    The paper as printed: range from Eq. (4), bearing from the far-field Eq. (5).
``far_field``
    Exact range, far-field bearing (Eq. 5): the mean of the two adjacent-pair angles.
"""

import math

import numpy as np

from ..common.errors import InputError, ParameterError

__all__ = ["Location", "PositionEstimator", "ExactNearField", "PaperEq4", "FarField",
           "ESTIMATORS", "register_estimator", "make_estimator", "far_field_pair_bearings"]


class Location:
    """Range and bearing from M2 (arrays of one shape) and why each is or is not consistent.

    Attributes
    ----------
    distance : numpy.ndarray
        Range from M2 [m]; NaN where no consistent solution exists.
    bearing : numpy.ndarray
        Bearing, left positive [rad]; NaN where no consistent solution exists.
    consistent : numpy.ndarray of bool
        A real solution in front of the array exists.
    """

    def __init__(self, distance, bearing, consistent):
        self.distance = distance
        self.bearing = bearing
        self.consistent = consistent


class PositionEstimator:
    """Base class: :meth:`locate` validates, then calls :meth:`_compute`.

    Parameters
    ----------
    mic_spacing : float
        ``l`` [m].
    speed_of_sound : float
        ``c`` [m/s].
    """

    name = None

    def __init__(self, mic_spacing, speed_of_sound):
        problems = []
        if not (np.isfinite(mic_spacing) and mic_spacing > 0.0):
            problems.append(f"mic_spacing = {mic_spacing!r} m must be finite and > 0")
        if not (np.isfinite(speed_of_sound) and speed_of_sound > 0.0):
            problems.append(f"speed_of_sound = {speed_of_sound!r} m/s must be finite and > 0")
        if problems:
            raise ParameterError(f"{type(self).__name__}: " + "; ".join(problems))
        self.mic_spacing = float(mic_spacing)
        self.speed_of_sound = float(speed_of_sound)

    def locate(self, tdoa_12, tdoa_23):
        """Return the :class:`Location` for delays ``tdoa_12 = t1 - t2``, ``tdoa_23 = t3 - t2`` [s].

        Raises
        ------
        InputError
            A delay is NaN or infinite.
        """
        tdoa_12 = np.asarray(tdoa_12, dtype=float)
        tdoa_23 = np.asarray(tdoa_23, dtype=float)
        for port, value in (("tdoa_12", tdoa_12), ("tdoa_23", tdoa_23)):
            if not np.isfinite(value).all():
                bad = value[~np.isfinite(value)].ravel()[0] if value.ndim else value
                raise InputError(f"{self.name} estimator: {port} = {float(bad)!r} s is not finite")
        a = self.speed_of_sound * tdoa_12
        b = self.speed_of_sound * tdoa_23
        # |R_i - R_2| <= l for any source (triangle inequality); equality means endfire.
        possible = (np.abs(a) < self.mic_spacing) & (np.abs(b) < self.mic_spacing)
        with np.errstate(divide="ignore", invalid="ignore"):
            distance, bearing, consistent = self._compute(a, b)
        consistent = consistent & possible & np.isfinite(distance) & np.isfinite(bearing)
        return Location(np.where(consistent, distance, np.nan),
                        np.where(consistent, bearing, np.nan), consistent)

    def locate_one(self, tdoa_12, tdoa_23):
        """:meth:`locate` for one pair of float delays, as Python scalars.

        Returns
        -------
        tuple
            ``(distance, bearing, consistent)``: floats (NaN where inconsistent) and a bool.

        Raises
        ------
        InputError
            A delay is NaN or infinite.
        """
        for port, value in (("tdoa_12", tdoa_12), ("tdoa_23", tdoa_23)):
            if not math.isfinite(value):
                raise InputError(f"{self.name} estimator: {port} = {float(value)!r} s is not finite")
        a = self.speed_of_sound * tdoa_12
        b = self.speed_of_sound * tdoa_23
        if abs(a) < self.mic_spacing and abs(b) < self.mic_spacing:
            distance, bearing, consistent = self._compute_one(a, b)
            if consistent and math.isfinite(distance) and math.isfinite(bearing):
                return distance, bearing, True
        return math.nan, math.nan, False

    def _compute(self, a, b):
        """Return ``(distance, bearing, consistent)`` from range differences ``a``, ``b`` [m]."""
        raise NotImplementedError

    def _compute_one(self, a, b):
        """:meth:`_compute` for float ``a``, ``b``; returns floats and a bool.

        Subclasses override it with the same arithmetic in Python scalars (a fix's numpy
        calls on 0-d arrays cost more than the work); this default calls :meth:`_compute`.
        """
        with np.errstate(divide="ignore", invalid="ignore"):
            distance, bearing, consistent = self._compute(np.float64(a), np.float64(b))
        return float(distance), float(bearing), bool(consistent)


def _unit_clamp(x):
    """``np.clip(x, -1, 1)`` at a fraction of its call overhead (it runs every fix)."""
    return np.minimum(np.maximum(x, -1.0), 1.0)


def _exact_range(a, b, spacing):
    return (2.0 * spacing**2 - a * a - b * b) / (2.0 * (a + b))


def far_field_pair_bearings(a, b, spacing):
    """Return the bearings of Eq. (5-a) and (5-b) alone (left positive) [rad].

    Eq. (5) gives the angle from the array axis, ``acos(c dt / l)``; M1 is on the left, so pair
    M1-M2 gives ``bearing = theta_1 - pi/2`` and pair M2-M3 gives ``bearing = pi/2 - theta_2``.
    """
    theta_1 = np.arccos(_unit_clamp(a / spacing))
    theta_2 = np.arccos(_unit_clamp(b / spacing))
    return theta_1 - 0.5 * np.pi, 0.5 * np.pi - theta_2


def _far_field_bearing_one(a, b, spacing):
    """The mean of :func:`far_field_pair_bearings` for float ``a``, ``b``."""
    # np.arccos, not math.acos: the libraries' results differ in the last bit.
    theta_1 = float(np.arccos(min(max(a / spacing, -1.0), 1.0)))
    theta_2 = float(np.arccos(min(max(b / spacing, -1.0), 1.0)))
    return 0.5 * ((theta_1 - 0.5 * np.pi) + (0.5 * np.pi - theta_2))


class ExactNearField(PositionEstimator):
    """Exact near-field range and bearing (the default)."""

    name = "exact"

    def _compute(self, a, b):
        spacing = self.mic_spacing
        distance = _exact_range(a, b, spacing)
        sine = (b - a) * (2.0 * distance + a + b) / (4.0 * spacing * distance)
        consistent = (a + b > 0.0) & (distance > 0.0) & (np.abs(sine) <= 1.0)
        return distance, np.arcsin(_unit_clamp(sine)), consistent

    def _compute_one(self, a, b):
        spacing = self.mic_spacing
        # Short-circuits where _compute divides by zero: those are inconsistent anyway.
        if not a + b > 0.0:
            return math.nan, math.nan, False
        distance = _exact_range(a, b, spacing)
        if not distance > 0.0:
            return distance, math.nan, False
        sine = (b - a) * (2.0 * distance + a + b) / (4.0 * spacing * distance)
        # np.arcsin, not math.asin: the libraries' results differ in the last bit.
        return distance, float(np.arcsin(min(max(sine, -1.0), 1.0))), abs(sine) <= 1.0


class PaperEq4(PositionEstimator):
    """The paper as printed: Eq. (4) range, far-field Eq. (5) bearing (comparison only)."""

    name = "paper"

    def _compute(self, a, b):
        # Eq. (4) with c*dt_12 = a and c*dt_23 = b (the paper's Eq. 1 convention).
        spacing = self.mic_spacing
        distance = (spacing**2 + spacing * (a + b) - (a * a + a * b + b * b)) / (2.0 * (a + b))
        left, right = far_field_pair_bearings(a, b, spacing)
        consistent = (a + b > 0.0) & (distance > 0.0)
        return distance, 0.5 * (left + right), consistent

    def _compute_one(self, a, b):
        if not a + b > 0.0:
            return math.nan, math.nan, False
        spacing = self.mic_spacing
        distance = (spacing**2 + spacing * (a + b) - (a * a + a * b + b * b)) / (2.0 * (a + b))
        return distance, _far_field_bearing_one(a, b, spacing), distance > 0.0


class FarField(PositionEstimator):
    """Exact range with the far-field bearing of Eq. (5) (comparison only)."""

    name = "far_field"

    def _compute(self, a, b):
        distance = _exact_range(a, b, self.mic_spacing)
        left, right = far_field_pair_bearings(a, b, self.mic_spacing)
        return distance, 0.5 * (left + right), (a + b > 0.0) & (distance > 0.0)

    def _compute_one(self, a, b):
        if not a + b > 0.0:
            return math.nan, math.nan, False
        distance = _exact_range(a, b, self.mic_spacing)
        return distance, _far_field_bearing_one(a, b, self.mic_spacing), distance > 0.0


ESTIMATORS = {}


def register_estimator(cls):
    """Add a :class:`PositionEstimator` subclass to :data:`ESTIMATORS` under ``cls.name``."""
    if not (isinstance(cls, type) and issubclass(cls, PositionEstimator) and cls.name):
        raise ParameterError(f"cannot register {cls!r}: not a named PositionEstimator subclass")
    ESTIMATORS[cls.name] = cls
    return cls


for _cls in (ExactNearField, PaperEq4, FarField):
    register_estimator(_cls)


def make_estimator(method, mic_spacing, speed_of_sound):
    """Return the estimator registered as ``method``.

    Raises
    ------
    ParameterError
        ``method`` is not registered; the message lists the valid choices.
    """
    if method not in ESTIMATORS:
        raise ParameterError(f"method = {method!r}; valid choices: {', '.join(sorted(ESTIMATORS))}")
    return ESTIMATORS[method](mic_spacing, speed_of_sound)
