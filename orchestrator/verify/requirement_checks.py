"""Verdicts on the off-nominal requirements, and how far each holds.

One check per requirement and design (``<requirement>_<design>``): a requirement for the
default form (what WheelController runs), a finding for the paper's form and the CPID (their
failures judge the paper's design, not ours). A check passes when the requirement holds on
every judged wheel (:func:`.wheel_experiments.judged_cells`) on the discrete-time loop and,
where it runs, through the FMUs. :func:`largest_ranges` says over which plant-gain and
time-constant ranges of the evaluated grid it holds; :func:`design_lines` is the report's
first screen.
"""

import math

from .checks import Check
from .designs import DESIGN_LABELS, UNCOMMISSIONED
from .wheel_experiments import REQUIREMENTS, judged_words

__all__ = ["check_requirement", "largest_ranges", "design_lines", "REQUIREMENT_LABELS",
           "format_value", "requirement_checks", "span_words"]

REQUIREMENT_LABELS = {
    "off_nominal_settling": "settling", "load_step_recovery": "load recovery",
    "ramp_lag": "ramp lag", "no_creep": "creep", "no_limit_cycle": "limit cycle",
    "no_slip_chatter": "slip chatter"}
# (scale, unit, format) of each requirement's value in words
_UNITS = {"off_nominal_settling": (1.0, "s", ".2f"), "load_step_recovery": (1.0, "s", ".2f"),
          "ramp_lag": (1000.0, "mm/s", ".1f"), "no_creep": (1000.0, "mm", ".2f"),
          "no_limit_cycle": (1.0, "quanta", ".2f"),
          "no_slip_chatter": (1.0, "slide entries in 1 s", "g")}


def format_value(name, value):
    """A requirement's measured value in words with its unit (``never`` for inf)."""
    scale, unit, spec = _UNITS[name]
    if value is None or not math.isfinite(value):
        return "never" if name in ("off_nominal_settling", "load_step_recovery") else "inf"
    return f"{format(scale * value, spec)} {unit}"


def _threshold(name, table):
    if name == "off_nominal_settling":
        return (f"2 % settling ({100 * table['band_fraction']:g} % of a {table['step_m_s']:g} m/s "
                f"step) <= {table['max_settling_time_s']:g} s")
    if name == "load_step_recovery":
        return (f"recovery into +-{100 * table['band_fraction']:g} % after a load of "
                f"{100 * table['load_fraction_of_stall']:g} % of stall torque <= "
                f"{table['max_recovery_time_s']:g} s")
    if name == "ramp_lag":
        bound = table["acceleration_m_s2"] * table["fix_period_s"]
        return (f"lag behind the {table['acceleration_m_s2']:g} m/s^2 ramp <= "
                f"{1000 * bound:g} mm/s (a_max x fix period {table['fix_period_s']:g} s)")
    if name == "no_creep":
        return (f"travel with the reference held at 0 < {1000 * table['max_creep_m']:g} mm "
                f"(over {table['hold_time_s']:g} s, from {table['settle_allowance_s']:g} s "
                "after the stop)")
    if name == "no_limit_cycle":
        return (f"true speed peak-to-peak at {table['speed_m_s']:g} m/s < "
                f"{table['max_peak_to_peak_quanta']:g} encoder quantum")
    return (f"at most {table['max_entries_per_second']:g} slide entries in any 1 s of the "
            "trapezoid, friction 0.05..0.4")


def _contiguous(values, passes, around=1.0):
    """The contiguous run of passing ``values`` around ``around``: (low, high) or None."""
    index = min(range(len(values)), key=lambda i: abs(math.log(values[i] / around)))
    if not passes[index]:
        return None
    low = high = index
    while low > 0 and passes[low - 1]:
        low -= 1
    while high < len(values) - 1 and passes[high + 1]:
        high += 1
    return values[low], values[high]


def largest_ranges(rows, gains, taus):
    """Where a requirement holds on the evaluated grid, around RobotPlant's wheel.

    Parameters
    ----------
    rows : list of dict
        One per cell: ``gain_factor``, ``time_constant_factor``, ``passed``.
    gains, taus : sequence of float
        The grid's factors, sorted.

    Returns
    -------
    dict
        ``gain_at_tau_1`` and ``tau_at_gain_1``: the contiguous ranges through the nominal
        wheel along each axis (None when it fails there); ``box``: the largest rectangle of
        passing cells containing the nominal wheel, by its number of cells, then by the
        product of its log spans (``[g_lo, g_hi, t_lo, t_hi]`` or None); ``passing`` and
        ``cells``: counts.
    """
    ok = {(r["gain_factor"], r["time_constant_factor"]): r["passed"] for r in rows}
    gains, taus = sorted(gains), sorted(taus)
    g1 = min(gains, key=lambda g: abs(math.log(g)))
    t1 = min(taus, key=lambda t: abs(math.log(t)))
    best, box = None, None
    for i in range(len(gains)):
        for j in range(i, len(gains)):
            if not gains[i] <= g1 <= gains[j]:
                continue
            for k in range(len(taus)):
                for m in range(k, len(taus)):
                    if not taus[k] <= t1 <= taus[m]:
                        continue
                    if all(ok.get((g, t), False) for g in gains[i:j + 1] for t in taus[k:m + 1]):
                        size = ((j - i + 1) * (m - k + 1),
                                math.log(gains[j] / gains[i]) * math.log(taus[m] / taus[k]))
                        if box is None or size > best:
                            best, box = size, [gains[i], gains[j], taus[k], taus[m]]
    return {"gain_at_tau_1": _contiguous(gains, [ok.get((g, t1), False) for g in gains]),
            "tau_at_gain_1": _contiguous(taus, [ok.get((g1, t), False) for t in taus]),
            "box": box, "passing": sum(1 for v in ok.values() if v), "cells": len(ok)}


def span_words(low, high):
    """``x0.5..x2``, or ``x1 only`` for a single factor."""
    return f"x{low:g} only" if low == high else f"x{low:g}..x{high:g}"


def _range_words(ranges):
    if not ranges["box"]:
        # the box always contains the nominal wheel, so no box means it fails there
        return (f"fails on RobotPlant's own wheel ({ranges['passing']} of {ranges['cells']} "
                "wheels pass)")

    def span(pair, what):
        return f"{what} {span_words(*pair)}" if pair else f"not at {what} x1"
    box = ranges["box"]
    boxed = (f"largest box gain {span_words(box[0], box[1])} by tau "
             f"{span_words(box[2], box[3])}")
    return (f"holds for {span(ranges['gain_at_tau_1'], 'gain')} at tau x1 and "
            f"{span(ranges['tau_at_gain_1'], 'tau')} at gain x1; {boxed} "
            f"({ranges['passing']} of {ranges['cells']} wheels pass)")


def _worst(rows):
    return max(rows, key=lambda r: (not r["passed"], r["value"] if math.isfinite(r["value"])
                                    else math.inf))


def check_requirement(name, design, model_rows, fmu_rows, grid, table, judged,
                      fmu_absent="the FMUs were not run"):
    """The verdict of one requirement for one design.

    Parameters
    ----------
    name, design : str
    model_rows : list of dict
        The discrete-time loop's results over the whole evaluated grid.
    fmu_rows : list of dict or None
        The FMU results on the judged cells (None: not run).
    grid, table : dict
        ``off_nominal_grid`` and the requirement's table.
    judged : list of (float, float)
    fmu_absent : str, optional
        Why there are no FMU results, when ``fmu_rows`` is None.

    Returns
    -------
    Check
    """
    judged = set(judged)
    on_judged = [r for r in model_rows if (r["gain_factor"], r["time_constant_factor"]) in judged]
    failing = [r for r in on_judged if not r["passed"]]
    fmu_failing = [r for r in (fmu_rows or []) if not r["passed"]]
    ranges = largest_ranges(model_rows, grid["gain_factors"], grid["time_constant_factors"])
    worst = _worst(on_judged)

    def where(r):
        text = f"gain x{r['gain_factor']:g}, tau x{r['time_constant_factor']:g}"
        return text + (f", mu {r['at_friction']:g}" if r.get("at_friction") is not None else "")

    measured = (f"loop: worst {format_value(name, worst['value'])} at {where(worst)}; "
                f"{len(failing)} of {len(on_judged)} judged wheels fail")
    if fmu_rows is not None:
        fmu_worst = _worst(fmu_rows)
        measured += (f"; FMUs: worst {format_value(name, fmu_worst['value'])} at "
                     f"{where(fmu_worst)}, {len(fmu_failing)} fail")
    else:
        measured += f"; FMUs: not run ({fmu_absent})"
    measured += f". On the grid it {_range_words(ranges)}."
    severity = "requirement" if design == "default" else "finding"
    return Check(name=f"{name}_{design}",
                 title=f"{table['title']} ({DESIGN_LABELS[design]})",
                 requirement=f"{_threshold(name, table)} on the {len(on_judged)} judged "
                             f"wheels ({judged_words(grid)}), "
                             + ("as shipped (RobotPlant's constants), on the loop"
                                if design in UNCOMMISSIONED else
                                "each commissioned first, on the loop and through the FMUs"),
                 measured=measured, passed=not failing and not fmu_failing,
                 severity=severity,
                 values={"worst": worst["value"], "failing": len(failing),
                         "fmu_failing": len(fmu_failing) if fmu_rows is not None else None,
                         "ranges": ranges},
                 why=table["why"])


def requirement_checks(results, req):
    """Every requirement's check for every design, requirement outer.

    Parameters
    ----------
    results : dict
        ``{"model": design -> requirement -> rows, "fmu": design -> requirement -> rows or
        {}, "judged": cells}``.
    req : dict
        The requirements file's tables.
    """
    grid = req["off_nominal_grid"]
    out = []
    for name in REQUIREMENTS:
        for design, by_name in results["model"].items():
            fmu = results["fmu"].get(design, {}).get(name)
            out.append(check_requirement(name, design, by_name[name], fmu, grid, req[name],
                                         results["judged"]))
    return out


def design_lines(checks):
    """One line per design: which off-nominal requirements it meets on the judged wheels."""
    lines = []
    for design, label in DESIGN_LABELS.items():
        mine = [c for c in checks if c.name.endswith(f"_{design}")
                and c.name[:-len(design) - 1] in REQUIREMENTS]
        if not mine:
            continue
        met = [REQUIREMENT_LABELS[c.name[:-len(design) - 1]] for c in mine if c.passed]
        failed = [REQUIREMENT_LABELS[c.name[:-len(design) - 1]] for c in mine if not c.passed]
        line = f"{label}: meets {', '.join(met) if met else 'none'}"
        line += f"; fails {', '.join(failed)}" if failed else " (all six)"
        lines.append(line + ".")
    return lines
