"""``verification.md``: the checks first, then the tables behind them; figures linked relatively."""

import math
from pathlib import Path

__all__ = ["markdown_report", "fmt", "LIMITS", "edge_rows", "edge_statements", "findings",
           "EDGE_TIME_CONSTANTS"]

# Columns of the largest-stable-gain-factor table (the figure has the finer grid).
EDGE_TIME_CONSTANTS = (0.5, 1.0, 2.0)
_NAMES = {"fgs_pd": "FGS-PD corner", "pd": "fixed PD", "pid": "PID"}

# What the linear model leaves out, said in every report (Markdown and HTML).
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


def fmt(value, spec=".3g"):
    """Format a number; None as '-', non-finite as inf / nan."""
    if value is None:
        return "-"
    if isinstance(value, str):
        return value
    if isinstance(value, float) and not math.isfinite(value):
        return "inf" if value > 0 else ("nan" if math.isnan(value) else "-inf")
    return format(value, spec)


def _grid_table(surface, key, spec):
    by = {(g["kp"], g["kd"]): g for g in surface["grid"]}
    rows = ["| kd \\ kp | " + " | ".join(f"{kp:.2f}" for kp in surface["kps"]) + " |",
            "|---" * (len(surface["kps"]) + 1) + "|"]
    for kd in surface["kds"]:
        cells = [key(by[(kp, kd)]) if callable(key) else fmt(by[(kp, kd)][key], spec)
                 for kp in surface["kps"]]
        rows.append(f"| {kd:.2f} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def _robustness_table(points, gains, taus):
    by = {(p["gain_factor"], p["time_constant_factor"]): p for p in points}
    rows = ["| tau factor \\ gain factor | " + " | ".join(f"x{g:g}" for g in gains) + " |",
            "|---" * (len(gains) + 1) + "|"]
    for tau in taus:
        cells = []
        for g in gains:
            p = by[(g, tau)]
            cells.append(f"**unstable** ({p['spectral_radius']:.3f})"
                         if p["spectral_radius"] >= 1.0 else
                         f"{100 * p['steady_state_error']:.2f} % / {p['settling_time_s']:.2f} s "
                         f"({p['spectral_radius']:.4f})")
        rows.append(f"| x{tau:g} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


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


def _escape(text):
    return str(text).replace("|", "\\|")


def markdown_report(report, strict=False):
    """The Markdown text of a :class:`.report.VerificationReport`."""
    f, s = report.figures, report.summary(strict)
    surface, m = f["surface"], f["model"]
    lines = ["# Wheel-speed loop verification", "",
             "Generated by `sonotrack verify` (`orchestrator/verify/`); how to read it: "
             "`docs/verification.md`. Self-contained version with the figures embedded: "
             "[verification.html](verification.html).", ""]
    lines += [f"- {text}" for text in f["statement"]]
    lines += ["", "## Checks", "",
              f"{s['passed']} passed, {s['failed']} failed, {s['warnings']} warning(s) of "
              f"{s['checks']} checks; exit status {s['exit_status']}"
              + (" (strict: warnings count)." if strict else "."), "",
              "| check | requirement | measured | verdict |", "|---|---|---|---|"]
    lines += [f"| {c.name} | {_escape(c.requirement)} | {_escape(c.measured)} | "
              f"**{c.verdict}** |" for c in report.checks]
    lines += ["", "Why each threshold is what it is: "
              "`orchestrator/data/verification_requirements.toml`.", ""]
    bad = findings(report)
    if bad:
        lines += ["### Failures and findings a designer must read", ""]
        lines += [f"- **{c.verdict}** `{c.name}` ({c.title}): {c.measured}" for c in bad]
        lines += [""]
    lines += ["## Figures", ""]
    for name, caption in report.captions.items():
        lines += [f"![{caption}]({Path(report.paths[name]).name})", "", f"*{caption}*", ""]
    lines += [
        "## Model figures", "",
        f"M_eff = {m['effective_mass_kg']:.4g} kg, K_f = {m['force_per_current_n_a']:.4g} N/A, "
        f"K_e = {m['emf_per_speed_v_s_m']:.4g} V s/m, B = {m['damping_n_s_m']:.4g} N s/m, "
        f"L = {m['inductance_h']:.3g} H, R = {m['resistance_ohm']:.3g} Ohm; time constants "
        f"{1000 * m['electrical_time_constant_s']:.3f} ms (electrical), "
        f"{m['mechanical_time_constant_s']:.4f} s (mechanical); DC gain "
        f"{m['dc_gain_m_s_per_v']:.6g} m/s per V.", "",
        "## Stability over the gain grid", "",
        "Cell: largest closed-loop |z| (stable when < 1; `U` marks unstable by Routh).", "",
        _grid_table(surface, lambda g: fmt(g["spectral_radius"], ".3f")
                    + ("" if g["stable_routh"] else " U"), None), "",
        "Largest stable kp at fixed kd (Routh on the w-plane vs numeric roots):", "",
        "| kd | ki [1/s] | kp edge (Routh) | kp edge (roots) | relative difference |",
        "|---|---|---|---|---|",
    ]
    for b in surface["boundaries"] + [f["pid"]["boundary"]]:
        lines.append(f"| {b['kd']:.3g} | {b['ki']:g} | {fmt(b['kp_routh'], '.6f')} | "
                     f"{fmt(b['kp_roots'], '.6f')} | {fmt(b['relative_difference'], '.1e')} |")
    if f.get("jacobi_boundaries"):
        lines += ["", "With one more sample of delay (a Jacobi master) the kp edge is " + ", ".join(
            f"{fmt(b['kp_routh'], '.3f')} at kd = {b['kd']:g}" for b in f["jacobi_boundaries"])
            + "."]
    lines += ["", "## Margins and steps over the grid", "",
              "Gain margin (factor on the whole controller):", "",
              _grid_table(surface, "gain_margin", ".2f"), "", "Phase margin [deg]:", "",
              _grid_table(surface, "phase_margin_deg", ".1f"), "", "Overshoot [%]:", "",
              _grid_table(surface, "overshoot_pct", ".2f"), "",
              "Settling time into +-5 % [s]:", "", _grid_table(surface, "settling_time_s", ".3f"),
              "", f"The analysis is linear: a reference step larger than "
              f"{surface['summary']['linear_step_limit_min_m_s']:.3f} m/s from rest saturates "
              "the voltage at some gain of the surface.", ""]
    r = f["robustness"]
    lines += ["## Robustness to the plant", ""]
    for sentence in f.get("robustness_statement", []):
        lines += [" ".join(sentence.split()), ""]
    lines += ["Largest stable plant-DC-gain factor of each frozen gain set (exact: Brent on "
              "max abs(z) - 1, Routh on the w-plane to agree within 1e-9; no lower edge down "
              "to x1/64):", ""]
    lines += [f"- {x}" for x in edge_statements(f["gain_factor_edges"])] + [""]
    lines += ["| gain set | kp | kd | ki [1/s] | "
              + " | ".join(f"largest gain factor, tau x{t:g}" for t in EDGE_TIME_CONSTANTS)
              + " | oscillation at the edge, tau x1 [Hz] |",
              "|---" * (5 + len(EDGE_TIME_CONSTANTS)) + "|"]
    lines += ["| " + " | ".join([row[0], fmt(row[1], "g"), fmt(row[2], "g"), fmt(row[3], "g")]
                                + [fmt(v, ".3f") for v in row[4:-1]] + [fmt(row[-1], ".2f")])
              + " |" for row in edge_rows(f["gain_factor_edges"])]
    lines += ["", "Cell: steady-state error (final value theorem) / settling time into +-5 % "
              "(largest abs(z)); unstable cells give abs(z).", ""]
    for name, points in list(r["points"].items()) + [("fgs_pd, pure PD (trim off)",
                                                      f["robustness_pure_pd"])]:
        lines += [f"**{name}**", "", _robustness_table(points, r["gain_factors"],
                                                       r["time_constant_factors"]), ""]
    lines += ["## The PD form", "",
              "The controller runs the PD of Eq. (46) with an integral trim (docs/control.md). "
              "The incremental form, the same law read as a voltage change per sample, would "
              "make kp an integral gain per sample; on this loop it gives:", "",
              "| kp | kd | largest abs(z) | dominant pole [Hz] | damping ratio |",
              "|---|---|---|---|---|"]
    lines += [f"| {x['kp']:g} | {x['kd']:g} | {x['spectral_radius']:.4f} | "
              f"{x['frequency_hz']:.2f} | {x['damping_ratio']:.3f} |"
              for x in f["pd_forms"]["incremental"]]
    lines += ["", "## Not in this model (honest limits)", ""] + [f"- {x}" for x in LIMITS]
    lines += ["", f"Wall time: {f.get('wall_time_s', math.nan):.1f} s."]
    return "\n".join(lines) + "\n"
