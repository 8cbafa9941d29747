"""A claim of the paper, judged on its runs: the effect, the paper's magnitude, the verdict.

A :class:`Claim` holds one value per run of what the claim is about (a paired difference
between two cells whose run i shares its draws, a per-run slope over the speeds, or a
figure), the direction the paper claims, the paper's own magnitude of the effect in the same
units (None where the paper gives only text) and the runs that failed or were lost. The
interval, the sign test and the verdict are computed from those, never set by hand
(:mod:`orchestrator.reproduce.verdicts`). The reason shown beside it is written from the
mechanisms measured in the cells the claim compares (:func:`mechanism_text`), never a fixed
text per claim.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from orchestrator.files.json_policy import json_ready

from .statistics import evidence
from .verdicts import (CONTRADICTED, INCONCLUSIVE, NO_EFFECT, SUPPORTED, WEAKER,  # noqa: F401
                       classify)

__all__ = ["Judgement", "judge_claim", "Claim", "MECHANISMS", "CONTROL_MECHANISMS",
           "MOTION_MECHANISMS", "ROTATE_MECHANISMS", "MODES_MECHANISMS", "TRACKING_MECHANISMS", "mechanism_figures", "mechanism_text", "paired_at_arrival",
           "per_run_slopes", "failure_text", "FAILURE_TEXT"]


@dataclass(frozen=True)
class Judgement:
    """How a claim fares: the evidence (interval, rule, sign test, lost runs) and the verdict
    (:func:`~orchestrator.reproduce.verdicts.classify`)."""

    evidence: object
    verdict: object
    paper_note: str = ""

    @property
    def category(self):
        return self.verdict.category

    @property
    def estimate(self):
        return self.evidence.estimate

    @property
    def interval_rule(self):
        return self.evidence.rule

    @property
    def sign_test(self):
        sign = self.evidence.sign
        return {"plus": sign.positive, "minus": sign.negative, "ties": sign.ties,
                "p_value": sign.p_value}

    @property
    def ratio(self):
        return self.verdict.ratio

    def rule_text(self, unit=""):
        """The rule's numbers and the one that decided, e.g. ``"below 0 m; no effect within
        +-0.0102 m; ..."``."""
        unit = f" {unit}" if unit else ""
        v = self.verdict
        text = f"{v.claimed} {v.threshold:.4g}{unit}"
        if v.margin:
            text += f"; no effect within +-{v.margin:.3g}{unit}"
        if v.paper is not None:
            text += f"; supported needs >= {v.support_fraction:g} x the paper's {v.paper:.3g}"
        if self.paper_note:
            text += f"; {self.paper_note}"
        return f"{text}. Decided: {v.rule}"


def judge_claim(samples, claimed, paper=None, threshold=0.0, margin=None):
    """The evidence and verdict of one claim.

    ``paper`` is the paper's own value of the measure (signed, e.g. its difference of two
    printed numbers); its magnitude in the claimed direction is what the verdict compares
    with. A paper value on the other side of the threshold (the paper's own numbers do not
    show what it claims) is not a magnitude: the claim is then judged on its direction alone,
    and the rule says why.
    """
    found = evidence(samples, center=threshold)
    magnitude, note = None, ""
    if paper is not None and math.isfinite(paper):
        signed = (paper - threshold) * (1.0 if claimed == "above" else -1.0)
        if signed > 0:
            magnitude = signed
        else:
            note = f"the paper's own value {paper:.3g} is not on the claimed side"
    # a loss is entered as +-inf on its side: -inf in the claimed direction is a run lost by
    # the arm the claim favours alone
    sign = 1.0 if claimed == "above" else -1.0
    infinite = [sign * float(v) for v in samples
                if v is not None and not isinstance(v, bool) and math.isinf(float(v))]
    verdict = classify(found.estimate, magnitude, claimed, threshold,
                       margin=0.0 if margin is None else float(margin),
                       lost_against=sum(v < 0 for v in infinite),
                       lost_for=sum(v > 0 for v in infinite))
    return Judgement(found, verdict, note)


@dataclass
class Claim:
    """One claim under one condition.

    Attributes
    ----------
    source, claim, condition : str
        Where the paper makes it, what it says, the condition it is judged under.
    measure : str
        What ``samples`` hold, e.g. ``"paired difference error(CFGS-PD) - error(CPID)"``.
    samples : list
        One value per run (None where the run gave none).
    claimed : str
        ``"below"`` or ``"above"`` ``threshold``: the direction the paper claims.
    unit : str
    paper : float or None
        The paper's own value of the measure (e.g. its difference of two printed numbers),
        None where it gives only text.
    paper_text : str
        The paper's numbers as printed.
    threshold : float
        What the effect is measured from (0 for a difference; a bound for a test).
    margin : float or None
        Equivalence margin of "no effect" (None: the verdict rule's default).
    comparator : str
        What the claim compares against (e.g. ``"CPID, per-second ki"``).
    failures : int
        Runs of the compared cells that failed or were lost (shown beside the interval; they
        make the interval robust).
    reason : str
        The mechanisms measured in the compared cells (:func:`mechanism_text`).
    tally : bool
        True for a claim of the paper (counted in the tally once per condition); False for a
        design comparison of ours, listed apart.
    cells : tuple of str
        The cells the claim compares (for the figures shown beside it).
    """

    source: str
    claim: str
    condition: str
    measure: str
    samples: list
    claimed: str
    unit: str = ""
    paper: float = None
    paper_text: str = ""
    threshold: float = 0.0
    margin: float = None
    comparator: str = ""
    failures: int = 0
    reason: str = ""
    tally: bool = True
    cells: tuple = ()
    _judged: object = field(default=None, repr=False, compare=False)

    @property
    def judged(self):
        """The :class:`~orchestrator.reproduce.verdicts.Judgement` (computed once)."""
        if self._judged is None:
            self._judged = judge_claim(self.samples, self.claimed, self.paper,
                                       threshold=self.threshold, margin=self.margin)
        return self._judged

    @property
    def estimate(self):
        """The interval the verdict was read from (t-interval or robust, by rule)."""
        return self.judged.estimate

    @property
    def verdict(self):
        """supported / weaker than claimed / no effect / contradicted / inconclusive."""
        return self.judged.category

    def requirement(self):
        """The verdict rule's numbers as text (threshold, margin, paper magnitude)."""
        return self.judged.rule_text(self.unit)

    def to_dict(self):
        """JSON-able form."""
        judged = self.judged
        return {"source": self.source, "claim": self.claim, "condition": self.condition,
                "comparator": self.comparator, "measure": self.measure,
                "estimate": self.estimate.to_dict(), "interval_rule": judged.interval_rule,
                "sign_test": json_ready(judged.sign_test), "failures": self.failures,
                "claimed": self.claimed, "threshold": json_ready(self.threshold),
                "unit": self.unit, "paper": json_ready(self.paper),
                "paper_text": self.paper_text, "ratio": json_ready(judged.ratio),
                "requirement": self.requirement(), "verdict": self.verdict,
                "reason": self.reason, "tally": self.tally, "cells": list(self.cells)}


# The mechanisms measured per cell, by kind of claim, each with how it is shown: (figure key,
# label, scale, unit, format). They are figures of orchestrator/reproduce/measures.py and
# orchestrator/reproduce/following.py.
_SHOWN = {
    "arrival_s": ("arrival", 1.0, "s", ".2f"),
    "error_at_arrival_m": ("error at arrival", 1000.0, "mm", ".0f"),
    "drift_after_arrival_m": ("creep after arrival", 1000.0, "mm", ".0f"),
    "rmse_speed_m_s": ("wheel-speed RMS error", 1000.0, "mm/s", ".1f"),
    "slip_time_s": ("slip time", 1.0, "s", ".2f"),
    "peak_slip": ("peak slip ratio", 1.0, "", ".3f"),
    "turn_error_deg": ("turn error", 1.0, "deg", ".1f"),
    "radius_fit_m": ("radius driven", 1.0, "m", ".3f"),
    "fix_range_bias_m": ("heard-range bias", 1000.0, "mm", ".0f"),
    "fix_bearing_rmse_deg": ("heard-bearing RMS error", 1.0, "deg", ".2f"),
    "late_gap_m": ("gap in the 2nd half", 1.0, "m", ".3f"),
    "lane_rms_m": ("RMS from the source's path", 1000.0, "mm", ".0f"),
    "rmse_own_plan_m": ("RMS from own plan", 1000.0, "mm", ".1f"),
    "min_gap_m": ("smallest gap", 1.0, "m", ".3f"),
}
# The smallest difference between two cells' medians that counts as a mechanism, per
# measure (SI units): below it the measure does not resolve a difference (one 20 ms sample for
# times, a few encoder quanta of 0.5 mm for positions, the localizer's mm-level bias jitter), so
# a -0 vs -1 mm heard-range bias is not "the largest difference" however large its ratio.
_RESOLUTION = {
    "arrival_s": 0.1, "error_at_arrival_m": 0.002, "drift_after_arrival_m": 0.002,
    "rmse_speed_m_s": 0.001, "slip_time_s": 0.02, "peak_slip": 0.01, "turn_error_deg": 0.2,
    "radius_fit_m": 0.01, "fix_range_bias_m": 0.005, "fix_bearing_rmse_deg": 0.05,
    "late_gap_m": 0.02, "lane_rms_m": 0.005, "rmse_own_plan_m": 0.002, "min_gap_m": 0.02,
}
CONTROL_MECHANISMS = ("arrival_s", "error_at_arrival_m", "drift_after_arrival_m",
                      "rmse_speed_m_s", "slip_time_s", "peak_slip")
# Tables 1-3: each mode's own geometry (the turn on the spot of rotate then go, the driven
# radius of the arc), and what both share when the two modes are compared
MOTION_MECHANISMS = ("arrival_s", "error_at_arrival_m", "rmse_speed_m_s", "radius_fit_m",
                     "fix_range_bias_m", "fix_bearing_rmse_deg")
ROTATE_MECHANISMS = ("arrival_s", "error_at_arrival_m", "rmse_speed_m_s", "turn_error_deg",
                     "fix_range_bias_m", "fix_bearing_rmse_deg")
MODES_MECHANISMS = ("arrival_s", "error_at_arrival_m", "rmse_speed_m_s", "rmse_own_plan_m",
                    "fix_range_bias_m", "fix_bearing_rmse_deg")
TRACKING_MECHANISMS = ("late_gap_m", "lane_rms_m", "rmse_own_plan_m", "min_gap_m",
                       "slip_time_s", "fix_range_bias_m", "fix_bearing_rmse_deg")
MECHANISMS = {"control": CONTROL_MECHANISMS, "motion": MOTION_MECHANISMS,
              "rotate": ROTATE_MECHANISMS, "modes": MODES_MECHANISMS,
              "tracking": TRACKING_MECHANISMS}


def _median(values):
    finite = [float(v) for v in values if v is not None and math.isfinite(float(v))]
    return float(np.median(finite)) if finite else None


def mechanism_figures(analysis, cell, keys=CONTROL_MECHANISMS):
    """Median of each mechanism over a cell's runs, and how many runs never arrived."""
    figures = analysis.figures(cell)
    ran = [f for f in figures if f is not None]
    arrived = [f for f in ran if f.get("arrived")]
    out = {"runs": len(figures), "failed": len(figures) - len(ran),
           "arrived": len(arrived) if ran and "arrived" in ran[0] else None}
    for key in keys:
        out[key] = _median([f.get(key) for f in ran])
    return out


def _shown(value, scale, unit, fmt):
    return "-" if value is None else f"{value * scale:{fmt}} {unit}".strip()


# How much of a failed run's error a reason quotes (the report lists every failed run whole).
FAILURE_TEXT = 110


def failure_text(index, summary, kind):
    """One failed run as a reason shows it: when, why, and (tracking) the smallest gap it had
    reached by then, which bounds the whole run's from above."""
    error = str(summary.get("error") or summary.get("status") or "no reason recorded")
    # "instance X returned fmi2Discard in doStep at t = ...: <the FMU's own message>"
    error = error.split(": ", 1)[1] if error.startswith("instance ") and ": " in error else error
    if len(error) > FAILURE_TEXT:
        error = error[:FAILURE_TEXT].rsplit(" ", 1)[0] + " ..."
    when = summary.get("sim_time_s")
    text = f"run {index} failed" + (f" at {float(when):.2f} s" if when is not None else "")
    text += f" ({error})"
    gap = summary.get("min_distance_to_source_m")
    if kind == "tracking" and gap is not None:
        text += f", smallest gap before it {float(gap):.3f} m"
    return text


def mechanism_text(analysis, cells, kind="control"):
    """The measured mechanisms of the compared cells, the most different first.

    Measures are ranked by the relative difference of the two cells' medians, counted only
    where the absolute difference reaches the measure's resolution (:data:`_RESOLUTION`); the
    first is named "largest difference" when it exceeds 25 %.

    Parameters
    ----------
    analysis : Analysis
    cells : dict
        Label -> cell name (e.g. ``{"CFGS-PD": ..., "CPID": ...}``), two or one.
    kind : str
        Which mechanisms to measure (:data:`MECHANISMS`): control, motion (a curvature cell),
        rotate (a rotate-then-go cell), modes (the two modes compared) or tracking.

    Returns
    -------
    str
        E.g. ``"CFGS-PD: 17/20 arrived, 3 never (final error ...); largest difference: creep
        after arrival 0 vs 26 mm; ..."``; says so where no mechanism was measured.
    """
    keys = MECHANISMS[kind]
    measured = {label: mechanism_figures(analysis, cell, keys) for label, cell in cells.items()}
    labels = list(measured)
    parts = []
    for label in labels:
        m = measured[label]
        if m["arrived"] is not None:
            parts.append(f"{label}: {m['arrived']}/{m['runs']} arrived"
                         + (f", {m['failed']} failed" if m["failed"] else ""))
        elif m["failed"]:
            parts.append(f"{label}: {m['failed']}/{m['runs']} failed")
        parts += [failure_text(index, summary, kind)
                  for index, summary in analysis.failed_runs(cells[label])[:2]]
    ranked = []
    for key in keys:
        name, scale, unit, fmt = _SHOWN[key]
        values = [measured[label][key] for label in labels]
        if any(v is None for v in values):
            continue
        if len(values) == 2 and abs(values[0] - values[1]) >= _RESOLUTION[key]:
            spread = abs(values[0] - values[1]) / max(abs(values[0]), abs(values[1]))
        else:   # one cell, or a difference the measure does not resolve
            spread = 0.0
        text = " vs ".join(_shown(v, scale, "", fmt) for v in values) + f" {unit}".rstrip()
        ranked.append((spread, f"{name} {text}"))
    if not ranked:
        return "; ".join(parts + ["mechanisms not measured in these cells"])
    ranked.sort(key=lambda item: -item[0])
    head = ("medians " + " vs ".join(labels) + ": " if len(labels) == 2
            else f"medians {labels[0]}: ")
    if len(labels) == 2 and ranked[0][0] > 0.25:
        head += f"largest difference {ranked[0][1]}; "
        ranked = ranked[1:]
    return "; ".join(parts + [head + "; ".join(text for _, text in ranked)])


# Figures read at arrival: a run that never arrived has none, and is lost for them. Figures
# of the whole run (path RMSE, slip time) are measured whether it arrived or not: a robot that
# lost control shows it in them, and one that creeps at 2 cm/s has not lost its path.
AT_ARRIVAL = ("error_at_arrival_m", "arrival_s", "drift_after_arrival_m")


def paired_at_arrival(analysis, better, comparator, key):
    """Per-run ``key(better) - key(comparator)``, losses as +-inf; and the lost-run count.

    A run that failed is a loss; so is one that never arrived (figure ``arrived`` false) when
    ``key`` is read at arrival (:data:`AT_ARRIVAL`). Returns ``(samples, losses)``,
    ``losses`` counting runs lost on either side.
    """
    samples, losses = [], 0
    at_arrival = key in AT_ARRIVAL
    for a, b in zip(analysis.figures(better), analysis.figures(comparator)):
        lost_a = a is None or (at_arrival and not a.get("arrived", True))
        lost_b = b is None or (at_arrival and not b.get("arrived", True))
        losses += int(lost_a) + int(lost_b)
        if lost_a and lost_b:
            samples.append(None)
        elif lost_a:
            samples.append(math.inf)
        elif lost_b:
            samples.append(-math.inf)
        else:
            x, y = a.get(key), b.get(key)
            samples.append(None if x is None or y is None else float(x) - float(y))
    return samples, losses


def per_run_slopes(xs, runs):
    """Per-run least-squares slope of a figure over ``xs`` (None for a run with < 2 values).

    ``runs[i][j]`` is run ``i``'s figure at ``xs[j]`` (None where missing).
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
    return slopes
