"""Intervals and verdicts of the reproduction study against known distributions."""

import math

import numpy as np
import pytest
from scipy import stats

from orchestrator.reproduce.statistics import (INCONCLUSIVE, NOT_SUPPORTED, SUPPORTED,
                                               evidence, judge, mean_interval, median_interval,
                                               paired_difference, paired_evidence,
                                               paired_values, separation, sign_test,
                                               slope_interval)

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


def test_judge_without_an_interval_is_inconclusive():
    assert judge(mean_interval([1.0]), 0.0) == INCONCLUSIVE
    with pytest.raises(ValueError, match="valid choices: above, below"):
        judge(mean_interval([1.0, 2.0]), 0.0, "higher")


# --- sign test, median interval, the choice of interval ------------------------------------

def test_sign_test_counts_and_exact_p():
    test = sign_test([0.1] * 17 + [-0.2] * 3 + [0.0])
    assert (test.positive, test.negative, test.ties) == (17, 3, 1)
    # exact two-sided binomial: 2 P(B <= 3), B ~ Bin(20, 1/2)
    assert test.p_value == pytest.approx(2 * stats.binom.cdf(3, 20, 0.5))
    assert sign_test([0.1] * 20).text() == "sign test 20/0, p = 1.9e-06"
    assert sign_test([1.0, 2.0], center=1.5).positive == 1
    assert sign_test([0.0, None]).p_value == 1.0


@pytest.mark.parametrize("n, k, coverage", [(6, 1, 1 - 2 / 64), (20, 6, 0.9586), (40, 14, 0.9615)])
def test_median_interval_order_statistics_by_hand(n, k, coverage):
    e = median_interval(list(range(1, n + 1))[::-1])
    assert (e.low, e.high) == (k, n - k + 1) and e.method == "median"
    assert e.coverage == pytest.approx(coverage, abs=5e-5) and e.coverage >= 0.95
    # one rank tighter would cover less than 95 %
    assert 1 - 2 * stats.binom.cdf(k, n, 0.5) < 0.95
    assert e.text(".0f").endswith("(median)")


def test_median_interval_missing_below_six_runs():
    e = median_interval([1.0, 2.0, 3.0, 4.0, 5.0, None])
    assert e.mean == 3.0 and math.isnan(e.low) and e.missing == 1


@pytest.mark.parametrize("draw, median", [
    (lambda rng: rng.exponential(1.0, 20), math.log(2.0)),
    (lambda rng: np.where(rng.uniform(size=20) < 0.15, 2.0, 0.04) + rng.normal(0, 0.005, 20),
     None),
], ids=["exponential", "bimodal"])
def test_median_interval_covers_the_true_median(draw, median):
    rng = np.random.default_rng(5)
    if median is None:                   # the mixture's median: the lower cluster's centre
        median = 0.04 + 0.005 * stats.norm.ppf(0.5 / 0.85)
    hits = sum(e.low <= median <= e.high
               for e in (median_interval(draw(rng)) for _ in range(TRIALS)))
    # exact coverage 95.86 %: at least 95 % within the trials' noise
    assert hits / TRIALS > 0.9586 - COVERAGE_TOLERANCE


def test_separation_finds_a_minority_cluster_not_a_normal_sample():
    rng = np.random.default_rng(2)
    lost = list(0.045 + rng.normal(0, 0.003, 17)) + [2.18, 2.02, 0.41]
    split = separation(lost)
    assert split.separated and (split.below, split.above) == (0.41, 2.02)  # widest gap
    assert "values separated" in split.text()
    false_alarms = sum(separation(rng.normal(0, 1, 20)).separated for _ in range(1000))
    assert false_alarms <= 5                      # 0.14 % measured: about 1.4 in 1000
    assert separation([1.0, 2.0, 30.0]) is None   # too few runs to tell
    assert separation([1.0] * 20) is None


def test_a_bimodal_sample_with_lost_runs_gets_the_median_interval_and_its_counts():
    # Table 8 at mu 0.05: 17 runs within a few cm, 3 that lost control, one failed run
    rng = np.random.default_rng(4)
    values = list(0.045 + rng.normal(0, 0.003, 16)) + [2.18, 2.02, 0.41, None]
    lost = [False] * 16 + [True, True, True, False]
    chosen = evidence(values, lost)
    assert chosen.method == "median" and (chosen.failed, chosen.lost) == (1, 3)
    assert "1 failed" in chosen.rule and "3 lost" in chosen.rule
    assert chosen.estimate.high < 0.06                # not dragged by the lost runs
    t = mean_interval(values)                         # what the t-interval would say
    assert t.high > 0.4 and t.low < 0.045
    text = chosen.text()
    assert text.startswith("sign test 19/0, p = 3.8e-06; 1 failed run; 3 lost runs; ")
    assert text.endswith("median interval")
    # the separation alone chooses the median interval too
    assert evidence(values[:19]).method == "median"
    # a clean normal sample keeps the t-interval
    normal = rng.normal(1.0, 0.1, 20)
    clean = evidence(normal)
    assert clean.method == "mean" and clean.estimate == mean_interval(normal)
    assert clean.text() == "sign test 20/0, p = 1.9e-06; mean interval"
    with pytest.raises(ValueError, match="lost flags"):
        evidence([1.0, 2.0], [True])


def test_paired_evidence_uses_the_pairs_where_both_ran():
    a, b = [1.0, 2.0, None, 4.0], [0.5, 1.0, 1.0, 3.0]
    assert paired_values(a, b) == [0.5, 1.0, None, 1.0]
    chosen = paired_evidence(a, b)
    assert chosen.failed == 1 and chosen.sign.positive == 3


def test_lost_runs_entered_as_infinite_keep_their_rank():
    # 17 pairs 5 mm better, 3 where only the comparator lost (-inf: best for "below")
    differences = [-0.005 + 0.0001 * k for k in range(17)] + [-math.inf] * 3
    chosen = evidence(differences)
    assert (chosen.failed, chosen.lost, chosen.method) == (0, 3, "median")
    assert chosen.sign.negative == 20 and chosen.estimate.n == 20
    e = chosen.estimate                     # ranks 6 and 15 of 20: -inf x3 then the rest
    assert (e.low, e.high) == (sorted(differences)[5], sorted(differences)[14])
    # when the losses reach the bound's rank, the bound is infinite, still an interval
    many = median_interval([1.0] * 10 + [math.inf] * 10)
    assert many.low == 1.0 and many.high == math.inf
    assert evidence([1.0, 2.0], [True, False]).lost == 1


def test_module_examples():
    import doctest

    from orchestrator.reproduce import statistics
    assert doctest.testmod(statistics).failed == 0
