"""The verification report as one document: the checks first, then the tables behind them.

:func:`verification_document` builds the :class:`~orchestrator.report.document.Document` that
:mod:`.report` renders to ``verification.md`` (figures linked) and ``verification.html``
(figures embedded); both texts come from this one description.
"""

import math
from pathlib import Path

from orchestrator.report.document import Code, Column, Document, Verdict

from .requirements_document import off_nominal_section, summary_findings

__all__ = ["EDGE_TIME_CONSTANTS", "LIMITS", "edge_rows", "edge_statements", "findings",
           "verification_document"]

# Columns of the largest-stable-gain-factor table (the figure has the finer grid).
EDGE_TIME_CONSTANTS = (0.5, 1.0, 2.0)
_NAMES = {"fgs_pd": "FGS-PD corner", "pd": "fixed PD", "pid": "PID"}
_TONES = {"pass": "pass", "FAIL": "fail", "warning": "warn"}

# What the linear model leaves out, said in every report.
LIMITS = [
    "Encoder quantisation (26 mm/s per count at 20 ms): in closed loop it makes a limit cycle "
    "of about one count, which a linear model cannot show (docs/control.md).",
    "Voltage saturation at +-v_supply, the anti-windup, and the fuzzy scheduling itself: each "
    "grid point is a frozen gain set; stability of every frozen gain does not prove stability "
    "of the scheduled (time-varying, nonlinear) loop, though with these margins a slow "
    "scheduling is very unlikely to destabilise it.",
    "Turning (each wheel then sees about 1.98 kg instead of 2.44 kg), slip, Coulomb friction, "
    "PWM.",
]


def _edge_at(gain_set, tau):
    return next((e for e in gain_set["edges"] if abs(e["time_constant_factor"] - tau) < 1e-9),
                None)


def edge_rows(edge_sets, taus=EDGE_TIME_CONSTANTS):
    """One row per frozen gain set: controller, kp, kd, ki, then per tau the largest stable
    plant-gain factor (None when unstable at x1, the search's end when not found) and the
    oscillation frequency [Hz] at the edge for tau x1."""
    rows = []
    for gain_set in edge_sets["sets"]:
        cells = []
        for tau in taus:
            e = _edge_at(gain_set, tau)
            cells.append(e["upper"] if e and e["nominal_stable"] else None)
        nominal = _edge_at(gain_set, 1.0)
        rows.append([_NAMES.get(gain_set["controller"], gain_set["controller"]),
                     gain_set["kp"], gain_set["kd"], gain_set["ki"], *cells,
                     nominal["crossing_hz"] if nominal else None])
    return rows


def edge_statements(edge_sets, taus=EDGE_TIME_CONSTANTS):
    """'stable up to xG plant gain at tau xT' for the weakest gain set of each controller."""
    lines = []
    for controller in dict.fromkeys(s["controller"] for s in edge_sets["sets"]):
        parts = []
        for tau in taus:
            candidates = [(e["upper"], s) for s in edge_sets["sets"]
                          if s["controller"] == controller
                          for e in [_edge_at(s, tau)] if e and e["nominal_stable"]]
            if candidates:
                upper, weakest = min(candidates, key=lambda c: c[0])
                parts.append(f"x{upper:.3g} plant gain at tau x{tau:g}"
                             + (f" (kp {weakest['kp']:g}, kd {weakest['kd']:g})"
                                if controller == "fgs_pd" else ""))
        lines.append(f"{_NAMES.get(controller, controller)}"
                     f"{'s (weakest corner)' if controller == 'fgs_pd' else ''}: stable up to "
                     + ", ".join(parts) + ".")
    return lines


def findings(report):
    """Every check that did not pass (failures first, then warnings)."""
    return sorted((c for c in report.checks if not c.passed),
                  key=lambda c: c.severity != "requirement")


def _verdict(check):
    return Verdict(check.verdict, _TONES[check.verdict])


def _grid(section, surface, value, spec, caption):
    """A kd x kp matrix of the gain surface: one row per kd, one column per kp."""
    by = {(g["kp"], g["kd"]): g for g in surface["grid"]}
    columns = [Column("kd \\ kp")] + [Column(f"{kp:.2f}", format=spec) for kp in surface["kps"]]
    rows = [[f"{kd:.2f}"] + [value(by[(kp, kd)]) for kp in surface["kps"]]
            for kd in surface["kds"]]
    section.table(columns, rows, caption=caption)


def _robustness_cell(point):
    if point["spectral_radius"] >= 1.0:
        return Verdict(f"unstable ({point['spectral_radius']:.4f})", "fail")
    return (f"{100 * point['steady_state_error']:.4g} % / {point['settling_time_s']:.2f} s "
            f"({point['spectral_radius']:.4f})")


def _robustness_table(section, name, points, gains, taus):
    by = {(p["gain_factor"], p["time_constant_factor"]): p for p in points}
    section.table([Column("tau factor \\ gain factor")] + [Column(f"x{g:g}") for g in gains],
                  [[f"x{tau:g}"] + [_robustness_cell(by[(g, tau)]) for g in gains]
                   for tau in taus], caption=name)


def _checks(document, report, strict):
    s = report.summary(strict)
    section = document.section("Checks")
    section.paragraph(f"{s['passed']} passed, {s['failed']} failed, {s['warnings']} warning(s) "
                      f"of {s['checks']} checks; exit status {s['exit_status']}"
                      + (" (strict: warnings count)." if strict else "."),
                      tone="pass" if s["exit_status"] == 0 else "fail")
    section.table(["check", "requirement", "measured", "verdict"],
                  [[c.name, c.requirement, c.measured, _verdict(c)] for c in report.checks],
                  collapsed=False)   # the answer: never folded
    section.paragraph(["Why each threshold is what it is: ",
                       Code("orchestrator/data/verification_requirements.toml"),
                       " (the justifications below)."])
    # the failures and findings a designer must read open the report (its summary)
    document.section("Why each threshold", level=3).table(
        ["check", "justification"], [[c.name, " ".join(c.why.split())] for c in report.checks])


def _stability(document, f, model):
    surface, m = f["surface"], f["model"]
    document.section("Model figures").paragraph(
        f"M_eff = {m['effective_mass_kg']:.4g} kg, K_f = {m['force_per_current_n_a']:.4g} N/A, "
        f"K_e = {m['emf_per_speed_v_s_m']:.4g} V s/m, B = {m['damping_n_s_m']:.4g} N s/m, "
        f"L = {m['inductance_h']:.3g} H, R = {m['resistance_ohm']:.3g} Ohm; time constants "
        f"{1000 * m['electrical_time_constant_s']:.3f} ms (electrical), "
        f"{m['mechanical_time_constant_s']:.4f} s (mechanical); DC gain "
        f"{m['dc_gain_m_s_per_v']:.6g} m/s per V.")
    section = document.section("Stability over the gain grid")
    section.paragraph(f"Each cell is a frozen gain set (integral trim ki = {surface['ki']:g} 1/s); "
                      "its largest closed-loop abs(z): stable when < 1, U marks unstable by "
                      "Routh.")
    _grid(section, surface, lambda g: f"{g['spectral_radius']:.4f}"
          + ("" if g["stable_routh"] else " U"), None, "Largest closed-loop abs(z)")
    section.table([Column("kd", "1", ".3g"), Column("ki", "1/s", "g"),
                   Column("kp edge, Routh", "1", ".6f"), Column("kp edge, roots", "1", ".6f"),
                   Column("relative difference", "1", ".1e")],
                  [[b["kd"], b["ki"], b["kp_routh"], b["kp_roots"], b["relative_difference"]]
                   for b in surface["boundaries"] + [f["pid"]["boundary"]]],
                  caption=f"Largest stable kp at fixed kd (T = {1000 * model.period:g} ms; Routh "
                          "on the w-plane vs numeric roots)")
    if f.get("jacobi_boundaries"):
        section.paragraph("With one more sample of delay (a Jacobi master) the kp edge is "
                          + ", ".join(f"{b['kp_routh']:.3f} at kd = {b['kd']:g}"
                                      for b in f["jacobi_boundaries"]) + ".")
    section = document.section("Margins and steps over the grid")
    for key, spec, caption in (("gain_margin", ".2f", "Gain margin (factor on the whole "
                                                      "controller)"),
                               ("phase_margin_deg", ".1f", "Phase margin [deg]"),
                               ("overshoot_pct", ".2f", "Overshoot [%]"),
                               ("settling_time_s", ".3f", "Settling time into +-5 % [s]")):
        _grid(section, surface, lambda g, key=key: g[key], spec, caption)
    section.paragraph(f"The analysis is linear: a reference step larger than "
                      f"{surface['summary']['linear_step_limit_min_m_s']:.3f} m/s from rest "
                      "saturates the voltage at some gain of the surface.")


def _robustness(document, f):
    section = document.section("Robustness to the plant")
    for sentence in f.get("robustness_statement", []):
        section.paragraph(" ".join(sentence.split()))
    section.paragraph("Largest stable plant-DC-gain factor of each frozen gain set (exact: Brent "
                      "on max abs(z) - 1, Routh on the w-plane to agree within 1e-9; no lower "
                      "edge down to x1/64):")
    section.bullets(edge_statements(f["gain_factor_edges"]))
    section.table(["gain set", Column("kp", "1", "g"), Column("kd", "1", "g"),
                   Column("ki", "1/s", "g")]
                  + [Column(f"largest gain factor, tau x{t:g}", "1", ".3f")
                     for t in EDGE_TIME_CONSTANTS]
                  + [Column("oscillation at the edge, tau x1", "Hz", ".2f")],
                  edge_rows(f["gain_factor_edges"]),
                  caption="Largest stable plant-DC-gain factor (\u2014: unstable at x1)")
    section.paragraph("Cell: steady-state error in % of the reference (final value theorem) / "
                      "settling time into +-5 % (largest abs(z)); unstable cells give abs(z).")
    r = f["robustness"]
    for name, points in list(r["points"].items()) + [("fgs_pd, the paper's pure PD",
                                                      f["robustness_pure_pd"])]:
        _robustness_table(section, name, points, r["gain_factors"], r["time_constant_factors"])


def verification_document(report, model, strict=False):
    """The :class:`~orchestrator.report.document.Document` of a verification report.

    Parameters
    ----------
    report : VerificationReport
        With its figures, checks and the captions and paths of its PNG figures.
    model : WheelLoopModel
    strict : bool
        Whether warnings count in the exit status (said in the summary).

    Returns
    -------
    Document
    """
    f = report.figures
    document = Document("Wheel-speed loop verification",
                        intro=["Generated by ", Code("sonotrack verify"), " (",
                               Code("orchestrator/verify/"), "); how to read it: ",
                               Code("docs/verification.md"), "."])
    s = report.summary(strict)
    document.summarize([("passed", s["passed"], "pass"), ("warnings", s["warnings"], "warn"),
                        ("failed", s["failed"], "fail")],
                       summary_findings(report) or ["Every check passed."])
    document.section("Sign convention and model").bullets(f["statement"])
    _checks(document, report, strict)
    off_nominal_section(document, report)
    figures = document.section("Figures")
    for name, caption in report.captions.items():
        figures.figure(Path(report.paths[name]).name, caption)
    _stability(document, f, model)
    _robustness(document, f)
    forms = document.section("The PD form")
    forms.paragraph("The paper form runs the PD of Eq. (46) with an integral trim "
                    "(docs/control.md). The incremental form, the same law read as a voltage "
                    "change per sample, would make kp an integral gain per sample; on this loop "
                    "it gives:")
    forms.table([Column("kp", "1", "g"), Column("kd", "1", "g"),
                 Column("largest abs(z)", "1", ".4f"), Column("dominant pole", "Hz", ".2f"),
                 Column("damping ratio", "1", ".3f")],
                [[x["kp"], x["kd"], x["spectral_radius"], x["frequency_hz"], x["damping_ratio"]]
                 for x in f["pd_forms"]["incremental"]],
                caption="Incremental form on the sampled loop")
    limits = document.section("Not in this model (honest limits)")
    limits.bullets(LIMITS)
    limits.paragraph(f"Wall time: {f.get('wall_time_s', math.nan):.1f} s.")
    return document
