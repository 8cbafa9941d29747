"""Centre-of-gravity defuzzification over the output sets Small and Big.

With Mamdani max-min inference the aggregated output set is
``mu(y) = max(min(s, 1 - y), min(b, y))`` on [0, 1], where ``s`` and ``b`` are the strongest
firing of any rule concluding Small and Big. Its centroid has a closed form (no sampling):
``max(S, B) = S + B - min(S, B)``, and ``min(S, B) = min(m, y, 1 - y)`` with ``m = min(s, b)``
is a clipped tent symmetric about 1/2, so every area and moment is a polynomial in s, b and m.
"""

import numpy as np

__all__ = ["exact_centroid", "discrete_centroid", "weighted_average"]


def _clipped_small_area(h):
    # Area of min(h, 1 - y) on [0, 1].
    return h - 0.5 * h * h


def _clipped_small_moment(h):
    # First moment of min(h, 1 - y) on [0, 1]: (1 - (1 - h)^3) / 6.
    q = 1.0 - h
    return (1.0 - q * q * q) / 6.0


def exact_centroid(small, big):
    """Exact centroid of the max-aggregated, min-clipped Small and Big sets.

    Parameters
    ----------
    small, big : float
        Firing strengths in [0, 1] of the output sets Small (triangle (0, 0, 1)) and Big
        (triangle (0, 1, 1)); at least one must be positive.

    Returns
    -------
    float
        The centroid, in [1/3, 2/3].

    Examples
    --------
    >>> exact_centroid(1.0, 0.0)  # the centroid of triangle (0, 0, 1)
    0.3333333333333333
    """
    overlap = small if small < big else big
    if overlap > 0.5:
        overlap = 0.5  # the tent min(y, 1 - y) never exceeds 1/2
    tent_area = overlap * (1.0 - overlap)
    area_small = _clipped_small_area(small)
    area_big = _clipped_small_area(big)
    area = area_small + area_big - tent_area
    # Big is Small mirrored about y = 1/2: moment_big = area_big - moment_small(big).
    moment = (_clipped_small_moment(small) + area_big - _clipped_small_moment(big)
              - 0.5 * tent_area)
    return moment / area


def discrete_centroid(small, big, universe):
    """Centroid computed as scikit-fuzzy 0.5 does it, on a sampled output universe.

    scikit-fuzzy adds to the universe the points where each output set crosses its firing
    level, takes the max of the clipped sets there and integrates the piecewise-linear
    interpolant exactly. Kinks between grid points that are not such crossings (where the
    clipped Small level meets the Big ramp, at y = s and y = 1 - b) are linearised, which is
    the only difference from :func:`exact_centroid`.

    Parameters
    ----------
    small, big : float
        Firing strengths of Small and Big.
    universe : numpy.ndarray
        Sorted sample points on [0, 1] that include 0 and 1.

    Returns
    -------
    float
        The centroid of the sampled aggregate.
    """
    crossings = []
    for level, ramp in ((small, 1.0 - universe), (big, universe)):
        crossings.extend(_level_crossings(universe, ramp, level))
    y = np.union1d(universe, crossings)
    mu = np.maximum(np.minimum(small, 1.0 - y), np.minimum(big, y))
    width = np.diff(y)
    left, right = mu[:-1], mu[1:]
    area = 0.5 * width * (left + right)
    moment = width / 6.0 * (y[:-1] * (2.0 * left + right) + y[1:] * (left + 2.0 * right))
    return float(np.sum(moment) / max(np.sum(area), np.finfo(float).eps))


def _level_crossings(x, mf, level):
    # Linear interpolation of where the sampled membership crosses ``level`` (as skfuzzy's
    # _interp_universe_fast, including its strict test at level zero).
    above = mf > level if level == 0.0 else mf >= level
    idx = np.nonzero(np.diff(above))[0]
    return (x[idx] + (level - mf[idx]) * (x[idx + 1] - x[idx]) / (mf[idx + 1] - mf[idx])).tolist()


def weighted_average(weight_sum, weighted_sum):
    """The weighted-average form of the paper's Eqs. (51)-(52).

    Parameters
    ----------
    weight_sum : float
        Sum of the rule firing strengths, sum(w_i) (positive).
    weighted_sum : float
        Sum of firing strength times consequent value, sum(w_i C_i), with C_i = 0 for Small
        and 1 for Big (the peaks of the output sets).

    Returns
    -------
    float
        ``weighted_sum / weight_sum``, in [0, 1].
    """
    return weighted_sum / weight_sum
