"""What `sonotrack verify` measures on the linear loop: JSON-ready figures for the checks.

Each function takes the nominal :class:`.loop_model.WheelLoopModel` and the controller
settings (:data:`components.control.DEFAULTS` with overrides) and returns a plain dict; the
verdicts are given in :mod:`.checks`. The FGS-PD and fixed PD are analysed in the form the
settings select (:mod:`.designs`: each frozen (kp, kd) of the paper's boxes mapped onto the
loop model's gains, with the form's integral and feedforward); the PID with its own gains.
Grid entries keep kp and kd in the form's own units and carry the loop's gains as ``loop``.
"""

import math
from dataclasses import asdict

import numpy as np

from components.control.fgs_pd import PAPER_TO_OURS, scheduled_gain
from components.control.inference import FuzzyGainScheduler

from .analysis import analyse_gains, controller_cross_check, incremental_form, kp_edge, \
    routh_bounds, stability_boundary
from .designs import integral_gain, is_default_form, loop_gains, loop_model
from .robustness import largest_stable_gain_factor, plant_grid, robustness_point

__all__ = ["form_boundary", "gain_surface", "reachable_gains", "surface_distances", "paper_box",
           "pid_baseline", "robustness", "gain_factor_edges", "gain_sets", "routh_finding",
           "core_cross_check", "pd_forms", "paper_case1", "PAPER_BOX_SIGNED",
           "FINE_TIME_CONSTANT_FACTORS"]

# The paper's printed ranges on its own error convention (y - r): Sec. 4.1.
PAPER_BOX_SIGNED = {"Kp": (-4.0, -3.0), "Kd": (-2.0, -0.3)}

# Time-constant factors of the largest-stable-gain-factor figure: x0.5..x2 in steps of
# 2^(1/6) (12 %), exact powers of two so that 0.5, 1 and 2 are on it.
FINE_TIME_CONSTANT_FACTORS = tuple(float(2.0 ** (k / 6)) for k in range(-6, 7))


def _trim(settings):
    return integral_gain(settings)


def _kp_scale(settings):
    """Loop kp per unit kp of the form (the default form's gain_scale; 1 for the paper's)."""
    return float(settings["gain_scale"]) if is_default_form(settings) else 1.0


def _analysis(model, settings, kp, kd):
    """One frozen gain set of the form, analysed on the loop; kp, kd in the form's units."""
    loop = loop_gains(settings, kp, kd)
    result = asdict(analyse_gains(loop_model(model, settings), *loop))
    result.update(kp=float(kp), kd=float(kd), loop=list(loop))
    return result


def form_boundary(model, settings, kd):
    """The kp stability edge at ``kd`` (form units), in the form's kp units."""
    loop_kp, loop_kd, ki = loop_gains(settings, 1.0, kd)
    boundary = stability_boundary(model, loop_kd, ki)
    def form_units(value):
        return None if value is None else value / loop_kp
    return dict(boundary, kd=float(kd), kp_routh=form_units(boundary["kp_routh"]),
                kp_roots=form_units(boundary["kp_roots"]), loop_kd=loop_kd)


def gain_surface(model, settings, grid_size):
    """Frozen-gain analyses on a ``grid_size`` x ``grid_size`` grid over the gain box.

    Returns
    -------
    dict
        ``kps``, ``kds``, ``grid`` (one :class:`.GainAnalysis` dict per point, kd outer),
        ``boundaries`` (:func:`.stability_boundary` at each kd) and a ``summary``.
    """
    ki = _trim(settings)
    kps = np.linspace(settings["kp_min"], settings["kp_max"], int(grid_size))
    kds = np.linspace(settings["kd_min"], settings["kd_max"], int(grid_size))
    grid = [_analysis(model, settings, kp, kd) for kd in kds for kp in kps]
    boundaries = [form_boundary(model, settings, kd) for kd in kds]
    stable = [g for g in grid if g["stable_roots"]]
    summary = {
        "gain_margin_min": min(g["gain_margin"] for g in grid),
        "phase_margin_min_deg": min(g["phase_margin_deg"] for g in grid),
        "overshoot_max_pct": max((g["overshoot_pct"] for g in stable), default=math.nan),
        "settling_max_s": max((g["settling_time_s"] for g in stable), default=math.nan),
        "spectral_radius_max": max(g["spectral_radius"] for g in grid),
        "linear_step_limit_min_m_s": min(g["linear_step_limit_m_s"] for g in grid),
    }
    return {"ki": ki, "kps": kps.tolist(), "kds": kds.tolist(), "grid": grid,
            "boundaries": boundaries, "summary": summary}


def reachable_gains(settings, points=41):
    """The (kp, kd) the fuzzy scheduler can output, over a grid of its normalised inputs.

    The grid spans the universe [-1, 1] in both inputs (beyond it the inputs are clipped, so
    nothing new is reachable); duplicates are removed.

    Returns
    -------
    numpy.ndarray
        Shape (n, 2): kp, kd.
    """
    scheduler = FuzzyGainScheduler(settings["e_range"], settings["de_range"],
                                   method=settings["fuzzy_method"])
    axis = np.linspace(-1.0, 1.0, int(points))
    gains = set()
    for e_n in axis:
        for de_n in axis:
            kp_n, kd_n = scheduler.evaluate_normalised(float(e_n), float(de_n))
            gains.add((round(scheduled_gain(kp_n, settings["kp_min"], settings["kp_max"]), 12),
                       round(scheduled_gain(kd_n, settings["kd_min"], settings["kd_max"]), 12)))
    return np.array(sorted(gains))


def surface_distances(model, gains, settings):
    """Stability of each gain set and its distance to the kp edge (``kp_edge(kd) / kp``).

    ``gains`` are (kp, kd) in the form's units; the edge and the ratio are the loop's (a
    ratio does not depend on the unit).

    Returns
    -------
    dict
        ``points`` (kp, kd, spectral radius, kp edge in the form's units, edge ratio),
        ``unstable`` count, ``min_edge_ratio`` and where it occurs.
    """
    edges = {}
    points = []
    for kp, kd in gains:
        loop_kp, loop_kd, ki = loop_gains(settings, kp, kd)
        if loop_kd not in edges:
            edges[loop_kd] = kp_edge(model, loop_kd, ki)
        radius = float(np.max(np.abs(np.roots(
            model.characteristic_polynomial(loop_kp, loop_kd, ki)))))
        edge = edges[loop_kd]
        ratio = edge / loop_kp if loop_kp > 0 else math.inf
        points.append({"kp": float(kp), "kd": float(kd), "spectral_radius": radius,
                       "kp_edge": edge * kp / loop_kp if loop_kp > 0 else edge,
                       "edge_ratio": ratio})
    worst = min(points, key=lambda p: (p["spectral_radius"] < 1.0, p["edge_ratio"]))
    return {"points": points, "count": len(points),
            "unstable": sum(1 for p in points if p["spectral_radius"] >= 1.0),
            "min_edge_ratio": worst["edge_ratio"] if worst["spectral_radius"] < 1.0 else 0.0,
            "worst": worst}


def paper_box(model, settings, box=None, points=9):
    """The paper's gain box on our convention: its edge and interior grid, with distances.

    Parameters
    ----------
    settings : dict
        The paper form's controller parameters (its trim is the loop's integral).
    box : dict, optional
        ``kp_min, kp_max, kd_min, kd_max`` on e = r - y; default
        :data:`components.control.fgs_pd.PAPER_TO_OURS` (the mapped paper ranges).
    """
    box = dict(box or PAPER_TO_OURS)
    kps = np.linspace(box["kp_min"], box["kp_max"], points)
    kds = np.linspace(box["kd_min"], box["kd_max"], points)
    gains = [(float(kp), float(kd)) for kd in kds for kp in kps]
    result = surface_distances(model, gains, settings)
    result.update(box=box, paper_signed=PAPER_BOX_SIGNED)
    ki = _trim(settings)
    literal = model.characteristic_polynomial(-box["kp_min"], -box["kd_min"], ki)
    result["literal_signs_spectral_radius"] = float(np.max(np.abs(np.roots(literal))))
    return result


def pid_baseline(model, settings):
    """Frozen analysis of the PID baseline and its kp stability edge."""
    model = loop_model(model, dict(settings, mode="pid"))
    result = asdict(analyse_gains(model, settings["pid_kp"], settings["pid_kd"],
                                  settings["pid_ki"]))
    result["boundary"] = stability_boundary(model, settings["pid_kd"], settings["pid_ki"])
    return result


def gain_sets(settings):
    """The frozen gain sets of each controller: FGS-PD surface corners, fixed PD, PID.

    Returns
    -------
    dict
        ``fgs_pd`` / ``pd`` / ``pid`` -> list of ``(kp, kd, ki)`` on the loop model
        (:func:`.designs.loop_gains`); FGS-PD and PD carry their form's integral.
    """
    corners = [(settings[f"kp_{a}"], settings[f"kd_{b}"]) for a, b in
               (("min", "min"), ("min", "max"), ("max", "min"), ("max", "max"))]
    return {
        "fgs_pd": [loop_gains(settings, kp, kd) for kp, kd in corners],
        "pd": [loop_gains(settings, settings["pd_kp"], settings["pd_kd"])],
        "pid": [(settings["pid_kp"], settings["pid_kd"], settings["pid_ki"])],
    }


def robustness(model, settings, gain_factors, time_constant_factors,
               controllers=("fgs_pd", "pd", "pid")):
    """FGS-PD (surface corners), fixed PD and PID on every plant variant of the grid."""
    sets = gain_sets(settings)
    variants = plant_grid(gain_factors, time_constant_factors)
    models = {name: loop_model(model, dict(settings, mode=name)) for name in controllers}
    return {"trim_ki": _trim(settings), "gain_factors": list(map(float, gain_factors)),
            "time_constant_factors": list(map(float, time_constant_factors)),
            "points": {name: [asdict(robustness_point(models[name], v, name, sets[name]))
                              for v in variants] for name in controllers}}


def gain_factor_edges(model, settings, time_constant_factors=FINE_TIME_CONSTANT_FACTORS,
                      controllers=("fgs_pd", "pd", "pid")):
    """Largest stable plant-DC-gain factor of every frozen gain set at each time constant.

    Returns
    -------
    dict
        ``time_constant_factors`` and ``sets``: per gain set its ``controller``, ``kp``,
        ``kd``, ``ki`` and ``edges`` (one :func:`.robustness.largest_stable_gain_factor`
        dict per time-constant factor).
    """
    sets = gain_sets(settings)
    out = []
    for name in controllers:
        for kp, kd, ki in sets[name]:
            out.append({"controller": name, "kp": float(kp), "kd": float(kd), "ki": float(ki),
                        "edges": [largest_stable_gain_factor(model, kp, kd, ki, tau)
                                  for tau in time_constant_factors]})
    return {"time_constant_factors": [float(t) for t in time_constant_factors], "sets": out}


def routh_finding(model, settings):
    """Routh's bounds for the paper's pure PD (continuous and sampled), at the box's ends."""
    return routh_bounds(model, kp_probe=(settings["kp_min"], settings["kp_max"]),
                        kd_probe=(settings["kd_min"], settings["kd_max"]), ki=0.0)


def core_cross_check(model, settings):
    """The real controller core on the sampled plant vs the TF: middle of the surface, PID.

    The core runs the form of ``settings`` in fixed-PD mode at the box's middle (no voltage
    limit); the TF is the loop model with that form's gains and feedforward.
    """
    mid_kp = 0.5 * (settings["kp_min"] + settings["kp_max"])
    mid_kd = 0.5 * (settings["kd_min"] + settings["kd_max"])
    core = dict(settings, mode="pd", pd_kp=mid_kp, pd_kd=mid_kd, v_supply=1e9)
    pd_model = loop_model(model, core)
    pid = dict(settings, mode="pid", v_supply=1e9)
    return {"pd_mid": controller_cross_check(pd_model, *loop_gains(settings, mid_kp, mid_kd),
                                             controller=core),
            "pid": controller_cross_check(loop_model(model, pid), settings["pid_kp"],
                                          settings["pid_kd"], settings["pid_ki"],
                                          controller=pid),
            "step_m_s": 0.05}


def pd_forms(model, settings):
    """The surface's corners and middle in the incremental form (docs/control.md's comparison)."""
    kps = (settings["kp_min"], 0.5 * (settings["kp_min"] + settings["kp_max"]), settings["kp_max"])
    kds = (settings["kd_min"], 0.5 * (settings["kd_min"] + settings["kd_max"]), settings["kd_max"])
    return {"incremental": [incremental_form(model, kp, kd) for kp in kps for kd in kds]}


def paper_case1(settings, plant=None, period=0.02):
    """Paper Case 1 on the nonlinear plant core: FGS-PD as configured, in the paper's form
    and as the paper's pure PD, and the CPID, every other setting as given (:mod:`.case1`).

    Returns
    -------
    dict
        ``results`` (controller -> wheel -> metrics), ``period_s``, ``trim_ki``.
    """
    from .case1 import compare
    from .designs import design_settings

    paper = design_settings(settings, "paper")
    configs = {"fgs_pd": dict(settings, mode="fgs_pd"),
               "fgs_pd_paper": paper,
               "fgs_pd_pure": dict(paper, trim_ki=0.0),
               "pid": dict(settings, mode="pid")}
    return {"results": compare(configs, h=period, plant_parameters=plant),
            "period_s": float(period), "trim_ki": _trim(settings),
            "form": settings.get("form", "default")}
