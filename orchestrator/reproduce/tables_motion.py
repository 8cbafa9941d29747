"""Sec. 3.6 (Tables 1-3) and Sec. 4.2's wheel profiles (Tables 6-7): tables, claims, ratios.

Every simulated figure is an estimate with its 95 % interval over a cell's Monte Carlo runs
(the mean, or the median where runs gave no value or the values separate: statistics.py);
Tables 6-7 put the simulated wheels (cruise speed, ramp acceleration, encoder distance) beside
the planner's formula values (Eqs. 36-42) and the paper's numbers.
"""

import math

import numpy as np

from .claims import Claim, mechanism_text, paired_at_arrival, per_run_slopes
from .report import Comparison, Table

__all__ = ["GROWTH_MARGIN", "TURN_MARGIN", "RADIUS_MARGIN", "motion_tables", "profile_tables",
           "formula_profiles"]

# Growth claims: the per-run slope over 0.1..0.5 m/s. "No effect" margin: an error that grows
# 2 cm over the whole 0.4 m/s range (0.05 m per m/s) is the smallest change that matters
# beside the paper's 5-73 cm errors and the localizer's cm-level noise; likewise 2 deg of turn
# error and 2 cm of radius over the range.
GROWTH_MARGIN = 0.05            # m per (m/s)
TURN_MARGIN = 5.0               # deg per (m/s)
RADIUS_MARGIN = 0.05            # m per (m/s)
# "A is better than B" (Table 3): "no effect" within a tenth of the paper's difference, never
# below 0.5 mm of RMSE.
BETTER_FRACTION, RMSE_RESOLUTION = 0.10, 5e-4
_MODES = {"rotate_then_go": "rotate then go", "curvature": "curvature"}


def _paper_slope(paper, table, column, speeds):
    """Least-squares slope of the paper's column over the selected speeds (None if < 2)."""
    values = [_paper(paper, table, column, s) for s in speeds]
    points = [(s, v) for s, v in zip(speeds, values) if v is not None]
    if len(points) < 2:
        return None
    return float(np.polyfit(*zip(*points), 1)[0])


def _paper(paper, table, column, speed):
    return dict(zip(paper[table]["v"], paper[table][column])).get(round(speed, 3))


def _beside_paper(row, ratios, paper, table, label, speed, columns):
    """Put the paper's value beside each simulated one of ``row`` and compare the two.

    ``columns`` are ``(key, paper column, unit)``: ``row[key + "_paper"]`` gets the paper's value
    at ``speed`` from ``paper[table]`` and ``ratios`` a :class:`Comparison` under ``label``.
    """
    for key, column, unit in columns:
        row[f"{key}_paper"] = _paper(paper, table, column, speed)
        ratios.append(Comparison(label, f"v = {speed:g}", f"{key} [{unit}]",
                                 row[f"{key}_paper"], row[key]))


def motion_tables(analysis, selected, speeds, paper):
    """Tables 1-3 with their claims and paper ratios."""
    tables, claims, ratios = {}, [], []

    def cell(speed, mode):
        return f"t13_v{speed:g}_{mode}"

    def est(speed, mode, key, scale=1.0):
        return analysis.estimate(cell(speed, mode), key, scale)

    def growth(mode, key, margin, unit, claim, paper_value, paper_text, source):
        runs = list(zip(*[analysis.values(cell(s, mode), key) for s in speeds]))
        slopes = per_run_slopes(speeds, runs)
        lost = 0
        if key == "error_at_arrival_m":
            # a run that never arrived at some speed has no error slope: a loss
            arrived = list(zip(*[analysis.values(cell(s, mode), "arrived") for s in speeds]))
            for i, flags in enumerate(arrived):
                if not all(flags):
                    slopes[i], lost = None, lost + 1
        ends = {f"v {speeds[0]:g}": cell(speeds[0], mode), f"v {speeds[-1]:g}":
                cell(speeds[-1], mode)}
        return Claim(source, claim, f"{len(speeds)} speeds {speeds[0]:g}-{speeds[-1]:g} m/s",
                     f"per-run slope of {key} over speed", slopes, "above", unit,
                     paper=paper_value, paper_text=paper_text, margin=margin,
                     comparator="no growth (slope 0)", failures=lost,
                     cells=tuple(cell(s, mode) for s in speeds),
                     reason=mechanism_text(analysis, ends,
                                            "motion" if mode == "curvature" else "rotate"))

    if "table1" in selected:
        t = Table("table1", "Table 1: rotate then go (without curvature), target (1.5, 1.5) m, "
                  "a_max 0.5 m/s^2",
                  [("v", "v [m/s]", ".1f"), ("distance", "distance [m] sim", ".3f"),
                   ("distance_paper", "paper", ".3f"), ("error", "error at arrival [m] sim", ".3f"),
                   ("error_paper", "paper", ".3f"), ("time", "time [ms] sim", ".0f"),
                   ("time_paper", "paper", ".0f"), ("turn", "first turn [deg] (ideal -45)",
                                                    ".1f")])
        for s in speeds:
            row = {"v": s, "distance": est(s, "rotate_then_go", "distance_m"),
                   "error": est(s, "rotate_then_go", "error_at_arrival_m"),
                   "time": est(s, "rotate_then_go", "arrival_s", 1000.0),
                   "turn": est(s, "rotate_then_go", "turn_deg")}
            _beside_paper(row, ratios, paper, "table1_without_curvature", "Table 1", s,
                          (("distance", "distance_m", "m"), ("error", "error_m", "m"),
                           ("time", "time_ms", "ms")))
            t.rows.append(row)
        t.notes += ["The straight-line distance to (1.5, 1.5) is 2.121 m; the paper's error "
                    "column equals its distance minus 2.000 m in every row.",
                    "time: until the robot has arrived (within 0.10 m of the target and at "
                    "rest, definitions); the paper's 'Time (m/s)' column is in ms.",
                    "Our rotate_then_go plans a new leg (turn, then straight) when a fix "
                    "arrived during the last leg; distance and time include it."]
        tables["table1"] = t
        claims.append(growth("rotate_then_go", "error_at_arrival_m", GROWTH_MARGIN, "m/(m/s)",
                             "rotate then go: the error at arrival grows with speed",
                             _paper_slope(paper, "table1_without_curvature", "error_m",
                                          speeds),
                             "0.050 -> 0.734 m", "Table 1 / Sec. 3.6"))
        claims.append(growth("rotate_then_go", "turn_error_deg", TURN_MARGIN, "deg/(m/s)",
                             "rotate then go: the rotation towards the target errs more at "
                             "higher speed", None, "(text only)", "Sec. 3.6"))
    if "table2" in selected:
        t = Table("table2", "Table 2: curvature, target (1.5, 1.5) m, a_max 0.5 m/s^2",
                  [("v", "v [m/s]", ".1f"), ("radius", "radius (planner) [m] sim", ".3f"),
                   ("radius_paper", "paper", ".3f"), ("radius_fit", "radius driven [m]", ".3f"),
                   ("distance", "distance [m] sim", ".3f"), ("distance_paper", "paper", ".3f"),
                   ("error", "error at arrival [m] sim", ".3f"), ("error_paper", "paper", ".3f"),
                   ("time", "time [ms] sim", ".0f"), ("time_paper", "paper", ".0f")])
        for s in speeds:
            row = {"v": s, "radius": est(s, "curvature", "radius_planner_m"),
                   "radius_fit": est(s, "curvature", "radius_fit_m"),
                   "distance": est(s, "curvature", "distance_m"),
                   "error": est(s, "curvature", "error_at_arrival_m"),
                   "time": est(s, "curvature", "arrival_s", 1000.0)}
            _beside_paper(row, ratios, paper, "table2_with_curvature", "Table 2", s,
                          (("radius", "rotation_radius_m", "m"), ("distance", "distance_m", "m"),
                           ("error", "error_m", "m"), ("time", "time_ms", "ms")))
            t.rows.append(row)
        t.notes += ["Ideal arc to (1.5, 1.5) from (0, 0) facing +y: R = 1.5 m, length 2.356 m. "
                    "The paper's distance is (pi/2) x its radius in every row: a quarter "
                    "circle of that radius would end at (R, R), not at (1.5, 1.5).",
                    "radius driven: circle fitted to the true path; the paper attributes its "
                    "growing radius to the outward force at speed."]
        tables["table2"] = t
        claims.append(growth("curvature", "error_at_arrival_m", GROWTH_MARGIN, "m/(m/s)",
                             "curvature: the error at arrival grows with speed",
                             _paper_slope(paper, "table2_with_curvature", "error_m", speeds),
                             "0.057 -> 0.656 m", "Table 2 / Sec. 3.6"))
        claims.append(growth("curvature", "radius_fit_m", RADIUS_MARGIN, "m/(m/s)",
                             "curvature: the actual rotation radius enlarges with speed",
                             _paper_slope(paper, "table2_with_curvature", "rotation_radius_m",
                                          speeds),
                             "1.944 -> 2.488 m", "Table 2 / Sec. 3.6"))
    if "table3" in selected:
        t = Table("table3", "Table 3: path RMSE from the ideal path of the mode",
                  [("v", "v [m/s]", ".1f"), ("trajectory", "trajectory", ""),
                   ("rmse", "RMSE [m] sim", ".4f"), ("rmse_paper", "paper", ".4f")])
        for s in speeds:
            for mode, label, column in (("rotate_then_go", "non-curvature", "non_curvature"),
                                        ("curvature", "curvature", "curvature")):
                row = {"v": s, "trajectory": label, "rmse": est(s, mode, "rmse_path_m"),
                       "rmse_paper": _paper(paper, "table3_rmse", column, s)}
                t.rows.append(row)
                ratios.append(Comparison("Table 3", f"v = {s:g}, {label}", "RMSE [m]",
                                         row["rmse_paper"], row["rmse"]))
            curved = _paper(paper, "table3_rmse", "curvature", s)
            straight = _paper(paper, "table3_rmse", "non_curvature", s)
            effect = None if None in (curved, straight) else curved - straight
            better, other = cell(s, "curvature"), cell(s, "rotate_then_go")
            samples, lost = paired_at_arrival(analysis, better, other, "rmse_path_m")
            claims.append(Claim(
                "Table 3", "the curvature trajectory has a lower RMSE than rotate then go",
                f"v = {s:g} m/s", "paired difference RMSE(curvature) - RMSE(rotate then go)",
                samples, "below", "m", paper=effect, paper_text=f"{curved} vs {straight}",
                margin=max(BETTER_FRACTION * abs(effect or 0.0), RMSE_RESOLUTION),
                comparator="rotate then go", failures=lost, cells=(better, other),
                reason=mechanism_text(analysis, {"curvature": better,
                                                 "rotate then go": other}, "modes")))
        t.notes.append("Ideal paths: each mode against its own plan, the segment (0, 0) -> "
                       "(1.5, 1.5) for non-curvature and the tangent arc R = 1.5 m for "
                       "curvature; the paper does not define its RMSE.")
        tables["table3"] = t
    return tables, claims, ratios


def formula_profiles(track_width, v_cruise=0.3, v_max=0.4, a_max=0.4):
    """Tables 6-7 from the planner's formulas (Eqs. 36-42 and its ramp limits).

    Returns
    -------
    dict
        ``case1``, ``case2_segment1``, ``case2_segment2``: ``radius``, ``centre_length`` and
        per side ``{left,right}_{velocity,acceleration,distance}``; the acceleration is the
        planner's ramp (outer wheel at ``a_max``), not the paper's 1 s ramp.
    """
    from components.planner.geometry import (arc_curvature, arc_length, radius_of,
                                             wheel_arc_lengths, wheel_factors)

    profiles = {}
    for name, distance, bearing in (("case1", 2.0, -math.pi / 4),
                                    ("case2_segment1", 1.0, -math.pi / 4),
                                    ("case2_segment2", 1.0, math.pi / 4)):
        kappa = arc_curvature(distance, bearing)
        factors = wheel_factors(kappa, track_width)
        scale = max(abs(f) for f in factors)
        centre = min(v_cruise, v_max / scale)
        lengths = wheel_arc_lengths(kappa, arc_length(distance, bearing), track_width)
        profile = {"radius": radius_of(kappa), "centre_length": arc_length(distance, bearing)}
        for side, factor, length in zip(("left", "right"), factors, lengths):
            profile[f"{side}_velocity"] = factor * centre
            profile[f"{side}_acceleration"] = factor * a_max / scale
            profile[f"{side}_distance"] = length
        profiles[name] = profile
    return profiles


def profile_tables(analysis, selected, paper):
    """Tables 6-7: simulated wheels at L = 0.40 m and 0.289 m beside formulas and paper."""
    tables, ratios = {}, []
    formulas = {0.40: formula_profiles(0.40), 0.289: formula_profiles(0.289)}
    cells = {0.40: "t67_{case}_track040", 0.289: "t89_{case}_fgs_pd_ff_on_mu0.8"}
    keys = {"velocity": "cruise_m_s", "acceleration": "ramp_m_s2", "distance": "encoder_m"}
    columns = [("quantity", "quantity", ""), ("sim040", "sim L=0.40", ".3f"),
               ("formula040", "formula L=0.40", ".3f"), ("sim0289", "sim L=0.289", ".3f"),
               ("formula0289", "formula L=0.289", ".3f"), ("paper", "paper", ".3f")]
    note = ("Track width erratum (docs/errata.md): the paper's wheel figures need L = 0.40 m; the "
            "robot's own L = 0.289 m (Table 11). sim: FGS-PD with feedforward, nominal "
            "friction, the planner's ramps (outer wheel at a_max = 0.4 m/s^2); the paper "
            "prints velocity / (1 s) as its acceleration. Wheel distances are the encoder's "
            "(nominal radius).")
    specs = []
    if "table6" in selected:
        printed = paper["table6_static_profile"]
        specs.append(("table6", "Table 6: Case 1 wheel profile (2 m at 45 deg right, V 0.3 "
                      "m/s)", "static", [("case1", 0, "", {s: {k: printed[s][k] for k in keys}
                                                             for s in ("left", "right")})],
                      paper["table7_dynamic_profile"]["static_radius_m"],
                      paper["table7_dynamic_profile"]["static_moving_distance_m"]))
    if "table7" in selected:
        printed = paper["table7_dynamic_profile"]
        segments = []
        for i, segment in enumerate(("segment1", "segment2")):
            values = {s: {k: printed[segment][f"{s}_{k}"] for k in keys}
                      for s in ("left", "right")}
            segments.append((f"case2_{segment}", i, f"{segment} ", values))
        specs.append(("table7", "Table 7: Case 2 wheel profile (1 m at 45 deg right, then 1 m "
                      "at 45 deg left, V 0.3 m/s)", "dynamic", segments, None,
                      printed["dynamic_moving_distance_m"]))
    for name, title, case, segments, radius_paper, distance_paper in specs:
        table = Table(name, title, columns)
        label = f"Table {name[-1]}"
        for profile, segment, prefix, printed in segments:
            for side in ("left", "right"):
                for quantity, key in keys.items():
                    unit = {"velocity": "m/s", "acceleration": "m/s^2", "distance": "m"}[quantity]
                    row = {"quantity": f"{prefix}{side} {quantity} [{unit}]",
                           "paper": printed[side][quantity]}
                    for width, tag in ((0.40, "040"), (0.289, "0289")):
                        row[f"sim{tag}"] = analysis.estimate(cells[width].format(case=case),
                                                             f"{side}_{key}", segment=segment)
                        row[f"formula{tag}"] = formulas[width][profile][f"{side}_{quantity}"]
                    table.rows.append(row)
                    ratios.append(Comparison(label, row["quantity"], "L=0.40 sim",
                                             row["paper"], row["sim040"]))
        first = segments[0][0]
        row = {"quantity": "radius at the first fix [m]", "paper": radius_paper}
        centre = {"quantity": "centre distance [m]", "paper": distance_paper}
        for width, tag in ((0.40, "040"), (0.289, "0289")):
            cell = cells[width].format(case=case)
            row[f"sim{tag}"] = analysis.estimate(cell, "radius_planner_m")
            row[f"formula{tag}"] = formulas[width][first]["radius"]
            centre[f"sim{tag}"] = analysis.estimate(cell, "distance_m")
            centre[f"formula{tag}"] = sum(formulas[width][p]["centre_length"]
                                          for p, *_ in segments)
        table.rows += [row, centre]
        ratios.append(Comparison(label, "centre distance [m]", "L=0.40 sim", distance_paper,
                                 centre["sim040"]))
        if radius_paper is not None:
            ratios.append(Comparison(label, "radius [m]", "L=0.40 sim", radius_paper,
                                     row["sim040"]))
        table.notes.append(note)
        if name == "table7":
            table.notes.append("Segments split where the planned curvature turns left. "
                               "Segment 1's printed left distance 2.214 m equals Case 1's "
                               "centre distance; by symmetry with segment 2 it should read "
                               "about 1.413 m (likely a misprint). The paper's second radius "
                               "0.707 m is not in the table's data.")
        tables[name] = table
    return tables, ratios
