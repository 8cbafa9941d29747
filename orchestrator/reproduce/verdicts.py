"""How a claim of the paper fares: its effect measured against the paper's, in five verdicts.

A claim says that a quantity (a paired difference, a per-run slope, a figure) lies on one
side of a threshold (``claimed`` "above" or "below", usually of 0). :func:`classify` takes our
interval of that quantity (an :class:`~orchestrator.reproduce.statistics.Estimate`), the
paper's magnitude of the effect in the same units (``P > 0``, measured from the threshold in
the claimed direction: 0.102 m for "A's error, 0.044 m, is below B's, 0.146 m"), and an
equivalence margin, and first turns our numbers so that the claimed direction is positive:
``e = s (x - threshold)`` with ``s = +1`` for "above" and ``-1`` for "below". On our interval
``[lo, hi]`` and point ``e`` (the estimate's mean, or its median for a median interval):

1. no interval (fewer than two runs, or too few for the interval's coverage):
   :data:`INCONCLUSIVE`; an infinite bound (lost runs ranked as the worst outcome) is an
   interval;
2. the whole interval inside the margin, ``-margin <= lo`` and ``hi <= margin``:
   :data:`NO_EFFECT` (an equivalence test: whatever the true effect, it is too small to matter);
3. the whole interval beyond the margin on the opposite side, ``hi < -margin``:
   :data:`CONTRADICTED`;
4. the claimed direction established, ``lo > 0``: :data:`SUPPORTED` if ``e >= f P``
   (``f`` = ``support_fraction``), else :data:`WEAKER`; without a paper magnitude, the
   direction alone supports the claim;
5. anything else (the interval straddles 0 beyond the margin, or lies on the opposite side
   but reaches inside the margin): :data:`INCONCLUSIVE`.

Then the lost runs (a robot that lost control or never arrived), which no interval weighs by
their size: a loss is an outcome beyond any margin. ``lost_against`` counts the pairs in which
only the arm the claim favours was lost, ``lost_for`` those in which only its comparator was
(pairs lost on both sides say nothing about the difference). With ``P`` the one-sided sign
test of the larger count among the two (exact binomial, ``n = lost_against + lost_for``):

6. losses against the claim with ``P < 0.05`` (five or more, none for it): :data:`CONTRADICTED`,
   unless the interval established the claimed direction (then the cell is mixed:
   :data:`INCONCLUSIVE`); fewer or mixed losses against it: a verdict of supported, weaker or
   no effect becomes :data:`INCONCLUSIVE`;
7. losses for the claim likewise: with ``P < 0.05``, a verdict of no effect or inconclusive
   becomes :data:`SUPPORTED` (the comparator lost runs the favoured arm kept) and contradicted
   becomes :data:`INCONCLUSIVE`; fewer, contradicted or no effect becomes
   :data:`INCONCLUSIVE`.

So five robots lost by CFGS-PD alone out of 20 make "CFGS-PD's error is lower" contradicted,
even where the 15 that arrived show no difference; one lost robot is enough to withhold "no
effect".

Defaults and why:

- ``support_fraction`` 0.5: the simulated robot is not the paper's hardware, so its effect is
  not expected to match to the per cent; an effect within a factor of two of the paper's is
  the same effect, and one under half of it means the paper overstates it by more than 2x.
- ``margin`` 0: the caller states the equivalence margin per claim, in the claim's units
  (e.g. 10 % of the comparator's mean); with 0, rules 2-3 test the direction only.
- The direction comes from the interval, the size from the point estimate against the
  paper's: a claim is not "weaker" just because its interval is wide.

The ratio ``e / P`` is reported for every claim with a paper magnitude (negative when our
effect has the opposite sign).

Examples
--------
>>> from orchestrator.reproduce.statistics import Estimate
>>> ours = Estimate(-0.0102, -0.012, -0.0084, 20, 0.004)   # a tenth of the paper's effect
>>> classify(ours, paper=0.102, claimed="below").category
'weaker than claimed'
>>> no_difference = Estimate(0.001, -0.004, 0.009, 20, 0.01)   # the 15 runs that arrived
>>> classify(no_difference, paper=0.102, claimed="below", margin=0.0102).category
'no effect'
>>> classify(no_difference, paper=0.102, claimed="below", margin=0.0102,
...          lost_against=5).category
'contradicted'
"""

import math
from dataclasses import dataclass

__all__ = ["SUPPORTED", "WEAKER", "NO_EFFECT", "CONTRADICTED", "INCONCLUSIVE", "CATEGORIES",
           "SUPPORT_FRACTION", "LOSS_LEVEL", "Verdict", "classify"]

SUPPORTED = "supported"
WEAKER = "weaker than claimed"
NO_EFFECT = "no effect"
CONTRADICTED = "contradicted"
INCONCLUSIVE = "inconclusive"
#: The verdicts, from the claim's best to its worst outcome (inconclusive apart).
CATEGORIES = (SUPPORTED, WEAKER, NO_EFFECT, CONTRADICTED, INCONCLUSIVE)

SUPPORT_FRACTION = 0.5
#: One-sided level at which lost runs alone decide a verdict (rules 6-7).
LOSS_LEVEL = 0.05


def _finite(value):
    return value is not None and math.isfinite(value)


@dataclass(frozen=True)
class Verdict:
    """A claim's verdict with the numbers it rests on (units of the claim's quantity).

    Attributes
    ----------
    category : str
        One of :data:`CATEGORIES`.
    ours, low, high : float
        Our point estimate and interval, as measured (not sign-adjusted).
    paper : float or None
        The paper's magnitude of the effect (> 0), None when it gives none.
    ratio : float or None
        Our effect ``e`` over the paper's magnitude (negative when ours has the opposite
        sign; None without a paper magnitude).
    claimed, threshold, margin, support_fraction
        The rule's inputs (see the module docstring).
    rule : str
        Which rule decided, in words with its numbers.
    """

    category: str
    ours: float
    low: float
    high: float
    paper: object
    ratio: object
    claimed: str
    threshold: float
    margin: float
    support_fraction: float
    rule: str

    def text(self, fmt=".3g", unit=""):
        """One line for the report, e.g. ``weaker than claimed: ours -0.0102 [-0.012,
        -0.0084] m vs paper's magnitude 0.102 m (ratio 0.1; supported needs >= 0.5); ...``."""
        unit = f" {unit}" if unit else ""
        ours = (format(self.ours, fmt) if self.low is None or math.isnan(self.low)
                else f"{self.ours:{fmt}} [{self.low:{fmt}}, {self.high:{fmt}}]")
        line = f"{self.category}: ours {ours}{unit}"
        if self.paper is not None:
            line += f" vs paper's magnitude {self.paper:{fmt}}{unit}"
            if self.ratio is not None:
                line += (f" (ratio {self.ratio:.2g}; supported needs >= "
                         f"{self.support_fraction:g})")
        return f"{line}; {self.rule}"

    def to_dict(self):
        """JSON-able form (non-finite numbers as None)."""
        def clean(v):
            return float(v) if _finite(v) else None
        return {"category": self.category, "ours": clean(self.ours), "low": clean(self.low),
                "high": clean(self.high), "paper": clean(self.paper),
                "ratio": clean(self.ratio), "claimed": self.claimed,
                "threshold": clean(self.threshold), "margin": clean(self.margin),
                "support_fraction": self.support_fraction, "rule": self.rule}


def classify(estimate, paper=None, claimed="above", threshold=0.0,
             support_fraction=SUPPORT_FRACTION, margin=0.0, lost_against=0, lost_for=0):
    """Verdict of a claim that the true value lies ``claimed`` of ``threshold``.

    Parameters
    ----------
    estimate : Estimate
        Our interval of the claim's quantity (``mean`` is its point estimate).
    paper : float or None
        The paper's magnitude of the effect, > 0, in the quantity's units, measured from the
        threshold in the claimed direction (e.g. ``0.146 - 0.044`` m for "A's error is
        below B's"; 1.52 m per m/s for "the error grows with speed"); None if the paper gives
        no number.
    claimed : {"above", "below"}
        The side of ``threshold`` the claim puts the quantity on.
    threshold : float
        The claim's reference value (0 for a difference or a slope).
    support_fraction : float
        Share of the paper's effect our point estimate must reach to support the claim.
    margin : float
        Equivalence margin (>= 0) in the quantity's units: effects within +-margin of the
        threshold are too small to matter.
    lost_against, lost_for : int
        Pairs lost by the claim's favoured arm alone, and by its comparator alone (rules 6-7).

    Returns
    -------
    Verdict

    Raises
    ------
    ValueError
        For an unknown ``claimed``, a negative or non-finite margin, a support fraction
        outside (0, 1], or a paper magnitude that is not a finite number > 0.
    """
    if claimed not in ("above", "below"):
        raise ValueError(f"claimed = {claimed!r}; valid choices: above, below")
    if not (math.isfinite(margin) and margin >= 0.0):
        raise ValueError(f"margin = {margin!r}: must be a finite number >= 0")
    if min(lost_against, lost_for) < 0:
        raise ValueError(f"lost_against = {lost_against!r}, lost_for = {lost_for!r}: counts "
                         "of runs, >= 0")
    if not 0.0 < support_fraction <= 1.0:
        raise ValueError(f"support_fraction = {support_fraction!r}: must lie in (0, 1]")
    sign = 1.0 if claimed == "above" else -1.0
    paper_effect = None
    if paper is not None:
        paper_effect = float(paper)
        if not (math.isfinite(paper_effect) and paper_effect > 0.0):
            raise ValueError(f"paper = {paper!r}: the paper's magnitude of the effect must be "
                             "a finite number > 0 (measured in the claimed direction)")
    point, low, high = estimate.mean, estimate.low, estimate.high
    ratio = (sign * (point - threshold) / paper_effect
             if paper_effect is not None and _finite(point) else None)

    def verdict(category, rule):
        return Verdict(category, point, low, high, paper, ratio, claimed, threshold, margin,
                       support_fraction, rule)

    base = _by_interval(verdict, estimate, point, low, high, sign, threshold, margin,
                        claimed, paper_effect, support_fraction)
    return _by_losses(base, verdict, lost_against, lost_for)


def _by_interval(verdict, estimate, point, low, high, sign, threshold, margin, claimed,
                 paper_effect, support_fraction):
    """Rules 1-5."""
    if estimate.n < 2 or math.isnan(low) or math.isnan(high) or math.isnan(point):
        # an infinite bound is an interval (losses ranked at its end), nan is none
        return verdict(INCONCLUSIVE, f"no interval ({estimate.n} runs)")
    lo, hi = sorted((sign * (low - threshold), sign * (high - threshold)))
    e = sign * (point - threshold)
    side = "above" if claimed == "above" else "below"
    if -margin <= lo and hi <= margin:
        return verdict(NO_EFFECT, f"the whole interval within +-{margin:.3g} of "
                                  f"{threshold:.3g}")
    if hi < -margin:
        return verdict(CONTRADICTED, f"the whole interval beyond the margin {margin:.3g} "
                                     f"on the other side of {threshold:.3g}")
    if lo > 0.0:
        if paper_effect is None:
            return verdict(SUPPORTED, f"the whole interval {side} {threshold:.3g} (the "
                                      "paper gives no magnitude)")
        if e >= support_fraction * paper_effect:
            return verdict(SUPPORTED, f"the whole interval {side} {threshold:.3g}, the "
                                      f"effect >= {support_fraction:g} x the paper's")
        return verdict(WEAKER, f"the whole interval {side} {threshold:.3g}, the effect "
                               f"< {support_fraction:g} x the paper's")
    return verdict(INCONCLUSIVE, f"the interval straddles {threshold:.3g} or the margin "
                                 f"{margin:.3g}")


def _upper_tail(k, n):
    """P(B >= k) for B ~ Binomial(n, 1/2)."""
    return sum(math.comb(n, i) for i in range(k, n + 1)) / 2.0 ** n


def _by_losses(base, verdict, against, for_):
    """Rules 6-7: lost runs on one side overrule what the interval alone says."""
    if against == for_:
        return base
    n = against + for_
    worse = "against" if against > for_ else "for"
    count, other = (against, for_) if worse == "against" else (for_, against)
    p = _upper_tail(count, n)
    alone, rest = (("the claimed-better arm", "the comparator") if worse == "against"
                   else ("the comparator", "the claimed-better arm"))
    losses = (f"{count} run(s) lost by {alone} alone, {other} by {rest} alone (one-sided "
              f"sign test p = {p:.2g})")
    interval_says = f"the interval alone: {base.category} ({base.rule})"
    if worse == "against":
        if p < LOSS_LEVEL and base.category not in (SUPPORTED, WEAKER):
            return verdict(CONTRADICTED, f"{losses}; the losses decide; {interval_says}")
        if base.category in (SUPPORTED, WEAKER, NO_EFFECT):
            return verdict(INCONCLUSIVE, f"{losses} against {interval_says}")
        return base
    if p < LOSS_LEVEL and base.category in (NO_EFFECT, INCONCLUSIVE):
        return verdict(SUPPORTED, f"{losses}; the losses decide; {interval_says}")
    if base.category in (CONTRADICTED, NO_EFFECT):
        return verdict(INCONCLUSIVE, f"{losses} against {interval_says}")
    return base
