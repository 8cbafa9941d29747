"""Intervals and verdicts of the reproduction study against known distributions."""

import math

import numpy as np
import pytest
from scipy import stats

from orchestrator.reproduce.statistics import (INCONCLUSIVE, NOT_SUPPORTED, SUPPORTED,
                                               judge, mean_interval, paired_difference,
                                               slope_interval)
from orchestrator.reproduce.tables_tracking import _better

TRIALS = 2000
# 3 binomial standard deviations of a 95 % coverage over TRIALS intervals: 0.0146
COVERAGE_TOLERANCE = 3.0 * math.sqrt(0.95 * 0.05 / TRIALS)


def test_interval_of_three_values_by_hand():
    estimate = mean_interval([1.0, 2.0, 3.0])
    half = stats.t.ppf(0.975, 2) * 1.0 / math.sqrt(3)     # s = 1
    assert estimate.mean == 2.0 and estimate.n == 3
    assert (estimate.low, estimate.high) == pytest.approx((2.0 - half, 2.0 + half))


def test_missing_and_non_finite_samples_are_counted_not_averaged():
    estimate = mean_interval([1.0, None, math.nan, 3.0, math.inf])
    assert estimate.n == 2 and estimate.missing == 3 and estimate.mean == 2.0
    assert math.isnan(mean_interval([5.0]).low) and mean_interval([]).n == 0


@pytest.mark.parametrize("draw, true_mean", [
    (lambda rng, size: rng.normal(3.0, 2.0, size), 3.0),
    (lambda rng, size: rng.uniform(-1.0, 5.0, size), 2.0),
], ids=["normal", "uniform"])
def test_interval_covers_the_true_mean_95_percent_of_the_time(draw, true_mean):
    rng = np.random.default_rng(7)
    hits = 0
    for _ in range(TRIALS):
        e = mean_interval(draw(rng, 20))
        hits += e.low <= true_mean <= e.high
    assert abs(hits / TRIALS - 0.95) < COVERAGE_TOLERANCE


def test_a_too_narrow_interval_fails_the_coverage_check():
    # the check above can fail: a z-interval with half the width covers far less than 95 %
    rng = np.random.default_rng(7)
    hits = 0
    for _ in range(TRIALS):
        sample = rng.normal(3.0, 2.0, 20)
        e = mean_interval(sample)
        half = 0.5 * (e.high - e.low) / 2
        hits += e.mean - half <= 3.0 <= e.mean + half
    assert abs(hits / TRIALS - 0.95) > COVERAGE_TOLERANCE


def test_paired_difference_removes_the_shared_variation():
    rng = np.random.default_rng(3)
    shared = rng.normal(0.0, 1.0, 30)               # the run's physics, common to both cells
    a = shared + 0.10 + rng.normal(0.0, 0.01, 30)
    b = shared + rng.normal(0.0, 0.01, 30)
    paired = paired_difference(a, b)
    assert paired.low < 0.10 < paired.high and paired.high - paired.low < 0.02
    unpaired = mean_interval(a).high - mean_interval(a).low
    assert unpaired > 10 * (paired.high - paired.low)
    with pytest.raises(ValueError, match="different lengths"):
        paired_difference([1.0], [1.0, 2.0])


def test_slope_interval_covers_a_known_slope():
    rng = np.random.default_rng(11)
    speeds = np.array([0.1, 0.2, 0.3, 0.4, 0.5])
    hits = 0
    for _ in range(TRIALS // 4):
        runs = [0.02 + 1.5 * speeds + rng.normal(0.0, 0.05, speeds.size) for _ in range(20)]
        e = slope_interval(speeds, runs)
        hits += e.low <= 1.5 <= e.high
    assert abs(hits / (TRIALS // 4) - 0.95) < 3.0 * math.sqrt(0.95 * 0.05 / (TRIALS // 4))


def test_slope_uses_every_speed_not_the_end_points():
    speeds = [0.1, 0.2, 0.3, 0.4, 0.5]
    # a hump: the end points are equal, the middle is high; the least-squares slope is 0,
    # and a run with a dip at the end but a rise elsewhere keeps a positive slope
    hump = [[0.1, 0.3, 0.5, 0.3, 0.1]] * 3
    assert slope_interval(speeds, hump).mean == pytest.approx(0.0, abs=1e-12)
    rising = [[0.1, 0.2, 0.3, 0.4, 0.05], [0.1, 0.2, 0.3, 0.4, 0.06]]
    assert slope_interval(speeds, rising).mean > 0


@pytest.mark.parametrize("shift, verdict", [(-0.10, SUPPORTED), (0.0, NOT_SUPPORTED),
                                            (-0.05, INCONCLUSIVE)],
                         ids=["beyond", "short", "straddles"])
def test_verdict_flips_across_the_threshold(shift, verdict):
    rng = np.random.default_rng(5)
    difference = shift + rng.normal(0.0, 0.01, 20)
    assert judge(mean_interval(difference), -0.05, "below") == verdict
    assert judge(mean_interval(-difference), 0.05, "above") == verdict


class _FakeAnalysis:
    """Per-cell samples for the real claim builder (no runs)."""

    def __init__(self, values):
        self._values = values

    def estimate(self, cell, key):
        return mean_interval(self._values[cell])

    def difference(self, a, b, key):
        return paired_difference(self._values[a], self._values[b])


@pytest.mark.parametrize("improvement, verdict", [(0.30, SUPPORTED), (0.0, NOT_SUPPORTED)])
def test_controller_claim_flips_with_a_synthetic_difference(improvement, verdict):
    rng = np.random.default_rng(9)
    pid = 0.10 + rng.normal(0.0, 0.005, 20)
    fgs = pid * (1.0 - improvement) + rng.normal(0.0, 0.001, 20)
    claim = _better(_FakeAnalysis({"pid": pid, "fgs": fgs}), "Table 8", "lower error",
                    "error_m", "m", "fgs", "pid", "ff on", "paper")
    assert claim.threshold == pytest.approx(-0.10 * pid.mean())
    assert claim.verdict == verdict
    assert claim.to_dict()["verdict"] == verdict and claim.requirement().startswith("<")


def test_judge_without_an_interval_is_inconclusive():
    assert judge(mean_interval([1.0]), 0.0) == INCONCLUSIVE
    with pytest.raises(ValueError, match="valid choices: above, below"):
        judge(mean_interval([1.0, 2.0]), 0.0, "higher")
