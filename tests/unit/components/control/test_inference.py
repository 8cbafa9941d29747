"""Fuzzy engine of the FGS-PD controller against scikit-fuzzy, quadrature and the tables."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from components.control import (
    INPUT_TERMS, KD_TABLE, KP_TABLE, FuzzyGainScheduler, exact_centroid, fuzzify,
    input_membership, rule_matrix,
)
from components.common.errors import ParameterError

skfuzzy = pytest.importorskip("skfuzzy")
pytest.importorskip("networkx")

_SPEED = Path(__file__).resolve().parents[4] / "benchmarks" / "fuzzy_speed.py"
_spec = importlib.util.spec_from_file_location("fuzzy_speed", _SPEED)
fuzzy_speed = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(fuzzy_speed)

PEAKS = np.linspace(-1.0, 1.0, 7)
# scikit-fuzzy 0.5 calls np.maximum with a positional out argument.
_SKFUZZY_WARNING = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def _skfuzzy_outputs(points):
    from skfuzzy import control as ctrl
    sim = ctrl.ControlSystemSimulation(fuzzy_speed.skfuzzy_system())
    sim.input["e"] = points[:, 0]
    sim.input["de"] = points[:, 1]
    sim.compute()
    return np.column_stack([sim.output["kp"], sim.output["kd"]])


def _ours(engine, points):
    return np.array([engine.evaluate_normalised(e, de) for e, de in points])


@pytest.mark.parametrize("x", [-1.5, -1.0, -0.9, -1 / 3, 0.0, 0.123, 0.5, 2 / 3, 0.99, 1.0, 3.0],
                         ids=lambda x: f"x={x:.3g}")
def test_fuzzify_matches_skfuzzy_trimf(x):
    clipped = min(1.0, max(-1.0, x))
    for k, term in enumerate(INPUT_TERMS):
        abc = [PEAKS[max(k - 1, 0)], PEAKS[k], PEAKS[min(k + 1, 6)]]
        expected = float(skfuzzy.trimf(np.array([clipped]), abc)[0])
        assert input_membership(x, term) == pytest.approx(expected, abs=1e-12), term
    _, left, right = fuzzify(x)
    assert left + right == pytest.approx(1.0, abs=1e-15)


@_SKFUZZY_WARNING
def test_mamdani_discrete_matches_skfuzzy_fast():
    points = np.random.default_rng(7).uniform(-1.2, 1.2, size=(150, 2))
    engine = FuzzyGainScheduler(1.0, 1.0, method="mamdani", centroid="discrete",
                                universe_points=fuzzy_speed.OUTPUT_POINTS)
    np.testing.assert_allclose(_ours(engine, points), _skfuzzy_outputs(points), atol=1e-6, rtol=0)


@pytest.mark.slow
@_SKFUZZY_WARNING
def test_mamdani_discrete_matches_skfuzzy_10000(capsys):
    points = np.random.default_rng(2024).uniform(-1.2, 1.2, size=(10_000, 2))
    reference = _skfuzzy_outputs(points)
    discrete = FuzzyGainScheduler(1.0, 1.0, method="mamdani", centroid="discrete",
                                  universe_points=fuzzy_speed.OUTPUT_POINTS)
    exact = FuzzyGainScheduler(1.0, 1.0, method="mamdani", centroid="exact")
    diff_discrete = np.abs(_ours(discrete, points) - reference).max()
    diff_exact = np.abs(_ours(exact, points) - reference).max()
    with capsys.disabled():
        print(f"\nskfuzzy vs ours on 10000 points: discrete {diff_discrete:.2e}, "
              f"exact {diff_exact:.2e}")
    assert diff_discrete <= 1e-6
    # The exact centroid differs only by scikit-fuzzy's linearised kinks on a 0.01 grid:
    # at most (grid step)^2 order, here ~2e-5.
    assert diff_exact <= 1e-4


@pytest.mark.parametrize("small,big", [(1, 0), (0, 1), (1, 1), (0.3, 0.7), (0.7, 0.3),
                                       (0.5, 0.5), (0.2, 0.2), (0.9, 0.05), (0.0, 0.4)],
                         ids=lambda v: str(v))
def test_exact_centroid_matches_quadrature(small, big):
    def mu(y):
        return max(min(small, 1 - y), min(big, y))
    breaks = sorted({small, 1 - small, big, 1 - big, 0.5})
    area = quad(mu, 0, 1, points=breaks, epsabs=1e-14)[0]
    moment = quad(lambda y: y * mu(y), 0, 1, points=breaks, epsabs=1e-14)[0]
    assert exact_centroid(small, big) == pytest.approx(moment / area, abs=1e-12)


def _eq51_reference(e_n, de_n, table):
    # Eq. (51) over all 49 rules, memberships from skfuzzy.trimf (independent of fuzzify()).
    x = np.clip([e_n, de_n], -1, 1)
    mu = [[float(skfuzzy.trimf(np.array([v]), [PEAKS[max(k - 1, 0)], PEAKS[k],
                                                PEAKS[min(k + 1, 6)]])[0]) for k in range(7)]
          for v in x]
    w = np.minimum.outer(np.array(mu[0]), np.array(mu[1]))
    c = np.array([[1.0 if ch == "B" else 0.0 for ch in row] for row in table])
    return float((w * c).sum() / w.sum())


def test_weighted_matches_eq51_over_all_rules():
    engine = FuzzyGainScheduler(1.0, 1.0, method="weighted")
    for e_n, de_n in np.random.default_rng(3).uniform(-1.2, 1.2, size=(300, 2)):
        kp_n, kd_n = engine.evaluate_normalised(e_n, de_n)
        assert kp_n == pytest.approx(_eq51_reference(e_n, de_n, KP_TABLE), abs=1e-12)
        assert kd_n == pytest.approx(_eq51_reference(e_n, de_n, KD_TABLE), abs=1e-12)


@pytest.mark.parametrize("method,small_value,big_value",
                         [("weighted", 0.0, 1.0), ("mamdani", 1 / 3, 2 / 3)], ids=["weighted", "mamdani"])
def test_rule_centres_reproduce_tables(method, small_value, big_value):
    engine = FuzzyGainScheduler(1.0, 1.0, method=method)
    for i, e_n in enumerate(PEAKS):
        for j, de_n in enumerate(PEAKS):
            kp_n, kd_n = engine.evaluate_normalised(e_n, de_n)
            want_kp = big_value if KP_TABLE[i][j] == "B" else small_value
            want_kd = big_value if KD_TABLE[i][j] == "B" else small_value
            assert kp_n == pytest.approx(want_kp, abs=1e-12), (i, j)
            assert kd_n == pytest.approx(want_kd, abs=1e-12), (i, j)


@pytest.mark.parametrize("method", ["weighted", "mamdani"], ids=["weighted", "mamdani"])
def test_surfaces_are_even_in_e_and_de(method):
    # The tables are palindromic along rows and symmetric between rows NB/PB, NM/PM, NS/PS.
    matrix = np.array(rule_matrix(KP_TABLE)), np.array(rule_matrix(KD_TABLE))
    for m in matrix:
        assert (m == m[::-1]).all() and (m == m[:, ::-1]).all()
    engine = FuzzyGainScheduler(0.4, 4.0, method=method)
    for e, de in np.random.default_rng(5).uniform([-0.5, -5], [0.5, 5], size=(400, 2)):
        base = engine.evaluate(e, de)
        for mirrored in (engine.evaluate(-e, de), engine.evaluate(e, -de),
                         engine.evaluate(-e, -de)):
            np.testing.assert_allclose(mirrored, base, atol=1e-12)


def test_far_from_reference_high_kp_low_kd():
    engine = FuzzyGainScheduler(0.4, 4.0)
    assert engine.evaluate(0.4, 0.0) == pytest.approx((1.0, 0.0))
    assert engine.evaluate(-0.8, 0.0) == pytest.approx((1.0, 0.0))


@pytest.mark.parametrize("kwargs,words", [
    ({"method": "cog"}, ["method", "'cog'", "weighted", "mamdani"]),
    ({"centroid": "bisector"}, ["centroid", "bisector", "exact", "discrete"]),
    ({"e_range": 0.0}, ["e_range", "0.0"]),
    ({"kp_table": ("BBBBBBB",) * 6 + ("BBBBBBX",)}, ["PB", "X"]),
], ids=["method", "centroid", "e_range", "table"])
def test_bad_parameters_are_named(kwargs, words):
    base = {"e_range": 0.4, "de_range": 4.0}
    base.update(kwargs)
    with pytest.raises(ParameterError) as info:
        FuzzyGainScheduler(**base)
    for word in words:
        assert word in str(info.value)
