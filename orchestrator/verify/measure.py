"""What `sonotrack verify` measures on the linear loop: JSON-ready figures for the checks.

Each function takes the nominal :class:`.loop_model.WheelLoopModel` and the controller
settings (:data:`components.control.DEFAULTS` with overrides) and returns a plain dict; the
verdicts are given in :mod:`.checks`. The FGS-PD and fixed PD are analysed with their
integral trim (``trim_ki``), the form the controller runs; the PID with its own gains.
"""

import math
from dataclasses import asdict

import numpy as np

from components.control.fgs_pd import PAPER_TO_OURS, scheduled_gain
from components.control.inference import FuzzyGainScheduler

from .analysis import analyse_gains, controller_cross_check, incremental_form, kp_edge, \
    routh_bounds, stability_boundary
from .robustness import largest_stable_gain_factor, plant_grid, robustness_point

__all__ = ["gain_surface", "reachable_gains", "surface_distances", "paper_box",
           "pid_baseline", "robustness", "gain_factor_edges", "gain_sets", "routh_finding",
           "core_cross_check", "pd_forms", "paper_case1", "PAPER_BOX_SIGNED",
           "FINE_TIME_CONSTANT_FACTORS"]

# The paper's printed ranges on its own error convention (y - r): Sec. 4.1.
PAPER_BOX_SIGNED = {"Kp": (-4.0, -3.0), "Kd": (-2.0, -0.3)}

# Time-constant factors of the largest-stable-gain-factor figure: x0.5..x2 in steps of
# 2^(1/6) (12 %), exact powers of two so that 0.5, 1 and 2 are on it.
FINE_TIME_CONSTANT_FACTORS = tuple(float(2.0 ** (k / 6)) for k in range(-6, 7))


def _trim(settings):
    return float(settings["trim_ki"])


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
    grid = [asdict(analyse_gains(model, kp, kd, ki)) for kd in kds for kp in kps]
    boundaries = [stability_boundary(model, kd, ki) for kd in kds]
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


def surface_distances(model, gains, ki):
    """Stability of each gain set and its distance to the kp edge (``kp_edge(kd) / kp``).

    Returns
    -------
    dict
        ``points`` (kp, kd, spectral radius, kp edge, edge ratio), ``unstable`` count,
        ``min_edge_ratio`` and where it occurs.
    """
    edges = {}
    points = []
    for kp, kd in gains:
        if kd not in edges:
            edges[kd] = kp_edge(model, kd, ki)
        radius = float(np.max(np.abs(np.roots(model.characteristic_polynomial(kp, kd, ki)))))
        edge = edges[kd]
        ratio = edge / kp if kp > 0 else math.inf
        points.append({"kp": float(kp), "kd": float(kd), "spectral_radius": radius,
                       "kp_edge": edge, "edge_ratio": ratio})
    worst = min(points, key=lambda p: (p["spectral_radius"] < 1.0, p["edge_ratio"]))
    return {"points": points, "count": len(points),
            "unstable": sum(1 for p in points if p["spectral_radius"] >= 1.0),
            "min_edge_ratio": worst["edge_ratio"] if worst["spectral_radius"] < 1.0 else 0.0,
            "worst": worst}


def paper_box(model, ki, box=None, points=9):
    """The paper's gain box on our convention: its edge and interior grid, with distances.

    Parameters
    ----------
    box : dict, optional
        ``kp_min, kp_max, kd_min, kd_max`` on e = r - y; default
        :data:`components.control.fgs_pd.PAPER_TO_OURS` (the mapped paper ranges).
    """
    box = dict(box or PAPER_TO_OURS)
    kps = np.linspace(box["kp_min"], box["kp_max"], points)
    kds = np.linspace(box["kd_min"], box["kd_max"], points)
    gains = [(float(kp), float(kd)) for kd in kds for kp in kps]
    result = surface_distances(model, gains, ki)
    result.update(box=box, paper_signed=PAPER_BOX_SIGNED)
    literal = model.characteristic_polynomial(-box["kp_min"], -box["kd_min"], ki)
    result["literal_signs_spectral_radius"] = float(np.max(np.abs(np.roots(literal))))
    return result


def pid_baseline(model, settings):
    """Frozen analysis of the PID baseline and its kp stability edge."""
    result = asdict(analyse_gains(model, settings["pid_kp"], settings["pid_kd"],
                                  settings["pid_ki"]))
    result["boundary"] = stability_boundary(model, settings["pid_kd"], settings["pid_ki"])
    return result


def gain_sets(settings):
    """The frozen gain sets of each controller: FGS-PD surface corners, fixed PD, PID.

    Returns
    -------
    dict
        ``fgs_pd`` / ``pd`` / ``pid`` -> list of ``(kp, kd, ki)``; FGS-PD and PD carry the
        integral trim.
    """
    ki = _trim(settings)
    return {
        "fgs_pd": [(settings["kp_min"], settings["kd_min"], ki),
                   (settings["kp_min"], settings["kd_max"], ki),
                   (settings["kp_max"], settings["kd_min"], ki),
                   (settings["kp_max"], settings["kd_max"], ki)],
        "pd": [(settings["pd_kp"], settings["pd_kd"], ki)],
        "pid": [(settings["pid_kp"], settings["pid_kd"], settings["pid_ki"])],
    }


def robustness(model, settings, gain_factors, time_constant_factors,
               controllers=("fgs_pd", "pd", "pid")):
    """FGS-PD (surface corners), fixed PD and PID on every plant variant of the grid."""
    sets = gain_sets(settings)
    variants = plant_grid(gain_factors, time_constant_factors)
    return {"trim_ki": _trim(settings), "gain_factors": list(map(float, gain_factors)),
            "time_constant_factors": list(map(float, time_constant_factors)),
            "points": {name: [asdict(robustness_point(model, v, name, sets[name]))
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
    """The real controller core on the sampled plant vs the TF: middle of the surface, PID."""
    mid_kp = 0.5 * (settings["kp_min"] + settings["kp_max"])
    mid_kd = 0.5 * (settings["kd_min"] + settings["kd_max"])
    return {"pd_mid": controller_cross_check(model, mid_kp, mid_kd, _trim(settings)),
            "pid": controller_cross_check(model, settings["pid_kp"], settings["pid_kd"],
                                          settings["pid_ki"], mode="pid"),
            "step_m_s": 0.05}


def pd_forms(model, settings):
    """The surface's corners and middle in the incremental form (docs/control.md's comparison)."""
    kps = (settings["kp_min"], 0.5 * (settings["kp_min"] + settings["kp_max"]), settings["kp_max"])
    kds = (settings["kd_min"], 0.5 * (settings["kd_min"] + settings["kd_max"]), settings["kd_max"])
    return {"incremental": [incremental_form(model, kp, kd) for kp in kps for kd in kds]}


def paper_case1(settings, plant=None, period=0.02):
    """Paper Case 1 on the nonlinear plant core: FGS-PD (as configured and without the trim)
    and the CPID, every other controller setting as given (:mod:`.case1`).

    Returns
    -------
    dict
        ``results`` (controller -> wheel -> metrics), ``period_s``, ``trim_ki``.
    """
    from .case1 import compare

    configs = {"fgs_pd": dict(settings, mode="fgs_pd"),
               "fgs_pd_pure": dict(settings, mode="fgs_pd", trim_ki=0.0),
               "pid": dict(settings, mode="pid")}
    return {"results": compare(configs, h=period, plant_parameters=plant),
            "period_s": float(period), "trim_ki": _trim(settings)}
