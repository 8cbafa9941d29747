"""Intervals, paired tests and the choice of interval over Monte Carlo runs.

A figure of the report is the mean over a cell's runs with a two-sided Student-t interval
(:func:`mean_interval`) unless :func:`evidence` below chooses the median's interval. A claim compares two cells run by run (the runs share their draws,
:mod:`orchestrator.reproduce.tolerances`) on the paired differences, or uses every speed: per
run, the least-squares slope of the figure over the speeds (:func:`slope_interval`).

Where the t-interval does not fit the sample, the median's distribution-free interval does
(:func:`median_interval`: order statistics, exact binomial coverage, no seed).
:func:`evidence` chooses between them by one rule, stated where it is applied: the median
interval when any run failed (its figure is missing) or was lost (the caller's flags, e.g. a
robot that never arrived, or a value of +-inf: a loss ranked as the worst outcome), or when the sample's values are separated into clusters
(:func:`separation`); the t-interval otherwise. Beside either it gives the paired sign test
(:func:`sign_test`), so a claim row can print "sign test 20/0, p = 1.9e-06; 3 lost runs;
median interval". Verdicts against the paper's magnitude are in
:mod:`orchestrator.reproduce.verdicts`; :func:`judge` is the older threshold-only verdict.
"""

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import stats

from .verdicts import INCONCLUSIVE, SUPPORTED

__all__ = ["CONFIDENCE", "SUPPORTED", "NOT_SUPPORTED", "INCONCLUSIVE", "SEPARATION_FACTOR",
           "SEPARATION_MIN_RUNS", "Estimate", "SignTest", "Separation", "Evidence",
           "mean_interval", "median_interval", "paired_difference", "paired_values",
           "slope_interval", "sign_test", "separation", "evidence", "paired_evidence", "judge"]

CONFIDENCE = 0.95
NOT_SUPPORTED = "not supported"     # the threshold-only verdict of judge()
# Values are "separated" when the largest gap between neighbours in the sorted sample exceeds
# 4 robust standard deviations (1.4826 x the median absolute deviation). Measured on 20 000
# samples each: a normal sample of 20 trips it 0.14 % of the time (10: 1.8 %), a uniform one
# of 20 never; a skewed or heavy-tailed one (exponential, t with 3 degrees of freedom) 10-13 %,
# where the median interval is the better choice anyway. Runs that lose control sit hundreds
# of spreads away. Below 6 runs the spread is too uncertain to tell (and no 95 % median
# interval exists), so the rule is not applied.
SEPARATION_FACTOR = 4.0
SEPARATION_MIN_RUNS = 6


@dataclass(frozen=True)
class Estimate:
    """Point estimate of ``n`` finite samples with its confidence interval ``[low, high]``.

    ``method`` says which: ``"mean"`` (``mean`` is the sample mean, the interval Student-t)
    or ``"median"`` (``mean`` holds the sample median, the interval from order statistics,
    :func:`median_interval`); ``coverage`` is the interval's coverage (nominal for the
    t-interval, exact under independence for the median's). ``missing`` counts the samples
    that were None or not finite (e.g. a run that did not settle); they are left out, and
    the report shows the count.
    """

    mean: float
    low: float
    high: float
    n: int
    std: float
    missing: int = 0
    method: str = "mean"
    coverage: float = CONFIDENCE

    @property
    def point(self):
        """The point estimate: the mean, or the median for a median interval."""
        return self.mean

    def to_dict(self):
        """JSON-able form (non-finite values as None)."""
        def clean(v):
            return float(v) if v is not None and math.isfinite(v) else None
        return {"mean": clean(self.mean), "low": clean(self.low), "high": clean(self.high),
                "n": self.n, "std": clean(self.std), "missing": self.missing,
                "method": self.method, "coverage": clean(self.coverage)}

    def text(self, fmt=".3f"):
        """``mean [low, high]`` (``... (median)`` for a median interval), or ``-`` without
        samples."""
        if self.n == 0:
            return "-"
        if self.n == 1 or not math.isfinite(self.low):
            return format(self.mean, fmt)
        text = f"{self.mean:{fmt}} [{self.low:{fmt}}, {self.high:{fmt}}]"
        return text + " (median)" if self.method == "median" else text


def _finite(samples):
    values = [float(v) for v in samples
              if v is not None and not isinstance(v, bool) and math.isfinite(float(v))]
    return np.array(values), len(list(samples)) - len(values)


def _ranked(samples):
    """The samples that have a rank: finite or +-inf (a lost run as the worst outcome on its
    side); None and nan are missing."""
    values = [float(v) for v in samples
              if v is not None and not isinstance(v, bool) and not math.isnan(float(v))]
    return np.array(values), len(list(samples)) - len(values)


def mean_interval(samples, confidence=CONFIDENCE):
    """Mean and two-sided Student-t interval of the finite samples.

    Parameters
    ----------
    samples : sequence of float or None
        One value per run; None and non-finite values are counted as missing.
    confidence : float
        Coverage of the interval (default 0.95).

    Returns
    -------
    Estimate
        With ``low = high = nan`` for fewer than two samples (no interval) and
        ``mean = nan`` for none.

    Examples
    --------
    >>> mean_interval([1.0, 2.0, 3.0]).text(".2f")
    '2.00 [-0.48, 4.48]'
    """
    samples = list(samples)
    values, missing = _finite(samples)
    n = len(values)
    if n == 0:
        return Estimate(math.nan, math.nan, math.nan, 0, math.nan, missing)
    mean = float(values.mean())
    if n == 1:
        return Estimate(mean, math.nan, math.nan, 1, math.nan, missing)
    std = float(values.std(ddof=1))
    half = _t_quantile(0.5 + confidence / 2.0, n - 1) * std / math.sqrt(n)
    return Estimate(mean, mean - half, mean + half, n, std, missing)


def paired_values(a, b):
    """``a[i] - b[i]`` per run, None where either is missing or not finite."""
    if len(a) != len(b):
        raise ValueError(f"paired samples of different lengths: {len(a)} and {len(b)}")
    differences = []
    for x, y in zip(a, b):
        ok = all(v is not None and math.isfinite(float(v)) for v in (x, y))
        differences.append(float(x) - float(y) if ok else None)
    return differences


def paired_difference(a, b, confidence=CONFIDENCE):
    """Interval of the mean of ``a[i] - b[i]`` over the runs where both are finite."""
    return mean_interval(paired_values(a, b), confidence)


def slope_interval(xs, runs, confidence=CONFIDENCE):
    """Interval of the mean per-run least-squares slope of a figure over ``xs``.

    Parameters
    ----------
    xs : sequence of float
        The abscissae (e.g. the speeds), at least two distinct values.
    runs : sequence of sequences
        ``runs[i][j]`` is run ``i``'s figure at ``xs[j]`` (None where missing; a run needs two
        finite points for a slope).

    Returns
    -------
    Estimate
        Of the slope, in units of the figure per unit of ``x``.
    """
    xs = np.asarray(xs, dtype=float)
    slopes = []
    for row in runs:
        row = np.array([math.nan if v is None else float(v) for v in row])
        ok = np.isfinite(row)
        if ok.sum() < 2 or np.ptp(xs[ok]) == 0.0:
            slopes.append(None)
            continue
        slopes.append(float(np.polyfit(xs[ok], row[ok], 1)[0]))
    return mean_interval(slopes, confidence)


def median_interval(samples, confidence=CONFIDENCE):
    """Median and its distribution-free interval from binomial order statistics.

    With the ``n`` finite samples sorted, ``x_(1) <= ... <= x_(n)``, the interval is
    ``[x_(k), x_(n-k+1)]`` for the largest ``k`` whose coverage ``1 - 2 P(B <= k-1)``,
    ``B ~ Binomial(n, 1/2)``, is at least ``confidence``: the number of samples below the
    true median is ``B`` for any continuous distribution, so the coverage is exact, with no
    assumption on the shape and no random resampling. It is the inversion of the sign test.
    Ranks need no finite values: a run entered as +-inf (lost, the worst outcome on its side)
    takes its place at the end, and a bound is infinite only if the losses reach its rank.
    For ``n = 20`` at 95 %: ``[x_(6), x_(15)]``, coverage 95.9 %; fewer than 6 samples cannot
    reach 95 % (``[min, max]`` of 5 covers 93.75 %), and the interval is then missing.

    Parameters
    ----------
    samples : sequence of float or None
        One value per run; None and non-finite values are counted as missing.
    confidence : float
        Least coverage of the interval.

    Returns
    -------
    Estimate
        ``method = "median"``, ``mean`` = the sample median, ``coverage`` the exact one
        (nan without an interval).

    Examples
    --------
    >>> e = median_interval(range(1, 21))
    >>> (e.low, e.high, round(e.coverage, 4))
    (6.0, 15.0, 0.9586)
    """
    samples = list(samples)
    values, missing = _ranked(samples)
    values = np.sort(values)
    n = len(values)
    if n == 0:
        return Estimate(math.nan, math.nan, math.nan, 0, math.nan, missing, "median", math.nan)
    middle = values[(n - 1) // 2], values[n // 2]
    median = float(middle[0] if middle[0] == middle[1] else 0.5 * (middle[0] + middle[1]))
    finite = values[np.isfinite(values)]
    std = float(finite.std(ddof=1)) if len(finite) > 1 else math.nan
    # the smallest k with P(B <= k) >= alpha / 2, so P(B <= k - 1) < alpha / 2: the largest
    # k whose interval covers at least 1 - alpha
    k, coverage = _median_rank(confidence, n)
    if k < 1:
        return Estimate(median, math.nan, math.nan, n, std, missing, "median", math.nan)
    return Estimate(median, float(values[k - 1]), float(values[n - k]), n, std, missing,
                    "median", coverage)


@dataclass(frozen=True)
class SignTest:
    """The paired sign test: runs above and below ``center``, ties, exact two-sided p."""

    positive: int
    negative: int
    ties: int
    p_value: float
    center: float = 0.0

    def text(self):
        """``sign test 20/0, p = 1.9e-06`` (``+ 2 ties`` when there are ties)."""
        ties = f" + {self.ties} ties" if self.ties else ""
        return f"sign test {self.positive}/{self.negative}{ties}, p = {self.p_value:.2g}"


def sign_test(differences, center=0.0):
    """Exact two-sided sign test of paired differences against ``center``.

    Counts the differences above and below ``center`` (+-inf count on their side; None and
    nan are left out); exact ties are left out (the usual convention). Under the null hypothesis that either side is equally likely, the
    number above is ``Binomial(positive + negative, 1/2)``; the p-value is the exact
    two-sided binomial one (:func:`scipy.stats.binomtest`), 1 when every run ties.

    Returns
    -------
    SignTest

    Examples
    --------
    >>> sign_test([0.1] * 20).text()
    'sign test 20/0, p = 1.9e-06'
    """
    values, _ = _ranked(list(differences))
    positive = int(np.count_nonzero(values > center))
    negative = int(np.count_nonzero(values < center))
    ties = len(values) - positive - negative
    total = positive + negative
    p = _sign_test_p(positive, total) if total else 1.0
    return SignTest(positive, negative, ties, p, float(center))


# The study asks these of scipy thousands of times for a few dozen distinct counts (each call
# about a millisecond): the values are kept, exactly as scipy gave them.
@lru_cache(maxsize=None)
def _t_quantile(q, dof):
    return float(stats.t.ppf(q, dof))


@lru_cache(maxsize=None)
def _median_rank(confidence, n):
    """The rank ``k`` of the median interval of ``n`` values and its exact coverage."""
    k = int(stats.binom.ppf((1.0 - confidence) / 2.0, n, 0.5))
    coverage = 1.0 - 2.0 * float(stats.binom.cdf(k - 1, n, 0.5)) if k >= 1 else math.nan
    return k, coverage


@lru_cache(maxsize=None)
def _sign_test_p(positive, total):
    return float(stats.binomtest(positive, total, 0.5).pvalue)


@dataclass(frozen=True)
class Separation:
    """The largest gap between neighbouring sorted values against the robust spread."""

    gap: float
    spread: float
    below: float
    above: float
    separated: bool

    def text(self):
        """E.g. ``values separated: gap 0.37 between 0.045 and 0.41 = 93 robust spreads``."""
        size = ("any gap (over half the values equal)" if self.spread == 0.0
                else f"{self.gap / self.spread:.3g} robust spreads")
        return (f"values separated: gap {self.gap:.3g} between {self.below:.3g} and "
                f"{self.above:.3g} = {size}")


def separation(samples, factor=SEPARATION_FACTOR, min_runs=SEPARATION_MIN_RUNS):
    """Whether the finite samples fall into separated clusters (see ``SEPARATION_FACTOR``).

    The robust spread is ``1.4826 x median(|x - median(x)|)`` (the standard deviation for a
    normal sample, unmoved by a minority cluster); the sample is separated when its largest
    neighbour gap exceeds ``factor`` spreads. When over half the values are equal the spread
    is 0 and any gap separates them.

    Returns
    -------
    Separation or None
        None for fewer than ``min_runs`` finite values or no gap at all.
    """
    values, _ = _finite(list(samples))
    if len(values) < min_runs:
        return None
    values = np.sort(values)
    gaps = np.diff(values)
    widest = int(np.argmax(gaps))
    gap = float(gaps[widest])
    if gap == 0.0:
        return None
    spread = 1.4826 * float(np.median(np.abs(values - np.median(values))))
    return Separation(gap, spread, float(values[widest]), float(values[widest + 1]),
                      gap > factor * spread)


@dataclass(frozen=True)
class Evidence:
    """The interval a claim uses, the rule that chose it, and what the runs say beside it.

    Attributes
    ----------
    estimate : Estimate
        The interval to judge on (t-interval of the mean or the median's interval).
    rule : str
        Why that interval, in words with the numbers.
    failed : int
        Runs without a finite value (failed runs, or figures the run could not give).
    lost : int
        Runs the caller flags as lost (e.g. never arrived), whatever their value.
    sign : SignTest
        The sign test of the finite values against the claim's reference.
    separation : Separation or None
        The cluster check (None when it was not applied).
    """

    estimate: Estimate
    rule: str
    failed: int
    lost: int
    sign: SignTest
    separation: object = None

    @property
    def method(self):
        """``"mean"`` or ``"median"``: which interval was chosen."""
        return self.estimate.method

    def text(self):
        """E.g. ``sign test 17/3, p = 0.0026; 3 lost runs; median interval``."""
        parts = [self.sign.text()]
        if self.failed:
            parts.append(f"{self.failed} failed run" + ("s" if self.failed > 1 else ""))
        if self.lost:
            parts.append(f"{self.lost} lost run" + ("s" if self.lost > 1 else ""))
        if self.separation is not None and self.separation.separated:
            parts.append(self.separation.text())
        parts.append(f"{self.estimate.method} interval")
        return "; ".join(parts)


def evidence(samples, lost=None, center=0.0, confidence=CONFIDENCE):
    """The interval to judge a sample on, chosen by the module's rule, with the sign test.

    The median interval (:func:`median_interval`) when any sample is missing (a failed
    run), any run is flagged in ``lost``, or the values are separated
    (:func:`separation`); the Student-t interval of the mean (:func:`mean_interval`)
    otherwise.

    Parameters
    ----------
    samples : sequence of float or None
        One value per run (e.g. the paired differences, :func:`paired_values`).
    lost : sequence of bool, optional
        Per run, True if the run lost control (the caller's criterion, e.g. it never
        arrived); aligned with ``samples``. A sample of +-inf counts as lost too (a lost run
        entered as the worst outcome on its side) and keeps its rank.
    center : float
        Reference of the sign test (the claim's threshold, usually 0).
    confidence : float
        Coverage of the interval.

    Returns
    -------
    Evidence
    """
    samples = list(samples)
    lost = [False] * len(samples) if lost is None else list(lost)
    if len(lost) != len(samples):
        raise ValueError(f"lost flags for {len(lost)} runs, samples of {len(samples)}")
    infinite = [v is not None and not isinstance(v, bool) and math.isinf(float(v))
                for v in samples]
    lost_count = sum(1 for flag, inf in zip(lost, infinite) if flag or inf)
    failed = len(samples) - len(_ranked(samples)[0])
    split = separation(samples)
    reasons = []
    if failed:
        reasons.append(f"{failed} failed")
    if lost_count:
        reasons.append(f"{lost_count} lost")
    if split is not None and split.separated:
        reasons.append("separated values")
    if reasons:
        estimate = median_interval(samples, confidence)
        rule = f"median interval ({', '.join(reasons)})"
    else:
        estimate = mean_interval(samples, confidence)
        rule = "t-interval of the mean (no failed or lost runs, no separated values)"
    return Evidence(estimate, rule, failed, lost_count, sign_test(samples, center), split)


def paired_evidence(a, b, lost=None, center=0.0, confidence=CONFIDENCE):
    """:func:`evidence` on the paired differences ``a[i] - b[i]`` (see :func:`paired_values`).

    ``lost`` flags a pair (True if either run of the pair lost control).
    """
    return evidence(paired_values(a, b), lost, center, confidence)


def judge(estimate, threshold, claimed="above"):
    """Verdict of a claim that the true mean lies ``claimed`` ("above" / "below") a threshold.

    Returns
    -------
    str
        :data:`SUPPORTED` if the whole interval is on the claimed side, :data:`NOT_SUPPORTED`
        if it is wholly on the other side (or on the threshold), else :data:`INCONCLUSIVE`
        (also without an interval: fewer than two runs).
    """
    if claimed not in ("above", "below"):
        raise ValueError(f"claimed = {claimed!r}; valid choices: above, below")
    if estimate.n < 2 or not (math.isfinite(estimate.low) and math.isfinite(estimate.high)):
        return INCONCLUSIVE
    low, high = estimate.low, estimate.high
    if claimed == "below":
        low, high, threshold = -high, -low, -threshold
    if low > threshold:
        return SUPPORTED
    if high <= threshold:
        return NOT_SUPPORTED
    return INCONCLUSIVE
