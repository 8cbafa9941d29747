"""Intervals and verdicts over Monte Carlo runs.

Each figure of the report is the mean over a cell's runs with a two-sided Student-t interval
(:func:`mean_interval`). A claim compares two cells run by run (the runs share their draws,
:mod:`orchestrator.reproduce.tolerances`) and is judged on the interval of the mean paired
difference against a stated threshold (:func:`judge`): *supported* when the whole interval lies
on the claimed side of the threshold, *not supported* when it lies wholly on the other side,
*inconclusive* when it straddles the threshold. A growth-with-speed claim uses every speed: per
run, the least-squares slope of the figure over the speeds, then the interval of the mean slope
(:func:`slope_interval`).
"""

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

__all__ = ["CONFIDENCE", "SUPPORTED", "NOT_SUPPORTED", "INCONCLUSIVE", "Estimate",
           "mean_interval", "paired_difference", "slope_interval", "judge"]

CONFIDENCE = 0.95
SUPPORTED, NOT_SUPPORTED, INCONCLUSIVE = "supported", "not supported", "inconclusive"


@dataclass(frozen=True)
class Estimate:
    """Mean of ``n`` finite samples with its confidence interval ``[low, high]``.

    ``missing`` counts the samples that were None or not finite (e.g. a run that did not
    settle); they are left out of the mean, and the report shows the count.
    """

    mean: float
    low: float
    high: float
    n: int
    std: float
    missing: int = 0

    def to_dict(self):
        """JSON-able form (non-finite values as None)."""
        def clean(v):
            return float(v) if v is not None and math.isfinite(v) else None
        return {"mean": clean(self.mean), "low": clean(self.low), "high": clean(self.high),
                "n": self.n, "std": clean(self.std), "missing": self.missing}

    def text(self, fmt=".3f"):
        """``mean [low, high]``, or ``-`` without samples."""
        if self.n == 0:
            return "-"
        if self.n == 1 or not math.isfinite(self.low):
            return format(self.mean, fmt)
        return f"{self.mean:{fmt}} [{self.low:{fmt}}, {self.high:{fmt}}]"


def _finite(samples):
    values = [float(v) for v in samples
              if v is not None and not isinstance(v, bool) and math.isfinite(float(v))]
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
    half = float(stats.t.ppf(0.5 + confidence / 2.0, n - 1)) * std / math.sqrt(n)
    return Estimate(mean, mean - half, mean + half, n, std, missing)


def paired_difference(a, b, confidence=CONFIDENCE):
    """Interval of the mean of ``a[i] - b[i]`` over the runs where both are finite."""
    if len(a) != len(b):
        raise ValueError(f"paired samples of different lengths: {len(a)} and {len(b)}")
    differences = []
    for x, y in zip(a, b):
        ok = all(v is not None and math.isfinite(float(v)) for v in (x, y))
        differences.append(float(x) - float(y) if ok else None)
    return mean_interval(differences, confidence)


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
