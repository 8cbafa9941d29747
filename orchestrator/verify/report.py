"""`sonotrack verify`: measure, judge, write ``verification.json``, ``.md`` and ``.html``.

:func:`verify` is the library entry point the CLI calls: it builds the sampled loop model,
runs the analyses (:mod:`.measure`), the FMU comparisons (:mod:`.fmu_runs`), the checks
(:mod:`.checks`, thresholds from the requirements file), draws the figures and writes the
three reports. Its :class:`VerificationReport` carries the checks; :meth:`exit_status` is the
number of failed checks (the CLI's exit status).
"""

import math
import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

from components.common.errors import ConfigError
from components.control.controller import DEFAULTS as CONTROLLER_DEFAULTS
from components.plant.motor import steady_wheel_speed
from components.plant.parameters import PlantParameters
from orchestrator.files.atomic import atomic_write_text
from orchestrator.files.json_policy import dumps
from orchestrator.report.html import write_html
from orchestrator.report.markdown import write_markdown

from . import checks as C
from . import robust_checks as R
from . import measure
from .designs import (OFF_NOMINAL_DESIGNS, UNCOMMISSIONED, design_settings,
                      integral_gain)
from .fmu_requirements import fmu_requirements
from .requirement_checks import design_lines, requirement_checks
from .requirement_runs import measure_requirements
from .wheel_experiments import judged_cells
from .fmu_runs import (
    built_fmu, closed_loop_fmu_comparison, compliance_bound, controller_fmu_comparison,
    fmu_step_comparison, fmu_variants,
)
from .loop_model import WheelLoopModel

__all__ = ["VerificationReport", "verify", "DEFAULT_OUT_DIR", "model_statement",
           "robustness_grid", "off_nominal"]

DEFAULT_OUT_DIR = "runs/verify"


@dataclass
class VerificationReport:
    """Everything :func:`verify` measured, its checks, and where it wrote them.

    Attributes
    ----------
    figures : dict
        JSON-ready figures (model, surface, robustness, FMU comparisons, ...).
    checks : list of Check
    paths : dict
        Name -> path of each written file.
    captions : dict
        Figure name -> caption.
    """

    figures: dict
    checks: list = field(default_factory=list)
    paths: dict = field(default_factory=dict)
    captions: dict = field(default_factory=dict)

    def exit_status(self, strict=False):
        """Number of failed checks (with ``strict``, warnings count too)."""
        return C.exit_status(self.checks, strict)

    def summary(self, strict=False):
        """Counts of passed, failed and warning checks, and the exit status."""
        return {"checks": len(self.checks),
                "passed": sum(1 for c in self.checks if c.passed),
                "failed": sum(1 for c in self.checks if c.verdict == "FAIL"),
                "warnings": sum(1 for c in self.checks if c.verdict == "warning"),
                "strict": bool(strict), "exit_status": self.exit_status(strict)}

    def to_json(self, strict=False, indent=1):
        """``{"summary", "checks", "figures"}`` as JSON (NaN and inf written as null)."""
        return dumps({"summary": self.summary(strict),
                      "checks": [c.to_dict() for c in self.checks],
                      "figures": self.figures}, indent=indent)

    def summary_lines(self):
        """Which design meets which off-nominal requirement, one console line per check,
        then the counts."""
        lines = design_lines(self.checks)
        lines += [f"{c.verdict:7s} {c.name}: {c.measured}" for c in self.checks]
        s = self.summary()
        lines.append(f"{s['passed']} passed, {s['failed']} failed, {s['warnings']} warning(s) "
                     f"of {s['checks']} checks")
        return lines


def model_statement(model, settings):
    """Sign convention, model and controller form in a few sentences (top of every report)."""
    if settings.get("form", "default") == "default":
        form = (f"the default form (docs/control.md): voltage = g d + g s (kp e + kd T_d de) + "
                f"g k_i integral(e) with s = {settings['gain_scale']:g}, T_d = "
                f"{settings['derivative_time']:g} s, k_i = {settings['integral_gain']:g} 1/s, "
                f"d the drive of a nominal wheel (tau_a = "
                f"{settings['acceleration_feedforward']:g} s) to the reference in one period, "
                "e measured against that wheel's window average, the integral emptied at a "
                "zero reference")
    else:
        form = ("the paper form: " + (f"integral trim ki = {settings['trim_ki']:g} 1/s on "
                                      "e/e_range" if settings["trim_ki"] > 0
                                      else "pure PD (no integral trim)"))
    return [
        "Sign convention: e = v_ref - v_meas (positive when the wheel is too slow), every "
        "gain positive. The paper writes its error as y - r, so its Kp in [-4, -3], Kd in "
        "[-2, -0.3] are kp in [3, 4], kd in [0.3, 2] here ('max' = larger magnitude).",
        f"Model: one wheel driving straight without slip (docs/plant.md), zero-order hold "
        f"over the loop period T = {1000 * model.period:g} ms, measured speed = exact average "
        f"of the rim speed over the encoder window (speed_window = "
        f"{1000 * model.plant.speed_window:g} ms; one sample late), no encoder quantisation, "
        f"no voltage limit; {model.extra_delay} extra sample(s) of master delay "
        "(0: our Gauss-Seidel master, controllers stepped before the plant).",
        f"Controller: voltage = g v_ref [feedforward {'on' if settings['feedforward'] else 'off'}]"
        f" + g e_range (kp e/e_range + kd de/de_range + ki integral), g = "
        f"{settings['volts_per_speed']:.4f} V s/m, e_range = {settings['e_range']:g} m/s, "
        f"de_range = {settings['de_range']:g} m/s^2, derivative filter "
        f"{settings['derivative_time_constant']:g} s. FGS-PD and PD: {form}; PID (the "
        f"paper's CPID in both forms): ki = {settings['pid_ki']:g} 1/s. Each gain set is "
        "analysed frozen (linear time-invariant).",
    ]


def _settings(controller_parameters):
    unknown = sorted(set(controller_parameters or {}) - set(CONTROLLER_DEFAULTS))
    if unknown:
        raise ConfigError(f"verify: unknown controller parameters {unknown}; valid: "
                          f"{sorted(CONTROLLER_DEFAULTS)}")
    return dict(CONTROLLER_DEFAULTS, **(controller_parameters or {}))


def _model_figures(model, plant):
    linear = model.linear
    electrical, mechanical = linear.time_constants
    return {
        "period_s": model.period, "extra_delay_samples": int(model.extra_delay),
        "speed_window_s": plant.speed_window,
        "effective_mass_kg": linear.effective_mass,
        "force_per_current_n_a": linear.force_per_current,
        "emf_per_speed_v_s_m": linear.emf_per_speed, "damping_n_s_m": linear.damping,
        "inductance_h": linear.inductance, "resistance_ohm": linear.resistance,
        "electrical_time_constant_s": electrical, "mechanical_time_constant_s": mechanical,
        "dc_gain_m_s_per_v": linear.dc_gain,
        "dc_gain_analytic_m_s_per_v": steady_wheel_speed(1.0, plant) * plant.wheel_radius,
        "measured_tf": {"num": model.meas_num.tolist(), "den": model.meas_den.tolist()},
        "rim_tf": {"num": model.rim_num.tolist(), "den": model.rim_den.tolist()},
    }


def robustness_grid(req):
    """The plant grid evaluated: every factor the requirement and the x4 finding name.

    Returns
    -------
    (list of float, list of float)
        Gain factors and time-constant factors, sorted.
    """
    tables = (req["robust_stability"], req["robust_stability_x4"])
    gains = sorted({float(g) for t in tables for g in t["gain_factors"]})
    taus = sorted({float(x) for t in tables for x in t["time_constant_factors"]})
    return gains, taus


def robustness_statement(req, checks):
    """The plant-robustness requirement and its reasoning, then each x4 finding, as sentences."""
    robust, beyond = req["robust_stability"], req["robust_stability_x4"]
    gains, taus = robust["gain_factors"], robust["time_constant_factors"]
    margin = req["gain_margin"]["min_gain_margin"]
    lines = [
        f"Requirement: every frozen gain set stable for plant DC gain x{min(gains):g}.."
        f"x{max(gains):g} and time constant x{min(taus):g}..x{max(taus):g} of RobotPlant's. "
        "A plant-gain factor G is, for stability, the whole controller made G times stronger, "
        f"so x{max(gains):g} is the {20 * math.log10(max(gains)):.0f} dB the gain-margin "
        f"requirement states (gain margin >= {margin:g}); at tau x1 the largest stable G "
        "equals the gain margin. An earlier version of the requirement asked for x0.25..x4 "
        "(12 dB), inconsistent with the gain margin; the "
        + "/".join(f"x{g:g}" for g in beyond["gain_factors"])
        + " column is still evaluated and shown, as the finding robust_stability_x4 (a "
        "warning; a failure with --strict)."]
    lines += [f"Finding: {c.measured}" for c in checks
              if c.name.startswith("robust_stability_x4") and not c.passed]
    return lines


def _judge(f, settings, req):
    surface = f["surface"]
    out = [
        C.check_routh_vs_roots(surface, req["routh_vs_roots"]),
        C.check_surface_stable(f["reachable"], req["surface_stable"]),
        C.check_gain_margin(surface, req["gain_margin"]),
        C.check_phase_margin(surface, req["phase_margin"]),
        C.check_step_response(surface, req["step_response"]),
        C.check_pid_baseline(f["pid"], req["pid_baseline"],
                             (req["gain_margin"], req["phase_margin"]), req["step_response"]),
        C.check_dc_gain(f["model"], req["dc_gain"]),
        C.check_controller_core_vs_tf(f["core_cross_check"], req["controller_core_vs_tf"]),
    ]
    if f.get("fmu_step"):
        out.append(C.check_plant_fmu_vs_tf(f["fmu_step"], f["fmu_step_bound_m_s"],
                                           req["plant_fmu_vs_tf"]))
    if f.get("controller_fmu"):
        out.append(C.check_controller_fmu_vs_law(f["controller_fmu"],
                                                 req["controller_fmu_vs_law"]))
    if f.get("closed_loop_fmus"):
        out.append(C.check_closed_loop_fmus_vs_tf(f["closed_loop_fmus"],
                                                  req["closed_loop_fmus_vs_tf"]))
    out.append(C.check_paper_gain_box(f["paper_box"], req["paper_gain_box"]))
    for name in ("fgs_pd", "pd", "pid"):
        points = f["robustness"]["points"][name]
        out.append(R.check_robust_stability(points, f["gain_factor_edges"], name,
                                            req["robust_stability"]))
        out.append(R.check_robust_stability_beyond(points, f["gain_factor_edges"], name,
                                                   req["robust_stability_x4"]))
        out.append(R.check_robust_steady_state(points, name, req["robust_steady_state"]))
    out.append(C.check_routh_gives_paper_bounds(f["routh_finding"], settings,
                                                req["routh_gives_paper_bounds"]))
    out.append(C.check_fgs_pd_overshoot_vs_pid(f["paper_case1"],
                                               surface["summary"]["overshoot_max_pct"],
                                               req["fgs_pd_overshoot_vs_pid"]))
    return out


def off_nominal(settings, plant, req, fmu=True, fmu_dir=None):
    """The off-nominal requirements of every design: the discrete-time loop over the whole
    grid, and the FMUs on the judged wheels (when ``fmu``).

    Returns
    -------
    dict
        ``judged`` (cells), ``grid`` (the grid table), ``model`` and ``fmu``: design ->
        requirement -> per-cell results (``fmu`` empty without the FMUs).
    """
    grid = req["off_nominal_grid"]
    judged = judged_cells(grid)
    designs = {name: design_settings(settings, form)
               for name, form in OFF_NOMINAL_DESIGNS.items()}
    result = {"judged": judged, "grid": dict(grid),
              "model": {name: measure_requirements(s, plant, req,
                                                   commission=name not in UNCOMMISSIONED)
                        for name, s in designs.items()},
              "fmu": {}}
    if fmu:
        result["fmu"] = fmu_requirements(
            {name: s for name, s in designs.items() if name not in UNCOMMISSIONED}, plant, req,
            judged, fmu_dir=fmu_dir)
    return result


def verify(out_dir=DEFAULT_OUT_DIR, plant_parameters=None, controller_parameters=None,
           grid_size=11, period=None, extra_delay=0, fmu=True, step_voltage=2.0, plots=True,
           requirements=None, strict=False, fmu_dir=None):
    """Verify the wheel-speed loop, judge every check and write the reports.

    Parameters
    ----------
    out_dir : path-like
        Folder for ``verification.json``, ``verification.md``, ``verification.html`` and
        the PNG figures.
    plant_parameters : PlantParameters, optional
    controller_parameters : dict, optional
        Overrides of :data:`components.control.DEFAULTS`.
    grid_size : int, optional
        Points per axis of the kp x kd grid (11: 121 gain sets).
    period : float, optional
        Loop period [s]; default the plant's ``speed_window`` (20 ms).
    extra_delay : int, optional
        Extra samples of delay (1 for a Jacobi master); see :class:`.WheelLoopModel`. The
        closed-loop FMU check needs 0 (our Gauss-Seidel master) and is skipped otherwise.
    fmu : bool, optional
        Build the FMUs and run the three FMU checks.
    step_voltage : float, optional
        Voltage of the plant FMU's step [V].
    plots : bool, optional
        Draw the figures (the HTML then embeds them).
    requirements : path-like or dict, optional
        The requirements file (default ``orchestrator/data/verification_requirements.toml``)
        or its parsed tables.
    strict : bool, optional
        Recorded in the summary: warnings count as failures.
    fmu_dir : path-like, optional
        A folder holding RobotPlant.fmu and WheelController.fmu built from this checkout
        (used as they are), or to build them into; default a temporary folder.

    Returns
    -------
    VerificationReport
    """
    started = time.perf_counter()
    plant = (plant_parameters or PlantParameters()).validate()
    settings = _settings(controller_parameters)
    req = requirements if isinstance(requirements, dict) else C.load_requirements(requirements)
    if int(grid_size) != grid_size or grid_size < 2:
        raise ConfigError(f"verify: grid_size = {grid_size!r} must be an integer >= 2")
    model = WheelLoopModel(
        plant=plant, period=period, e_range=settings["e_range"], de_range=settings["de_range"],
        derivative_time_constant=settings["derivative_time_constant"],
        volts_per_speed=settings["volts_per_speed"], feedforward=settings["feedforward"],
        extra_delay=extra_delay)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)

    f = {"settings": settings, "statement": model_statement(model, settings),
         "model": _model_figures(model, plant)}
    f["surface"] = measure.gain_surface(model, settings, grid_size)
    f["reachable"] = measure.surface_distances(model, measure.reachable_gains(settings),
                                               settings)
    paper = design_settings(settings, "paper")
    f["paper_box"] = measure.paper_box(model, paper)
    f["pid"] = measure.pid_baseline(model, settings)
    f["core_cross_check"] = measure.core_cross_check(model, settings)
    gains, taus = robustness_grid(req)
    f["requirements_grid"] = {
        "gain_factors": req["robust_stability"]["gain_factors"],
        "time_constant_factors": req["robust_stability"]["time_constant_factors"],
        "finding_gain_factors": req["robust_stability_x4"]["gain_factors"]}
    f["robustness"] = measure.robustness(model, settings, gains, taus)
    f["gain_factor_edges"] = measure.gain_factor_edges(
        model, settings, sorted(set(measure.FINE_TIME_CONSTANT_FACTORS) | set(taus)))
    f["robustness_pure_pd"] = measure.robustness(
        model, dict(paper, trim_ki=0.0), gains, taus, controllers=("fgs_pd",))["points"]["fgs_pd"]
    f["routh_finding"] = measure.routh_finding(model, settings)
    f["paper_case1"] = measure.paper_case1(settings, plant, model.period)
    f["pd_forms"] = measure.pd_forms(model, settings)
    if extra_delay == 0:
        jacobi = replace(model, extra_delay=1)
        f["jacobi_boundaries"] = [measure.form_boundary(jacobi, settings, kd)
                                  for kd in (settings["kd_min"], settings["kd_max"])]
    if fmu:
        # every FMU is built once, before any is loaded (fmu_runs.built_fmu says why)
        scratch = tempfile.TemporaryDirectory(prefix="sonotrack_verify_")
        fmu_dir = Path(fmu_dir or scratch.name)
        for name in ("RobotPlant", "WheelController"):
            built_fmu(name, fmu_dir)
        f["fmu_step"] = fmu_step_comparison(plant, voltage=step_voltage, duration=2.0,
                                            step=model.period, variants=fmu_variants(plant),
                                            fmu_dir=fmu_dir)
        f["fmu_step_bound_m_s"] = compliance_bound(plant, step_voltage)
        f["controller_fmu"] = controller_fmu_comparison(
            settings, samples=req["controller_fmu_vs_law"]["samples"], h=model.period,
            fmu_dir=fmu_dir)
        if extra_delay == 0:
            ki = integral_gain(settings)
            points = [("pd", settings["kp_min"], settings["kd_min"], ki),
                      ("pd", settings["kp_max"], settings["kd_max"], ki),
                      ("pid", settings["pid_kp"], settings["pid_kd"], settings["pid_ki"])]
            f["closed_loop_fmus"] = closed_loop_fmu_comparison(
                model, settings, points, step=req["closed_loop_fmus_vs_tf"]["step_m_s"],
                ramp=req["closed_loop_fmus_vs_tf"].get("ramp_m_s2"), fmu_dir=fmu_dir)
    f["off_nominal"] = off_nominal(settings, plant, req, fmu=fmu,
                                   fmu_dir=fmu_dir if fmu else None)
    if fmu:
        scratch.cleanup()
    report = VerificationReport(f, _judge(f, settings, req)
                                + requirement_checks(f["off_nominal"], req))
    f["robustness_statement"] = robustness_statement(req, report.checks)
    if plots:
        from .figures import write_figures

        for name, (path, caption) in write_figures(model, f, out_dir).items():
            report.paths[name] = path
            report.captions[name] = caption
    f["wall_time_s"] = time.perf_counter() - started
    _write_reports(report, model, out_dir, strict)
    return report


def _write_reports(report, model, out_dir, strict):
    from .document import verification_document

    report.paths["json"] = out_dir / "verification.json"
    atomic_write_text(report.paths["json"], report.to_json(strict), fsync=False)
    document = verification_document(report, model, strict)
    report.paths["markdown"] = write_markdown(document, out_dir / "verification.md",
                                              html_companion="verification.html")
    report.paths["html"] = write_html(document, out_dir / "verification.html")
