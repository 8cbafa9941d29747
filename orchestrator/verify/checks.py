"""Verdicts: each check states its requirement (from a data file), the measured value and passed.

The thresholds and their justification live in
``orchestrator/data/verification_requirements.toml`` (:func:`load_requirements`); each
``check_*`` function takes the figures :mod:`.measure` and :mod:`.fmu_runs` produced and one
requirement table, and returns a :class:`Check` (the plant-robustness checks are in
:mod:`.robust_checks`). A requirement that fails is a failure; a
*finding* (a claim of the paper judged, severity "finding") that does not hold is a warning.
:func:`exit_status` counts failures (and warnings with ``strict``).
"""

import math
import tomllib
from dataclasses import asdict, dataclass, field
from pathlib import Path

from components.common.errors import ConfigError

__all__ = ["Check", "load_requirements", "exit_status", "REQUIREMENTS_PATH",
           "check_routh_vs_roots", "check_surface_stable", "check_gain_margin",
           "check_phase_margin", "check_step_response", "check_pid_baseline", "check_dc_gain",
           "check_controller_core_vs_tf", "check_plant_fmu_vs_tf", "check_controller_fmu_vs_law",
           "check_closed_loop_fmus_vs_tf", "check_paper_gain_box",
           "check_routh_gives_paper_bounds", "check_fgs_pd_overshoot_vs_pid"]

REQUIREMENTS_PATH = Path(__file__).resolve().parent.parent / "data" / \
    "verification_requirements.toml"
_SEVERITIES = ("requirement", "finding")


@dataclass
class Check:
    """One verdict.

    Attributes
    ----------
    name : str
        Key in the requirements file (plus a suffix for per-controller checks).
    title : str
    requirement : str
        The requirement with its threshold, in words.
    measured : str
        The measured value, in words, with units.
    passed : bool
    severity : {"requirement", "finding"}
    values : dict
        The measured numbers.
    why : str
        The threshold's justification (from the requirements file).
    """

    name: str
    title: str
    requirement: str
    measured: str
    passed: bool
    severity: str = "requirement"
    values: dict = field(default_factory=dict)
    why: str = ""

    @property
    def verdict(self):
        """``pass``, ``FAIL`` (a requirement) or ``warning`` (a finding that does not hold)."""
        if self.passed:
            return "pass"
        return "FAIL" if self.severity == "requirement" else "warning"

    def to_dict(self):
        """Plain dict, with the verdict."""
        return dict(asdict(self), verdict=self.verdict)


def load_requirements(path=None):
    """Read the requirements file; every table needs ``title`` and ``why``.

    Parameters
    ----------
    path : path-like, optional
        Default :data:`REQUIREMENTS_PATH`.

    Returns
    -------
    dict
        Check name -> its table.

    Raises
    ------
    ConfigError
        Naming the file and the table when the file is unreadable or a table is incomplete.
    """
    path = Path(path or REQUIREMENTS_PATH)
    try:
        tables = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"{path}: cannot read the verification requirements: {exc}") from exc
    problems = []
    for name, table in tables.items():
        for key in ("title", "why"):
            if not isinstance(table.get(key), str):
                problems.append(f"[{name}] needs a text '{key}'")
        if table.get("severity", "requirement") not in _SEVERITIES:
            problems.append(f"[{name}] severity = {table.get('severity')!r}; valid: "
                            f"{', '.join(_SEVERITIES)}")
    if problems:
        raise ConfigError(f"{path}: " + "; ".join(problems))
    return tables


def exit_status(checks, strict=False):
    """Number of failed checks; with ``strict`` warnings count as failures too."""
    return sum(1 for c in checks if not c.passed and (strict or c.severity == "requirement"))


def _check(name, req, requirement, measured, passed, values, suffix=""):
    return Check(name=name + suffix, title=req["title"] + (f" ({suffix[1:]})" if suffix else ""),
                 requirement=requirement, measured=measured, passed=bool(passed),
                 severity=req.get("severity", "requirement"), values=values, why=req["why"])


def _finite_max(values):
    finite = [v for v in values if v is not None and math.isfinite(v)]
    return max(finite) if finite else math.nan


# ----- the linear loop over the surface -------------------------------------------------------
def check_routh_vs_roots(surface, req):
    """Routh and roots classify every grid point alike; their kp edges agree."""
    grid = surface["grid"]
    mismatches = sum(1 for g in grid if g["stable_routh"] != g["stable_roots"])
    rel = _finite_max(b["relative_difference"] for b in surface["boundaries"])
    limit = req["max_edge_relative_difference"]
    passed = mismatches <= req["max_mismatches"] and rel <= limit
    return _check("routh_vs_roots", req,
                  f"mismatches <= {req['max_mismatches']} over the grid; kp edges agree to "
                  f"<= {limit:g} relative",
                  f"{mismatches} mismatches in {len(grid)} points; largest edge difference "
                  f"{rel:.1e}", passed,
                  {"mismatches": mismatches, "points": len(grid),
                   "edge_max_relative_difference": rel})


def check_surface_stable(distances, req):
    """Every reachable gain set stable, and its kp edge at least ``min_edge_ratio`` x kp."""
    worst = distances["worst"]
    passed = distances["unstable"] == 0 and distances["min_edge_ratio"] >= req["min_edge_ratio"]
    return _check("surface_stable", req,
                  f"all reachable (kp, kd) stable; kp edge / kp >= {req['min_edge_ratio']:g}",
                  f"{distances['unstable']} of {distances['count']} reachable gain sets "
                  f"unstable; smallest kp edge / kp = {distances['min_edge_ratio']:.2f} at kp "
                  f"{worst['kp']:.3f}, kd {worst['kd']:.3f} (edge {worst['kp_edge']:.2f})",
                  passed, {k: distances[k] for k in ("count", "unstable", "min_edge_ratio",
                                                     "worst")})


def check_gain_margin(surface, req):
    """Smallest gain margin over the surface grid."""
    value = surface["summary"]["gain_margin_min"]
    limit = req["min_gain_margin"]
    return _check("gain_margin", req,
                  f"gain margin >= {limit:g} ({20 * math.log10(limit):.1f} dB) at every grid point",
                  f"smallest {value:.2f} ({20 * math.log10(value):.1f} dB)" if value > 0
                  else f"smallest {value:.3g}", value >= limit, {"gain_margin_min": value})


def check_phase_margin(surface, req):
    """Smallest phase margin over the surface grid."""
    value = surface["summary"]["phase_margin_min_deg"]
    limit = req["min_phase_margin_deg"]
    passed = math.isfinite(value) and value >= limit
    return _check("phase_margin", req, f"phase margin >= {limit:g} deg at every grid point",
                  f"smallest {value:.1f} deg", passed, {"phase_margin_min_deg": value})


def _step_verdict(overshoot, settling, req):
    ok = (math.isfinite(overshoot) and overshoot <= req["max_overshoot_pct"]
          and math.isfinite(settling) and settling <= req["max_settling_time_s"])
    return ok


def check_step_response(surface, req):
    """Largest overshoot and settling time over the (stable) surface grid."""
    s = surface["summary"]
    unstable = sum(1 for g in surface["grid"] if not g["stable_roots"])
    overshoot, settling = s["overshoot_max_pct"], s["settling_max_s"]
    passed = unstable == 0 and _step_verdict(overshoot, settling, req)
    return _check("step_response", req,
                  f"overshoot <= {req['max_overshoot_pct']:g} %, settling into +-5 % <= "
                  f"{req['max_settling_time_s']:g} s at every grid point",
                  f"overshoot <= {overshoot:.2f} %, settling <= {settling:.3f} s"
                  + (f"; {unstable} grid points unstable" if unstable else ""), passed,
                  {"overshoot_max_pct": overshoot, "settling_max_s": settling,
                   "unstable": unstable})


def check_pid_baseline(pid, req, margins, step):
    """The PID against the surface's requirements (margins, overshoot, settling)."""
    gm_min, pm_min = margins
    stable = pid["stable_roots"] and pid["stable_routh"]
    passed = (stable and pid["gain_margin"] >= gm_min["min_gain_margin"]
              and pid["phase_margin_deg"] >= pm_min["min_phase_margin_deg"]
              and _step_verdict(pid["overshoot_pct"], pid["settling_time_s"], step))
    return _check("pid_baseline", req,
                  f"stable, gain margin >= {gm_min['min_gain_margin']:g}, phase margin >= "
                  f"{pm_min['min_phase_margin_deg']:g} deg, overshoot <= "
                  f"{step['max_overshoot_pct']:g} %, settling <= {step['max_settling_time_s']:g} s",
                  f"kp {pid['kp']:g}, ki {pid['ki']:g} 1/s, kd {pid['kd']:g}: "
                  f"{'stable' if stable else 'UNSTABLE'} (max|z| {pid['spectral_radius']:.4f}), "
                  f"gain margin {pid['gain_margin']:.2f}, phase margin "
                  f"{pid['phase_margin_deg']:.1f} deg, overshoot {pid['overshoot_pct']:.2f} %, "
                  f"settling {pid['settling_time_s']:.3f} s", passed,
                  {k: pid[k] for k in ("kp", "ki", "kd", "spectral_radius", "gain_margin",
                                       "phase_margin_deg", "overshoot_pct", "settling_time_s")})


def check_dc_gain(model_figures, req):
    """The linear model's DC gain against the plant core's analytic steady state."""
    model_gain = model_figures["dc_gain_m_s_per_v"]
    analytic = model_figures["dc_gain_analytic_m_s_per_v"]
    rel = abs(model_gain - analytic) / abs(analytic)
    return _check("dc_gain", req, f"relative difference <= {req['max_relative_difference']:g}",
                  f"{model_gain:.9g} vs {analytic:.9g} m/s per V: {rel:.1e}",
                  rel <= req["max_relative_difference"], {"relative_difference": rel})


def check_controller_core_vs_tf(cross, req):
    """The real controller core on the sampled plant against the closed-loop TF."""
    worst = max(cross["pd_mid"], cross["pid"])
    limit = req["max_difference_m_s"]
    return _check("controller_core_vs_tf", req,
                  f"max |core - TF| <= {limit:g} m/s ({cross['step_m_s']:g} m/s step)",
                  f"{cross['pd_mid']:.1e} m/s (FGS-PD middle, as configured), "
                  f"{cross['pid']:.1e} m/s (PID)", worst <= limit,
                  {"pd_mid_m_s": cross["pd_mid"], "pid_m_s": cross["pid"]})


# ----- the FMUs -------------------------------------------------------------------------------
def check_plant_fmu_vs_tf(fmu_step, bound_m_s, req):
    """The default-parameter run of the plant FMU against u/V (compliance bound, t63)."""
    run = fmu_step["runs"][0]
    t63 = abs(run["fmu_t63_s"] - fmu_step["tf_t63_s"]) / fmu_step["tf_t63_s"]
    limit = req["max_t63_relative_difference"]
    passed = run["max_abs_difference_m_s"] <= bound_m_s and t63 <= limit
    return _check("plant_fmu_vs_tf", req,
                  f"max |FMU - TF| <= tyre-compliance bound {1000 * bound_m_s:.2f} mm/s; "
                  f"t63 within {100 * limit:g} %",
                  f"max {1000 * run['max_abs_difference_m_s']:.3f} mm/s; t63 "
                  f"{run['fmu_t63_s']:.4f} s vs {fmu_step['tf_t63_s']:.4f} s "
                  f"({100 * t63:.2f} %)", passed,
                  {"max_abs_difference_m_s": run["max_abs_difference_m_s"],
                   "bound_m_s": bound_m_s, "t63_relative_difference": t63,
                   "fmu_overrides": run.get("fmu_overrides", {})})


def check_controller_fmu_vs_law(comparison, req):
    """The WheelController FMU against the recomputed law, every mode."""
    runs = comparison["runs"]
    worst = max(r["max_voltage_difference_v"] for r in runs.values())
    gains = max(r["max_gain_difference"] for r in runs.values())
    limit = req["max_difference_v"]
    outside = {m: r["outside_universe"] for m, r in runs.items()}
    some = next(iter(runs.values()))
    return _check("controller_fmu_vs_law", req,
                  f"max |V_FMU - V_law| <= {limit:g} V in every mode, inputs inside and "
                  "outside the fuzzy universe",
                  f"max {worst:.2e} V (gains {gains:.1e}) over modes {', '.join(runs)}; "
                  f"{some['outside_universe']} of {some['samples']} samples outside the "
                  f"universe, {some['saturated']} saturated", worst <= limit and gains <= limit,
                  {"max_voltage_difference_v": worst, "max_gain_difference": gains,
                   "outside_universe": outside})


def check_closed_loop_fmus_vs_tf(loop, req):
    """Both FMUs in our master against the closed-loop TF at several gain points."""
    limit = req["max_difference_fraction_of_step"]
    worst = max(p["max_difference_fraction_of_step"] for p in loop["points"])
    where = ", ".join(f"{p['mode']} ({p['kp']:g}, {p['kd']:g}, {p['ki']:g}): "
                      f"{100 * p['max_difference_fraction_of_step']:.2f} %"
                      for p in loop["points"])
    return _check("closed_loop_fmus_vs_tf", req,
                  f"max |rim_FMU - TF| <= {100 * limit:g} % of the {loop['step_m_s']:g} m/s "
                  + ("step" if loop.get("ramp_m_s2") is None else
                     f"reached at {loop['ramp_m_s2']:g} m/s^2") + " at every gain point",
                  where, worst <= limit,
                  {"worst_fraction_of_step": worst,
                   "points": [{k: p[k] for k in ("mode", "kp", "kd", "ki",
                                                 "max_difference_fraction_of_step")}
                              for p in loop["points"]]})


# ----- the paper -------------------------------------------------------------------------------
def check_paper_gain_box(box, req):
    """The mapped paper box: all stable, kp edge at least ``min_edge_ratio`` x kp."""
    b, worst = box["box"], box["worst"]
    passed = box["unstable"] == 0 and box["min_edge_ratio"] >= req["min_edge_ratio"]
    return _check("paper_gain_box", req,
                  f"kp in [{b['kp_min']:g}, {b['kp_max']:g}], kd in [{b['kd_min']:g}, "
                  f"{b['kd_max']:g}] all stable with kp edge / kp >= {req['min_edge_ratio']:g}",
                  f"{box['unstable']} of {box['count']} points unstable; smallest kp edge / kp "
                  f"{box['min_edge_ratio']:.2f} at ({worst['kp']:.3g}, {worst['kd']:.3g}); "
                  + _literal_signs(box['literal_signs_spectral_radius']), passed,
                  {k: box[k] for k in ("box", "count", "unstable", "min_edge_ratio",
                                       "literal_signs_spectral_radius")})


def _literal_signs(radius):
    """The paper's printed signs read literally: why the box is judged with them mapped."""
    verdict = ("unstable: positive feedback, which is why the box is judged with the signs "
               "mapped (docs/errata.md)" if radius > 1 else "stable even so")
    return (f"read with the paper's printed (negative) signs on e = r - y, max|z| = "
            f"{radius:.3f}: {verdict}")


def check_routh_gives_paper_bounds(finding, settings, req):
    """Is any end of the paper's box a Routh-Hurwitz bound (continuous or sampled)?"""
    tol = req["relative_tolerance"]
    ends = {"kp_min": settings["kp_min"], "kp_max": settings["kp_max"],
            "kd_min": settings["kd_min"], "kd_max": settings["kd_max"]}
    bounds = []
    for kind, key in (("continuous", "continuous_kp"), ("sampled", "sampled_kp")):
        for entry in finding[key]:
            bounds += [(kind, "kp", v) for lo, hi in entry["intervals"] for v in (lo, hi)
                       if abs(v) < finding["limit"]]
    for entry in finding["sampled_kd"]:
        bounds += [("sampled", "kd", v) for lo, hi in entry["intervals"] for v in (lo, hi)
                   if abs(v) < finding["limit"]]
    matched = sorted({name for name, end in ends.items() for _, gain, v in bounds
                      if gain == name[:2] and abs(abs(v) - end) <= tol * end})
    cont = "; ".join(f"kd {e['kd']:g}: kp in " + ", ".join(
        f"({lo:.3g}, {'inf' if hi >= finding['limit'] else format(hi, '.3g')})"
        for lo, hi in e["intervals"]) for e in finding["continuous_kp"])
    samp = "; ".join(f"kd {e['kd']:g}: kp in " + ", ".join(
        f"({lo:.4g}, {hi:.4g})" for lo, hi in e["intervals"]) for e in finding["sampled_kp"])
    samp_kd = "; ".join(f"kp {e['kp']:g}: kd in " + ", ".join(
        f"({lo:.4g}, {hi:.4g})" for lo, hi in e["intervals"]) for e in finding["sampled_kd"])
    unbounded = all(hi >= finding["limit"] for e in finding["continuous_kp"]
                    for _, hi in e["intervals"][-1:])
    return _check("routh_gives_paper_bounds", req,
                  f"each end of the box (kp {ends['kp_min']:g}..{ends['kp_max']:g}, kd "
                  f"{ends['kd_min']:g}..{ends['kd_max']:g}) within {100 * tol:g} % of a "
                  "Routh bound",
                  f"continuous PD (e = r - y): {cont}"
                  + (" (no finite upper bound)" if unbounded else "")
                  + f"; sampled: {samp}; {samp_kd}. Ends that are Routh bounds: "
                  f"{', '.join(matched) or 'none'}",
                  len(matched) == len(ends), {"matched_ends": matched, "bounds": bounds})


def check_fgs_pd_overshoot_vs_pid(case1, linear_overshoot_pct, req):
    """The paper's claim that the FGS-PD overshoots less than the CPID, on its Case 1 run.

    Judged on the paper's form (the claim is the paper's); the default form and the paper's
    pure PD are shown beside it. ``linear_overshoot_pct`` is the largest overshoot of the
    linear loop over the surface (frozen gains), quoted to show where the nonlinear run's
    overshoot does not come from.
    """
    r = case1["results"]
    sides = ("left", "right")

    def pct(name):
        values = [r[name][s]["overshoot_percent"] for s in sides]
        return [math.nan if v is None else float(v) for v in values]

    paper, pure, pid = pct("fgs_pd_paper"), pct("fgs_pd_pure"), pct("pid")
    configured = pct("fgs_pd")
    passed = all(f <= p for f, p in zip(paper, pid))
    measured = (f"FGS-PD in the paper's form overshoots {paper[0]:.2f} / {paper[1]:.2f} % "
                f"against {pid[0]:.2f} / {pid[1]:.2f} % for the CPID (left / right wheel; Case 1 "
                f"on the RobotPlant core with its encoder, {1000 * case1['period_s']:g} ms); as "
                f"the pure PD of Eq. (46) {pure[0]:.2f} / {pure[1]:.2f} %; in the "
                f"{case1.get('form', 'default')} form as configured {configured[0]:.2f} / "
                f"{configured[1]:.2f} %. ")
    if passed:
        measured += "The claim holds in our simulation."
    else:
        measured += ("Our simulation does not support the paper's claim: the overshoot is the "
                     "encoder's one-count limit cycle and the trim's ramp integral, not the "
                     "gains' damping (the linear loop of the analysed form overshoots at most "
                     f"{linear_overshoot_pct:.2f} % with frozen gains).")
    return _check("fgs_pd_overshoot_vs_pid", req,
                  "FGS-PD (paper form) overshoot <= CPID overshoot on both wheels of Case 1",
                  measured, passed, {"fgs_pd_paper_pct": paper, "fgs_pd_pure_pct": pure,
                                     "fgs_pd_pct": configured, "pid_pct": pid})
