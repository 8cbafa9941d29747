"""The five verdicts of a claim against the paper's magnitude, on synthetic intervals."""

import doctest
import math

import pytest

from orchestrator.reproduce import verdicts
from orchestrator.reproduce.statistics import Estimate
from orchestrator.reproduce.verdicts import (CONTRADICTED, INCONCLUSIVE, NO_EFFECT, SUPPORTED,
                                             WEAKER, classify)


def interval(point, low, high, n=20):
    return Estimate(point, low, high, n, 1.0)


# The paper's Table 8 claim: CFGS-PD's final error below CPID's, 0.044 vs 0.146 m: a paired
# difference of magnitude 0.102 m in the claimed direction; the margin of "no effect" 0.013 m.
PAPER, MARGIN = 0.102, 0.013


@pytest.mark.parametrize("ours, expected", [
    (interval(-0.100, -0.110, -0.090), SUPPORTED),          # the paper's size
    (interval(-0.060, -0.080, -0.040), SUPPORTED),          # above half of it (ratio 0.59)
    (interval(-0.0102, -0.016, -0.004), WEAKER),  # a tenth of the size, past the margin
    (interval(-0.040, -0.045, -0.035), WEAKER),             # ratio 0.39
    (interval(0.002, -0.004, 0.008), NO_EFFECT),            # all within +-0.013
    (interval(0.050, 0.030, 0.070), CONTRADICTED),          # the other side, past the margin
    (interval(-0.020, -0.060, 0.020), INCONCLUSIVE),        # straddles 0 past the margin
    (interval(0.010, 0.005, 0.020), INCONCLUSIVE),          # opposite, but reaches the margin
    (interval(-0.100, math.nan, math.nan, n=1), INCONCLUSIVE),   # no interval
], ids=["paper_size", "above_half", "a_tenth", "ratio_0.39", "no_effect", "contradicted",
        "straddles", "opposite_within_margin", "one_run"])
def test_each_category_from_a_synthetic_interval(ours, expected):
    verdict = classify(ours, paper=PAPER, claimed="below", margin=MARGIN)
    assert verdict.category == expected
    assert verdict.paper == PAPER and verdict.ours == ours.mean


def test_a_tenth_of_the_papers_effect_is_weaker_with_its_ratio():
    verdict = classify(interval(-0.0102, -0.0122, -0.0082), paper=PAPER, claimed="below")
    assert verdict.category == WEAKER
    assert verdict.ratio == pytest.approx(0.1)
    text = verdict.text(unit="m")
    assert text.startswith("weaker than claimed: ours -0.0102 [-0.0122, -0.0082] m vs "
                           "paper's magnitude 0.102 m (ratio 0.1; supported needs >= 0.5); ")
    # the same interval without the paper's magnitude tests the direction only
    assert classify(interval(-0.0102, -0.0122, -0.0082), claimed="below").category == SUPPORTED


def test_the_support_fraction_is_the_boundary_between_supported_and_weaker():
    just_below = interval(-0.0509, -0.06, -0.04)
    just_above = interval(-0.0511, -0.06, -0.04)
    assert classify(just_below, PAPER, "below").category == WEAKER
    assert classify(just_above, PAPER, "below").category == SUPPORTED
    assert classify(just_below, PAPER, "below", support_fraction=0.4).category == SUPPORTED


def test_above_with_a_threshold_and_a_growth_slope():
    # error grows with speed: slope above 0; the paper's 1.52 m per m/s, ours 0.10
    weaker = classify(interval(0.100, 0.080, 0.120), paper=1.52, claimed="above")
    assert weaker.category == WEAKER and weaker.ratio == pytest.approx(0.100 / 1.52)
    # a bound claim: the gap stays below 1.17 m; the paper gives no number
    assert classify(interval(1.0, 0.99, 1.01), claimed="below",
                    threshold=1.17).category == SUPPORTED
    assert classify(interval(1.3, 1.25, 1.35), claimed="below",
                    threshold=1.17).category == CONTRADICTED


def test_the_ratio_is_negative_for_an_effect_of_the_opposite_sign():
    verdict = classify(interval(0.051, 0.04, 0.06), PAPER, "below", margin=MARGIN)
    assert verdict.category == CONTRADICTED and verdict.ratio == pytest.approx(-0.5)


def test_refuses_a_paper_magnitude_that_is_not_positive_and_bad_settings():
    for bad in (-0.102, 0.0, math.nan):
        with pytest.raises(ValueError, match="magnitude"):
            classify(interval(-0.1, -0.11, -0.09), paper=bad, claimed="below")
    with pytest.raises(ValueError, match="valid choices"):
        classify(interval(0, -1, 1), claimed="lower")
    with pytest.raises(ValueError, match="margin"):
        classify(interval(0, -1, 1), margin=-0.1)
    with pytest.raises(ValueError, match="support_fraction"):
        classify(interval(0, -1, 1), support_fraction=0.0)


def test_verdict_to_dict_is_json_ready():
    d = classify(interval(-0.1, math.nan, math.nan, n=1), PAPER, "below").to_dict()
    assert d["category"] == INCONCLUSIVE and d["low"] is None and d["paper"] == PAPER


def test_module_examples():
    assert doctest.testmod(verdicts).failed == 0


def test_an_unbounded_interval_from_lost_runs_is_judged():
    # the claimed-better arm never lost, the comparator lost often: (-inf, -0.02]
    verdict = classify(interval(-0.06, -math.inf, -0.02), PAPER, "below", margin=MARGIN)
    assert verdict.category == SUPPORTED
    assert "[-inf, -0.02]" in verdict.text()
    assert classify(interval(0.05, -math.inf, math.inf), PAPER, "below").category == INCONCLUSIVE


NO_DIFFERENCE = interval(0.001, -0.004, 0.009)   # the runs that arrived: inside the margin


@pytest.mark.parametrize("ours, against, for_, expected", [
    # losses against the claim: five alone (p 0.031) decide, one withholds "no effect"
    (NO_DIFFERENCE, 5, 0, CONTRADICTED),
    (NO_DIFFERENCE, 1, 0, INCONCLUSIVE),
    (NO_DIFFERENCE, 4, 0, INCONCLUSIVE),                    # p 0.0625: not decided
    (interval(-0.060, -0.080, -0.040), 5, 0, INCONCLUSIVE),  # mixed: the interval supports
    (interval(-0.020, -0.060, 0.020), 6, 0, CONTRADICTED),   # straddling, losses decide
    # losses for the claim: the comparator lost runs the favoured arm kept
    (NO_DIFFERENCE, 0, 5, SUPPORTED),
    (NO_DIFFERENCE, 0, 2, INCONCLUSIVE),
    (interval(0.050, 0.030, 0.070), 0, 6, INCONCLUSIVE),     # mixed: the interval contradicts
    (interval(-0.060, -0.080, -0.040), 0, 3, SUPPORTED),     # agrees: unchanged
    # as many on each side: the interval decides
    (NO_DIFFERENCE, 2, 2, NO_EFFECT),
], ids=["five_against", "one_against", "four_against", "mixed_supported", "straddles_six",
        "five_for", "two_for", "mixed_contradicted", "agreeing", "balanced"])
def test_lost_runs_on_one_side_overrule_the_interval(ours, against, for_, expected):
    verdict = classify(ours, PAPER, "below", margin=MARGIN, lost_against=against,
                       lost_for=for_)
    assert verdict.category == expected, verdict.rule
    if expected != classify(ours, PAPER, "below", margin=MARGIN).category:
        assert "lost by" in verdict.rule and "the interval alone" in verdict.rule


def test_judge_claim_counts_losses_by_the_side_they_fall_on():
    from orchestrator.reproduce.claims import judge_claim

    # "below": +inf is a run lost by the claimed-better arm alone (the difference a - b)
    arrived = [0.001 * (-1) ** i for i in range(15)]
    judged = judge_claim(arrived + [math.inf] * 5, "below", paper=-PAPER, margin=MARGIN)
    assert judged.verdict.category == CONTRADICTED
    assert "5 run(s) lost by the claimed-better arm alone" in judged.verdict.rule
    # the same losses on the comparator's side support the claim
    judged = judge_claim(arrived + [-math.inf] * 5, "below", paper=-PAPER, margin=MARGIN)
    assert judged.verdict.category == SUPPORTED
    # "above": -inf is the favoured arm's loss
    judged = judge_claim([-v for v in arrived] + [-math.inf] * 5, "above", paper=PAPER,
                         margin=MARGIN)
    assert judged.verdict.category == CONTRADICTED
