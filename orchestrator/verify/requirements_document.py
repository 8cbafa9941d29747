"""The off-nominal requirements in the verification report: which design meets what, where.

:func:`off_nominal_section` adds, to the report's :class:`~orchestrator.report.document.Document`,
one line per design, a table per requirement (verdict, worst value on the judged wheels on
the loop and through the FMUs, and how far it holds on the grid) and the grid of values;
:func:`summary_findings` gives the report's opening lines.
"""

from orchestrator.report.document import Code, Column, Verdict

from .designs import DESIGN_LABELS
from .requirement_checks import design_lines, format_value, largest_ranges, span_words
from .wheel_experiments import REQUIREMENTS, judged_words

__all__ = ["off_nominal_section", "summary_findings", "is_off_nominal_finding"]

_TONES = {"pass": "pass", "FAIL": "fail", "warning": "warn"}
_SHORT = {"default": "d", "paper": "p", "pid": "pid", "default_uncommissioned": "d0"}


def is_off_nominal_finding(check):
    """Whether ``check`` is an off-nominal requirement judged on the paper's designs."""
    return any(check.name == f"{name}_{design}" for name in REQUIREMENTS
               for design in ("paper", "pid"))


def summary_findings(report):
    """The report's opening lines: which design meets what, then each failed check or
    finding other than the paper's designs' off-nominal ones (those are in the first lines).
    """
    lines = design_lines(report.checks)
    rest = sorted((c for c in report.checks if not c.passed and not is_off_nominal_finding(c)),
                  key=lambda c: c.severity != "requirement")
    return lines + [[Verdict(c.verdict, _TONES[c.verdict]), " ", Code(c.name),
                     f" ({c.title}): {c.measured}"] for c in rest]


def _span(pair):
    return "\u2014" if pair is None else span_words(*pair)


def _box(box):
    return ("fails at x1, x1" if box is None
            else f"gain {span_words(box[0], box[1])}, tau {span_words(box[2], box[3])}")


def off_nominal_section(document, report):
    """Append the off-nominal requirements' section to ``document``.

    Parameters
    ----------
    document : Document
    report : VerificationReport
        Its figures carry ``off_nominal`` (:func:`.report.off_nominal`), its checks the
        verdicts (:func:`.requirement_checks.requirement_checks`).
    """
    results = report.figures.get("off_nominal")
    if not results:
        return
    grid = results["grid"]
    checks = {c.name: c for c in report.checks}
    section = document.section("Off-nominal requirements")
    section.paragraph(
        f"Each requirement on wheels with RobotPlant's DC gain x{min(grid['gain_factors']):g}.."
        f"x{max(grid['gain_factors']):g} and mechanical time constant "
        f"x{min(grid['time_constant_factors']):g}..x{max(grid['time_constant_factors']):g}, "
        "on the discrete-time loop (the real controller on the sampled wheel; the RobotPlant "
        "core for slip) and through the FMUs in our master (RobotPlant scaled + two "
        f"WheelController FMUs) on the judged wheels: {judged_words(grid)} "
        f"({len(results['judged'])} wheels). Every design is commissioned on each wheel first "
        "(its constants from a voltage step, orchestrator/verify/commissioning.py); the "
        "default form is also shown as shipped, told RobotPlant's constants. The verdict is on "
        "the judged wheels; the ranges say how far it holds on the whole grid "
        "(docs/verification.md).")
    section.bullets(design_lines(report.checks))
    for name in REQUIREMENTS:
        rows = []
        for design in results["model"]:
            check = checks.get(f"{name}_{design}")
            model_rows = results["model"][design][name]
            ranges = largest_ranges(model_rows, grid["gain_factors"],
                                    grid["time_constant_factors"])
            judged = [r for r in model_rows
                      if (r["gain_factor"], r["time_constant_factor"]) in
                      set(map(tuple, results["judged"]))]
            fmu = results["fmu"].get(design, {}).get(name)
            rows.append([DESIGN_LABELS[design],
                         Verdict(check.verdict, _TONES[check.verdict]) if check else None,
                         format_value(name, max(r["value"] for r in judged)),
                         format_value(name, max(r["value"] for r in fmu)) if fmu else
                         "not run", _span(ranges["gain_at_tau_1"]),
                         _span(ranges["tau_at_gain_1"]), _box(ranges["box"])])
        sub = document.section(checks[f"{name}_default"].title.rsplit(" (", 1)[0], level=3)
        sub.table(["design", "verdict", "worst on the judged wheels, loop", "same, FMUs",
                   "gain range at tau x1", "tau range at gain x1", "largest box"], rows)
        by = {design: {(r["gain_factor"], r["time_constant_factor"]): r for r in
                       results["model"][design][name]} for design in results["model"]}
        gains, taus = grid["gain_factors"], grid["time_constant_factors"]
        sub.table([Column("tau \\ gain")] + [Column(f"x{g:g}") for g in gains],
                  [[f"x{t:g}"] + [" | ".join(
                      f"{_SHORT[d]} {_cell(name, by[d][(g, t)])}" for d in by)
                      for g in gains] for t in taus],
                  caption="Loop values per wheel (d: default form, p: paper form, pid: CPID, each "
                          "commissioned; d0: default form told RobotPlant's constants; "
                          "! = does not hold)")


def _cell(name, row):
    return format_value(name, row["value"]).split(" ")[0] + ("" if row["passed"] else "!")
