"""Verdicts on the loop driving wheels unlike RobotPlant's (:mod:`.robustness`'s figures).

``robust_stability`` (a requirement: the gain margin's 6 dB as a plant-gain range, judged on
the grid and on the exact stable range of the gain factor), ``robust_stability_x4`` (a
finding: the x4 column beyond it) and ``robust_steady_state``; one check per controller.
"""

import math

from .checks import _check

__all__ = ["check_robust_stability", "check_robust_stability_beyond",
           "check_robust_steady_state"]

_LABELS = {"fgs_pd": "the FGS-PD (the paper's gain box, its surface corners)",
           "pd": "the fixed PD", "pid": "the CPID"}


def _on_grid(points, req):
    """The grid points whose factors the requirement table names."""
    gains, taus = set(map(float, req["gain_factors"])), set(map(float,
                                                               req["time_constant_factors"]))
    return [p for p in points
            if p["gain_factor"] in gains and p["time_constant_factor"] in taus]


def _edges_within(edge_sets, controller, req):
    """(set, edge) pairs of one controller at the time-constant factors inside the table's span."""
    low, high = min(req["time_constant_factors"]), max(req["time_constant_factors"])
    return [(s, e) for s in edge_sets["sets"] if s["controller"] == controller
            for e in s["edges"] if low - 1e-12 <= e["time_constant_factor"] <= high + 1e-12]


def _tau_words(tau):
    return {0.5: "half the", 1.0: "the same", 2.0: "twice the"}.get(float(tau), f"x{tau:g} the")


def check_robust_stability(points, edge_sets, controller, req):
    """Stable on every wheel of the required grid, and the exact stable factor range covers it.

    Parameters
    ----------
    points : list of dict
        :class:`.robustness.RobustnessPoint` dicts of one controller (the whole evaluated
        grid; only the factors the requirement names are judged).
    edge_sets : dict
        :func:`.measure.gain_factor_edges`.
    controller : str
    req : dict
        ``gain_factors``, ``time_constant_factors``.
    """
    judged = _on_grid(points, req)
    gains = req["gain_factors"]
    unstable = [p for p in judged if not p["spectral_radius"] < 1.0]
    edges = _edges_within(edge_sets, controller, req)
    worst_set, worst = min(edges, key=lambda se: se[1]["upper"] if se[1]["nominal_stable"]
                           else -math.inf)
    upper = worst["upper"] if worst["nominal_stable"] else math.nan
    lower = max((e["lower"] if e["nominal_stable"] else math.inf) for _, e in edges)
    covered = math.isfinite(upper) and upper > max(gains) and lower < min(gains)
    where = "; ".join(f"gain x{p['gain_factor']:g}, tau x{p['time_constant_factor']:g} "
                      f"(max|z| {p['spectral_radius']:.3f})" for p in unstable)
    measured = (f"{len(unstable)} of {len(judged)} wheels unstable"
                + (f": {where}" if unstable else "")
                + f"; largest max|z| {max(p['spectral_radius'] for p in judged):.4f}; "
                f"stable up to x{upper:.3g} plant gain at tau x{worst['time_constant_factor']:.3g}"
                f" (kp {worst_set['kp']:g}, kd {worst_set['kd']:g}), the least over tau "
                f"x{min(req['time_constant_factors']):g}..x{max(req['time_constant_factors']):g}"
                "; " + (f"lower edge x{lower:.3g}" if any(e["lower_found"] for _, e in edges)
                        else f"no lower edge down to x{lower:.3g} (the search's end)"))
    return _check("robust_stability", req,
                  f"stable on all {len(judged)} wheels: gain x{min(gains):g}..x{max(gains):g} "
                  f"(the {20 * math.log10(max(gains)):.0f} dB of the gain margin), time constant "
                  f"x{min(req['time_constant_factors']):g}..x{max(req['time_constant_factors']):g}"
                  "; exact stable gain-factor range covers it at every time constant",
                  measured, not unstable and covered,
                  {"unstable": len(unstable), "points": len(judged),
                   "largest_stable_gain_factor": upper,
                   "at_time_constant_factor": worst["time_constant_factor"],
                   "lower_edge_max": lower}, suffix=f"_{controller}")


def check_robust_stability_beyond(points, edge_sets, controller, req):
    """A finding: stable on the wheels beyond the requirement (4x the DC gain)?

    The same inputs as :func:`check_robust_stability`; ``req`` is the finding's table. The
    measured text leads with what a designer must do when it fails.
    """
    judged = _on_grid(points, req)
    unstable = [p for p in judged if not p["spectral_radius"] < 1.0]
    edges = {round(e["time_constant_factor"], 9): e
             for s in edge_sets["sets"] if s["controller"] == controller for e in s["edges"]}
    gain = max(req["gain_factors"])

    def edge_text(tau):
        e = edges.get(round(float(tau), 9))
        if e is None or not e["nominal_stable"]:
            return "-"
        return f"x{e['upper']:.3g}"

    taus = req["time_constant_factors"]
    ranges = ", ".join(f"{edge_text(t)} at tau x{t:g}" for t in taus)
    if unstable:
        first = min(unstable, key=lambda p: p["time_constant_factor"])
        head = (f"{_LABELS.get(controller, controller)} is UNSTABLE on a wheel with {gain:g}x "
                f"the DC gain and {_tau_words(first['time_constant_factor'])} time constant; "
                "retune for such a motor. ")
    else:
        head = (f"{_LABELS.get(controller, controller)} stays stable on a wheel with "
                f"{gain:g}x the DC gain at every time constant judged. ")
    head = head[0].upper() + head[1:]
    measured = head + "; ".join(
        f"gain x{p['gain_factor']:g}, tau x{p['time_constant_factor']:g}: max|z| "
        f"{p['spectral_radius']:.3f}" for p in judged) + f". Stable up to {ranges}."
    return _check("robust_stability_x4", req,
                  f"stable on a wheel with {gain:g}x RobotPlant's DC gain "
                  f"({20 * math.log10(gain):.0f} dB), time constant x{min(taus):g}..x"
                  f"{max(taus):g}", measured, not unstable,
                  {"unstable": len(unstable), "points": len(judged),
                   "largest_stable_gain_factor": {f"{t:g}": (edges[round(float(t), 9)]["upper"]
                                                             if round(float(t), 9) in edges
                                                             else None) for t in taus}},
                  suffix=f"_{controller}")


def check_robust_steady_state(points, controller, req):
    """Final-value error on every stable plant variant for one controller."""
    limit = req["max_steady_state_error_fraction"]
    stable = [p for p in points if p["spectral_radius"] < 1.0]
    worst = max(stable, key=lambda p: p["steady_state_error"]) if stable else None
    value = worst["steady_state_error"] if worst else math.nan
    passed = worst is not None and value <= limit
    text = (f"worst {100 * value:.3g} % at gain x{worst['gain_factor']:g}, tau "
            f"x{worst['time_constant_factor']:g} over {len(stable)} stable wheels; slowest "
            f"settling {max(p['settling_time_s'] for p in stable):.2f} s" if worst
            else "no stable wheel")
    return _check("robust_steady_state", req,
                  f"|steady-state error| <= {100 * limit:g} % of the reference on every stable "
                  "wheel (final value theorem)", text, passed,
                  {"worst_fraction": value, "stable_points": len(stable)},
                  suffix=f"_{controller}")
