"""Our Routh-Hurwitz and its w-plane form against numeric roots and textbook examples."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from components.common.errors import ParameterError
from components.control.routh import (
    bilinear_to_w, is_hurwitz, is_schur, largest_stable_gain, rhp_root_count, routh_table,
    stable_gain_intervals,
)


def _rhp(coefficients):
    return int(np.sum(np.roots(coefficients).real > 0))


# (coefficients, right-half-plane roots). Sources: Ogata, Modern Control Engineering, 5th ed.,
# Sec. 5-6; Nise, Control Systems Engineering, Ch. 6 (the epsilon and all-zero-row cases).
TEXTBOOK = [
    ([1, 2, 3, 4], 0),          # s^3 + 2s^2 + 3s + 4: 2*3 > 4
    ([1, 3, 3, 1], 0),          # (s + 1)^3
    ([1, 1, 2, 24], 2),         # Ogata: two sign changes
    ([1, 2, 3, 4, 5], 2),       # Ogata Example 5-12
    ([1, 2, 3, 6, 5, 3], 2),    # Nise Example 6.2: zero in the first column (epsilon rule)
    ([1, 1, 2, 2, 3], 2),       # epsilon rule, even degree
    ([1, 2, 2, 4, 11, 10], 2),  # epsilon rule
    ([1, -1, 1], 2),            # sign change in the coefficients
    ([2, 5], 0),
    ([-1, -3, -3, -1], 0),      # negative leading coefficient: same roots as (s + 1)^3
]


@pytest.mark.parametrize("coefficients,rhp", TEXTBOOK,
                         ids=[" ".join(map(str, c)) for c, _ in TEXTBOOK])
def test_textbook_polynomials(coefficients, rhp):
    assert _rhp(coefficients) == rhp  # the table above is itself right
    assert rhp_root_count(coefficients) == rhp
    assert is_hurwitz(coefficients) == (rhp == 0)


def test_first_column_of_a_cubic():
    # a3 s^3 + a2 s^2 + a1 s + a0 -> a3, a2, (a2 a1 - a3 a0)/a2, a0
    np.testing.assert_allclose(routh_table([1, 2, 3, 4])[:, 0], [1, 2, 1, 4])


def test_epsilon_rule_puts_a_small_positive_number_in_the_column():
    first = routh_table([1, 2, 3, 6, 5, 3])[:, 0]
    assert 0 < first[2] < 1e-6 and first[3] < 0  # epsilon, then -12/epsilon


@pytest.mark.parametrize("coefficients", [
    [1, 1, 3, 1, 2],    # (s^2 + 1)(s^2 + s + 2): row of s^1 vanishes
    [1, 0, 1],          # s^2 + 1
    [1, 1, 1, 1],       # (s + 1)(s^2 + 1)
    [1, 0, -1],         # s^2 - 1: roots +-1, mirror images
], ids=["(s2+1)(s2+s+2)", "s2+1", "(s+1)(s2+1)", "s2-1"])
def test_all_zero_row_is_a_clear_error_and_not_hurwitz(coefficients):
    with pytest.raises(ParameterError, match="all zero.*symmetric about the origin"):
        routh_table(coefficients)
    with pytest.raises(ParameterError):
        rhp_root_count(coefficients)
    assert not is_hurwitz(coefficients)


@pytest.mark.parametrize("bad", [[], [np.nan, 1.0], [0.0, 0.0], [[1, 2], [3, 4]]],
                         ids=["empty", "nan", "all-zero", "2-D"])
def test_bad_coefficients_are_refused(bad):
    with pytest.raises(ParameterError):
        routh_table(bad)


def test_root_at_origin_and_constant():
    assert not is_hurwitz([1, 2, 0])  # s (s + 2)
    assert is_hurwitz([5.0])          # no roots at all
    assert is_hurwitz([0, 0, 1, 2])   # leading zeros are dropped: s + 2


def _polynomial_from_roots(rng, degree, margin):
    """Random real polynomial with roots at least ``margin`` off the imaginary axis."""
    roots = []
    while len(roots) < degree:
        real = rng.uniform(margin, 3.0) * rng.choice([-1.0, 1.0])
        if degree - len(roots) >= 2 and rng.random() < 0.5:
            imag = rng.uniform(0.05, 5.0)
            roots += [complex(real, imag), complex(real, -imag)]
        else:
            roots.append(real)
    return rng.uniform(0.1, 10.0) * rng.choice([-1.0, 1.0]) * np.poly(roots).real, roots


def test_random_polynomials_against_numeric_roots():
    rng = np.random.default_rng(20261122)
    hurwitz_seen = 0
    for _ in range(1500):
        degree = int(rng.integers(1, 11))
        # Mostly stable roots so that Hurwitz polynomials are common, not a rarity.
        coefficients, roots = _polynomial_from_roots(rng, degree, margin=0.02)
        if rng.random() < 0.6:
            coefficients = np.poly([complex(-abs(r.real), r.imag) for r in roots]).real
        truth = np.roots(coefficients)
        rhp = int(np.sum(truth.real > 0))
        assert is_hurwitz(coefficients) == (rhp == 0), coefficients
        assert rhp_root_count(coefficients) == rhp, coefficients
        hurwitz_seen += rhp == 0
    assert hurwitz_seen > 500


def test_random_integer_coefficients_against_numeric_roots():
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(1500):
        coefficients = rng.integers(-3, 10, size=int(rng.integers(2, 9))).astype(float)
        if coefficients[0] == 0:
            continue
        truth = np.roots(coefficients)
        if truth.size and np.min(np.abs(truth.real)) < 1e-6:
            continue  # marginal in floating point: the test below covers exact marginal cases
        try:
            count = rhp_root_count(coefficients)
        except ParameterError:
            # All-zero row: only legitimate when roots come in +-s pairs (symmetric).
            assert not is_hurwitz(coefficients)
            assert any(np.isclose(truth, -r).any() for r in truth)
            continue
        assert count == int(np.sum(truth.real > 0)), coefficients
        assert is_hurwitz(coefficients) == bool(np.all(truth.real < 0))
        checked += 1
    assert checked > 700


@pytest.mark.parametrize("roots", [
    [1j, -1j, -1.0],
    [2j, -2j, -1 + 1j, -1 - 1j],
    [0.0, -1.0, -2.0],
    [0.5j, -0.5j, 3j, -3j],
    [-1e-3 + 1j, -1e-3 - 1j, -2.0],   # barely stable: must stay True
    [1e-3 + 1j, 1e-3 - 1j, -2.0],     # barely unstable
], ids=["jw-pair", "jw-pair+damped", "origin", "two-jw-pairs", "barely-stable",
        "barely-unstable"])
def test_marginal_polynomials(roots):
    coefficients = np.poly(roots).real
    expected = bool(np.all(np.real(roots) < 0))
    assert is_hurwitz(coefficients) == expected


def test_bilinear_map_sends_roots_to_w_equals_z_minus_one_over_z_plus_one():
    z_roots = np.array([0.5, -0.3, 0.2 + 0.7j, 0.2 - 0.7j, 1.5])
    w = np.roots(bilinear_to_w(np.poly(z_roots).real))
    expected = (z_roots - 1) / (z_roots + 1)
    np.testing.assert_allclose(np.sort_complex(w), np.sort_complex(expected), atol=1e-10)


@given(st.lists(st.tuples(st.floats(0.0, 1.6), st.floats(0.0, np.pi)), min_size=1,
                max_size=5),
       st.floats(0.5, 5.0))
@settings(max_examples=150, deadline=None)
def test_is_schur_matches_root_magnitudes(polar, scale):
    roots = []
    for radius, angle in polar:
        if abs(radius - 1.0) < 1e-3:
            radius += 2e-3  # keep off the circle; exact marginal cases are tested below
        root = radius * np.exp(1j * angle)
        roots += [root, np.conj(root)] if abs(root.imag) > 1e-9 else [root.real]
    coefficients = scale * np.poly(roots).real
    assert is_schur(coefficients) == bool(np.all(np.abs(roots) < 1.0))


@pytest.mark.parametrize("roots", [[1.0, 0.5], [-1.0, 0.2], [np.exp(0.7j), np.exp(-0.7j), 0.1]],
                         ids=["z=1", "z=-1", "unit-circle pair"])
def test_roots_on_the_unit_circle_are_not_schur(roots):
    assert not is_schur(np.poly(roots).real)


def test_gain_bound_of_a_triple_pole():
    # 1/(s + 1)^3 under gain K: (s + 1)^3 + K is Hurwitz for -1 < K < 8 (Routh: 9 > 1 + K).
    intervals = stable_gain_intervals([1, 3, 3, 1], [1], gain_max=20, gain_min=-5)
    assert len(intervals) == 1
    assert intervals[0] == pytest.approx((-1.0, 8.0), rel=1e-10)
    assert largest_stable_gain([1, 3, 3, 1], [1], gain_max=20) == pytest.approx(8.0, rel=1e-10)


def test_discrete_gain_bound_of_a_second_order_polynomial():
    # z^2 + (K - 1.5) z + 0.5 is Schur iff |0.5| < 1 and |K - 1.5| < 1.5, i.e. 0 < K < 3.
    intervals = stable_gain_intervals([1, -1.5, 0.5], [1, 0], gain_max=5, gain_min=-1,
                                      test=is_schur)
    assert len(intervals) == 1
    assert intervals[0] == pytest.approx((0.0, 3.0), abs=1e-10)
    assert largest_stable_gain([1, -1.5, 0.5], [1, 0], gain_max=5, test=is_schur) is None


def test_gain_search_range_is_checked():
    with pytest.raises(ParameterError):
        stable_gain_intervals([1, 1], [1], gain_max=0.0)



_CLUSTERS = [(m, r, a) for m in (2, 3, 4, 5) for r in (0.99, 0.998, 0.999, 1.001, 1.01)
             for a in (0.0, 0.3) if (m, r) not in ((5, 0.998), (5, 0.999))]


@pytest.mark.parametrize("multiplicity, radius, angle", _CLUSTERS,
                         ids=[f"{m}x{r}{'-pair' if a else ''}" for m, r, a in _CLUSTERS])
def test_clustered_roots_near_z_equals_one(multiplicity, radius, angle):
    # Clustered roots near z = 1 (slow poles, as an integral trim adds) give w-plane
    # coefficients spanning many decades; a row-wide zero tolerance in the Routh table called
    # four poles at z = 0.999 unstable. Five-fold clusters at 0.998-0.999 are left out: the
    # rounded coefficients' own roots leave the circle (|z| up to 1.0003), so double precision
    # does not decide them.
    root = radius * np.exp(1j * angle)
    roots = [root.real] * multiplicity if angle == 0.0 else [root, np.conj(root)] * multiplicity
    coefficients = np.poly(roots).real
    numeric = np.max(np.abs(np.roots(coefficients)))
    assert (numeric < 1.0) == (radius < 1.0)  # the reference decides this case
    assert is_schur(coefficients) == (radius < 1.0)
