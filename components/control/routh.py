"""Routh-Hurwitz stability test, its discrete-time form through the bilinear map, gain bounds.

Our own implementation (the project asks for one, checked against numeric roots), so that the
verification report can state *why* a gain is stable from the characteristic polynomial alone
rather than from a root finder. Coefficients are given highest power first, as for
:func:`numpy.roots` and :func:`numpy.polyval`.

A discrete-time polynomial ``p(z)`` has all roots inside the unit circle exactly when the
polynomial in ``w`` obtained with ``z = (1 + w) / (1 - w)`` (the bilinear, or w-plane, map)
has all roots in the open left half plane, so :func:`is_schur` is :func:`is_hurwitz` of
:func:`bilinear_to_w`. This replaces Jury's table with the Routh table we already test.
"""

import math

import numpy as np

from ..common.errors import ParameterError

__all__ = [
    "routh_table", "is_hurwitz", "rhp_root_count", "bilinear_to_w", "is_schur",
    "stable_gain_intervals", "largest_stable_gain",
]

# A first-column element this small relative to the entries it was computed from counts as
# zero. Floating-point cancellation leaves ~1e-16 relative residue where exact arithmetic
# would give 0; 1e-12 leaves four orders of magnitude of margin either way.
ZERO_TOLERANCE = 1e-12

# The epsilon rule's replacement for a zero first-column element, relative to the row's
# scale. Small enough that the sign pattern is that of the limit epsilon -> 0+, large enough
# that the next rows (which divide by it) stay finite in double precision.
EPSILON = 1e-9


def _coefficients(coefficients):
    """Validate and return the coefficients as a float array with a nonzero leading term."""
    a = np.atleast_1d(np.asarray(coefficients, dtype=float))
    if a.ndim != 1 or a.size == 0:
        raise ParameterError(f"polynomial coefficients {coefficients!r} must be a non-empty "
                             "1-D sequence (highest power first)")
    if not np.all(np.isfinite(a)):
        raise ParameterError(f"polynomial coefficients {a.tolist()} must all be finite")
    nonzero = np.flatnonzero(a)
    if nonzero.size == 0:
        raise ParameterError("polynomial coefficients are all zero: no degree, no roots")
    # Leading zeros do not change the roots; dropping them keeps the table's first row valid.
    return a[nonzero[0]:]


def routh_table(coefficients, epsilon=EPSILON, zero_tolerance=ZERO_TOLERANCE):
    """Routh array of a real polynomial, with the epsilon rule for a zero first element.

    Parameters
    ----------
    coefficients : sequence of float
        ``a_n, ..., a_1, a_0`` (highest power first); leading zeros are dropped.
    epsilon : float, optional
        A first-column element that is zero while the rest of its row is not is replaced by
        ``epsilon`` times the row's largest magnitude (the textbook epsilon rule, epsilon ->
        0+), and the table continues.
    zero_tolerance : float, optional
        An element is zero when its magnitude is at most ``zero_tolerance`` times the largest
        magnitude of the two rows it was computed from.

    Returns
    -------
    numpy.ndarray
        Shape ``(n + 1, ceil((n + 1) / 2))`` for degree ``n``; row ``i`` belongs to
        ``s^(n - i)``; missing entries are zero. The first column decides stability.

    Raises
    ------
    ParameterError
        If the coefficients are empty, not finite or all zero, or if a whole row vanishes.
        An all-zero row means the polynomial has a factor whose roots are symmetric about the
        origin (imaginary-axis pairs or mirror-image pairs); the previous row is that
        auxiliary polynomial, named in the message. It is not Hurwitz in any case;
        :func:`is_hurwitz` catches this error and returns False.

    Examples
    --------
    >>> routh_table([1, 2, 3, 4])[:, 0].tolist()
    [1.0, 2.0, 1.0, 4.0]
    """
    return _routh(coefficients, epsilon, zero_tolerance)[0]


def _routh(coefficients, epsilon, zero_tolerance):
    """The Routh table and the indices of the rows where the epsilon rule was applied."""
    a = _coefficients(coefficients)
    degree = a.size - 1
    width = degree // 2 + 1
    table = np.zeros((degree + 1, width))
    table[0, :len(a[0::2])] = a[0::2]
    if degree >= 1:
        table[1, :len(a[1::2])] = a[1::2]
    replaced = []
    for i in range(1, degree + 1):
        upper = table[i - 1]
        row = table[i]
        if i >= 2:
            lower, upper = upper, table[i - 2]
            row[:-1] = (lower[0] * upper[1:] - upper[0] * lower[1:]) / lower[0]
            # Cancellation residue of each element is relative to the two terms it was
            # computed from, not to the row's largest entry: with clustered roots the
            # coefficients span many decades, and a row-wide scale zeroed true small entries
            # (four poles at z = 0.999 were called unstable).
            terms = np.abs(upper[1:]) + np.abs(upper[0] * lower[1:] / lower[0])
            row[:-1][np.abs(row[:-1]) <= zero_tolerance * terms] = 0.0
        if not np.any(row):
            previous = table[i - 1]
            power = degree - i + 1
            auxiliary = " + ".join(f"{c:.6g} s^{power - 2 * k}"
                                   for k, c in enumerate(previous) if c != 0.0)
            raise ParameterError(
                f"Routh table of {a.tolist()}: the row of s^{degree - i} is all zero, so the "
                f"polynomial has roots symmetric about the origin (auxiliary polynomial "
                f"{auxiliary}); it is not Hurwitz. Count the imaginary-axis roots from the "
                "auxiliary polynomial's roots.")
        if row[0] == 0.0:
            row[0] = epsilon * np.max(np.abs(row))
            replaced.append(i)
    return table, replaced


def rhp_root_count(coefficients, epsilon=EPSILON, zero_tolerance=ZERO_TOLERANCE):
    """Number of roots in the open right half plane: sign changes in the Routh first column.

    Parameters
    ----------
    coefficients : sequence of float
        Highest power first.
    epsilon, zero_tolerance : float, optional
        See :func:`routh_table`.

    Returns
    -------
    int

    Raises
    ------
    ParameterError
        On an all-zero row (see :func:`routh_table`): then some roots are symmetric about the
        origin and the count needs the auxiliary polynomial, which we do not guess at.
    """
    first = routh_table(coefficients, epsilon, zero_tolerance)[:, 0]
    signs = np.sign(first)
    return int(np.count_nonzero(signs[1:] != signs[:-1]))


def is_hurwitz(coefficients, epsilon=EPSILON, zero_tolerance=ZERO_TOLERANCE):
    """True when every root has a strictly negative real part.

    Parameters
    ----------
    coefficients : sequence of float
        Highest power first.
    epsilon, zero_tolerance : float, optional
        See :func:`routh_table`.

    Returns
    -------
    bool
        True iff the Routh first column has one strict sign and no element had to be
        replaced by the epsilon rule (a zero there means a root on the imaginary axis or in
        the right half plane). An all-zero row (roots symmetric about the origin) gives
        False. A constant polynomial has no roots and is Hurwitz.
    """
    a = _coefficients(coefficients)
    # Necessary condition, and it catches a zero constant term (a root at s = 0), which the
    # table would only show as a zero in its last row.
    if not (np.all(a > 0.0) or np.all(a < 0.0)):
        return False
    try:
        table, replaced = _routh(a, epsilon, zero_tolerance)
    except ParameterError:
        return False
    # A zero that the epsilon rule replaced stands for a root on the axis or beyond.
    return not replaced and bool(np.all(table[:, 0] * np.sign(a[0]) > 0.0))


def bilinear_to_w(coefficients):
    """Map a polynomial in ``z`` to one in ``w`` with ``z = (1 + w) / (1 - w)``.

    The unit disc ``|z| < 1`` maps onto the open left half plane ``Re w < 0``, so ``p(z)`` is
    Schur stable iff the returned polynomial is Hurwitz. The result is
    ``(1 - w)^n p((1 + w) / (1 - w)) = sum_k a_k (1 + w)^k (1 - w)^(n - k)``.

    Parameters
    ----------
    coefficients : sequence of float
        ``a_n, ..., a_0`` of ``p(z)``, highest power first.

    Returns
    -------
    numpy.ndarray
        Coefficients in ``w``, highest power first, length ``n + 1``. The leading one is
        ``p(-1)`` up to sign (a root at ``z = -1`` maps to ``w = infinity`` and lowers the
        degree); the constant one is ``p(1)`` (a root at ``z = 1`` maps to ``w = 0``).
    """
    a = _coefficients(coefficients)
    degree = a.size - 1
    result = np.zeros(degree + 1)
    plus = [np.array([1.0])]   # (1 + w)^k, highest power first
    minus = [np.array([1.0])]  # (1 - w)^k
    for _ in range(degree):
        plus.append(np.convolve(plus[-1], [1.0, 1.0]))
        minus.append(np.convolve(minus[-1], [-1.0, 1.0]))
    for index, coefficient in enumerate(a):
        power = degree - index
        result += coefficient * np.convolve(plus[power], minus[degree - power])
    return result


def is_schur(coefficients, epsilon=EPSILON, zero_tolerance=ZERO_TOLERANCE):
    """True when every root of ``p(z)`` lies strictly inside the unit circle.

    Routh-Hurwitz on the bilinear image (:func:`bilinear_to_w`). A root at ``z = -1`` makes
    the image's leading coefficient vanish; that is a marginal root, so the answer is False.

    Parameters
    ----------
    coefficients : sequence of float
        Highest power first.
    epsilon, zero_tolerance : float, optional
        See :func:`routh_table`.

    Returns
    -------
    bool
    """
    a = _coefficients(coefficients)
    w = bilinear_to_w(a)
    if abs(w[0]) <= zero_tolerance * np.max(np.abs(w)):
        return False
    return is_hurwitz(w, epsilon, zero_tolerance)


def stable_gain_intervals(base, per_gain, gain_max, test=is_hurwitz, samples=400,
                          gain_min=0.0, rtol=1e-12):
    """Intervals of ``k`` in ``[gain_min, gain_max]`` where ``base + k * per_gain`` is stable.

    The characteristic polynomial of a loop is affine in any one gain, so its stability as a
    function of that gain changes only where a root crosses the boundary. The range is
    scanned at ``samples`` points with ``test`` and every change of the answer is refined by
    bisection on ``test`` itself, so the edges are those of the Routh criterion to ``rtol``.

    Parameters
    ----------
    base, per_gain : sequence of float
        Polynomials (highest power first; zero-padded to a common length).
    gain_max : float
        Upper end of the search.
    test : callable, optional
        Stability predicate on coefficients: :func:`is_hurwitz` (continuous time, default)
        or :func:`is_schur` (discrete time).
    samples : int, optional
        Scan points; an interval narrower than the spacing can be missed.
    gain_min : float, optional
        Lower end of the search.
    rtol : float, optional
        Relative width at which the bisection stops.

    Returns
    -------
    list of tuple
        ``(low, high)`` pairs; an end equal to ``gain_min`` or ``gain_max`` means the
        interval continues past the searched range.
    """
    if not (math.isfinite(gain_min) and math.isfinite(gain_max) and gain_max > gain_min):
        raise ParameterError(f"gain range [{gain_min!r}, {gain_max!r}] must be finite and "
                             "non-empty")
    base = np.asarray(base, dtype=float)
    per_gain = np.asarray(per_gain, dtype=float)
    length = max(base.size, per_gain.size)
    base = np.pad(base, (length - base.size, 0))
    per_gain = np.pad(per_gain, (length - per_gain.size, 0))

    def stable(k):
        return test(base + k * per_gain)

    grid = np.linspace(gain_min, gain_max, int(samples))
    flags = [stable(k) for k in grid]
    intervals = []
    start = grid[0] if flags[0] else None
    for i in range(1, grid.size):
        if flags[i] == flags[i - 1]:
            continue
        edge = _bisect(stable, grid[i - 1], grid[i], flags[i - 1], rtol)
        if flags[i]:
            start = edge
        else:
            intervals.append((float(start), float(edge)))
            start = None
    if start is not None:
        intervals.append((float(start), float(grid[-1])))
    return intervals


def _bisect(stable, low, high, low_flag, rtol):
    """Edge between ``low`` (answer ``low_flag``) and ``high`` (the other answer)."""
    while high - low > rtol * max(abs(low), abs(high), 1e-300):
        middle = 0.5 * (low + high)
        if middle in (low, high):
            break
        if stable(middle) == low_flag:
            low = middle
        else:
            high = middle
    return 0.5 * (low + high)


def largest_stable_gain(base, per_gain, gain_max, test=is_hurwitz, samples=400,
                        gain_min=0.0, rtol=1e-12):
    """Upper end of the stable interval that starts at ``gain_min`` (None if unstable there).

    Parameters
    ----------
    base, per_gain, gain_max, test, samples, gain_min, rtol
        As for :func:`stable_gain_intervals`.

    Returns
    -------
    float or None
        The gain at which stability is first lost going up from ``gain_min``; ``gain_max`` if
        it is never lost in the range; None if ``gain_min`` itself is unstable.
    """
    intervals = stable_gain_intervals(base, per_gain, gain_max, test, samples, gain_min, rtol)
    if not intervals or intervals[0][0] != gain_min:
        return None
    return intervals[0][1]
