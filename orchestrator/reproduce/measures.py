"""Per-run figures: what each table row measures, from one run's recorded traces.

Every function takes a :class:`~orchestrator.reproduce.runs.RunRecord` and returns a dict of
plain numbers (None where the run cannot give one, e.g. a robot that did not settle).
The definitions are in :data:`DEFINITIONS` and printed in the report.
"""

import math

import numpy as np

from orchestrator.reproduce.geometry import (ARRIVAL_TOLERANCE, apex_offsets, arrival_at_target,
                                             arrival_time, circle_fit_radius, path_length,
                                             path_rmse)
from orchestrator.reproduce.plans import own_plan_rmse, own_plans

__all__ = ["DEFINITIONS", "ENCODER_PPR", "NOMINAL_WHEEL_RADIUS", "SLIP_THRESHOLD",
           "arrival_figures", "slip_figures", "wheel_profile", "tracking_figures",
           "fix_figures", "first_heading_change", "own_plan_figure"]

ENCODER_PPR = 728               # counts per wheel revolution (docs/plant.md)
NOMINAL_WHEEL_RADIUS = 0.06     # m; the robot's own conversion of counts to distance
# A wheel "slips" while |slip ratio| exceeds 5 %: well above the 0.7-1.2 % peak of the rolling
# contact at mu >= 0.1 (measured), well below a spinning wheel (slip ratio ~ 1).
SLIP_THRESHOLD = 0.05

DEFINITIONS = {
    "distance_m": "length of the robot's true path (sum of distances between 20 ms samples "
                  "of plant.x, plant.y), the whole run",
    "error_m": "distance from the robot's true centre to the (final) source position at the "
               "end of the run",
    "settle_s": "time from t = 0 until the robot's true pose stays within 5 mm and 0.01 rad "
                "of its final pose, for at least the last 1 s of the run (else missing)",
    "arrived": "1 if the robot arrived (see arrival_s), else 0: runs that never arrive are "
               "counted, their arrival figures missing",
    "arrival_s": "first time at which the robot's true centre is within the tolerance (0.10 m "
                 "unless the table states another) of its planned stop (the target, or the "
                 "stop distance short of it) and at rest: for the next 0.5 s it stays within "
                 "5 mm of that point (a mean speed under 1 cm/s), its heading within 0.01 rad "
                 "and the whole 0.5 s within the tolerance (else missing)",
    "error_at_arrival_m": "|distance from the robot's true centre to the target - stop "
                          "distance| at the arrival time",
    "drift_after_arrival_m": "distance from the robot's true centre at arrival to its final "
                             "position: creep after arriving",
    "rmse_own_plan_m": "RMS distance of the robot's true path, over arc length, from the plan "
                       "its own planner had in force, laid from the true pose: curvature, the "
                       "arc tangent to the heading through the target heard at the latest "
                       "accepted fix (Eq. 36); rotate-then-go, the straight leg from where "
                       "the leg started at rest towards the target heard last before it (it "
                       "turns on the spot first); each plan continues along its own curve "
                       "past its end. 0 for a robot that follows its plans exactly, under "
                       "either planner",
    "radius_planner_m": "planner.radius at the first accepted fix (Eq. 36 from the heard "
                        "distance and bearing)",
    "radius_fit_m": "radius of the least-squares circle (Kasa fit) through the robot's true "
                    "path while moving: the radius actually driven",
    "rmse_path_m": "RMS distance of the true path, resampled every 5 mm of arc length, from the "
                   "ideal path of the mode (segment for rotate-then-go; tangent arc(s) through "
                   "the target(s) for curvature)",
    "rmse_speed_m_s": "RMS of (planner wheel reference - true rim speed), both wheels, while "
                      "the robot moves",
    "turn_error_deg": "|true heading change before the centre first moves 5 mm + 45 deg|: the "
                      "error of rotate-then-go's turn on the spot towards the target",
    "peak_slip": "largest |longitudinal slip ratio| of either wheel over the run",
    "slip_time_s": f"time during which either wheel's |slip ratio| > {SLIP_THRESHOLD}",
    "cruise_m_s": "median true rim speed while the planner's wheel reference is within 1 % of "
                  "its plateau (the median of its held, non-zero values) in that segment",
    "ramp_m_s2": "|least-squares slope| of the true rim speed while the wheel reference covers "
                 "10 % to 90 % of its first change to the plateau (from rest, or from the "
                 "previous arc's speed)",
    "encoder_m": "encoder counts of the segment x 2 pi r / 728 with the nominal r = 0.06 m "
                 "(the robot's own odometry)",
    "gap_m": "distance between the robot's and the source's true centres",
    "rmse_source_path_m": "RMS distance of the robot's true path (5 mm arc-length samples) from "
                          "the reference robot start -> source start -> source path",
    "inward_offset_m": "at each apex of the source's S-curve, the source's lateral offset minus "
                       "the robot's at the same forward coordinate, signed towards the curve's "
                       "centre (> 0: the robot runs inside); the smaller of the two apexes",
    "fix_range_rmse_m": "RMS of (heard - true) range over the run's valid fixes, each fix once "
                        "(localizer.distance - localizer.true_distance where measurement_id "
                        "has just grown and valid is true)",
    "fix_range_bias_m": "mean of (heard - true) range over the same fixes",
    "fix_bearing_rmse_deg": "RMS of (heard - true) bearing over the same fixes, wrapped to "
                            "+-180 deg",
    "fix_valid_fraction": "valid fixes / fix attempts while the source sounds "
                          "(localizer.measurement_id / localizer.fix_attempts at the last "
                          "sounding sample)",
}


def first_heading_change(xy, heading, moved=0.005):
    """True heading change [deg] before the centre first moves 5 mm (a turn on the spot)."""
    away = np.nonzero(np.hypot(*(xy - xy[0]).T) > moved)[0]
    if len(away) == 0:
        return None
    turned = np.unwrap(np.asarray(heading, dtype=float))
    return float(np.degrees(turned[away[0]] - turned[0]))


def slip_figures(run):
    """Peak |slip ratio| and the time either wheel slips (``SLIP_THRESHOLD``)."""
    data = run.data
    slip = np.maximum(np.abs(data["plant.slip_left"]), np.abs(data["plant.slip_right"]))
    dt = float(np.median(np.diff(data["time"]))) if len(data["time"]) > 1 else 0.0
    return {"peak_slip": float(slip.max()),
            "slip_time_s": float(np.count_nonzero(slip > SLIP_THRESHOLD) * dt)}


def _mode(run, mode):
    return mode or (run.parameters or {}).get("planner.mode") or "curvature"


def own_plan_figure(run, mode=None, stop_distance=0.0):
    """``rmse_own_plan_m`` of a run (:mod:`orchestrator.reproduce.plans`); ``mode`` defaults
    to the run's ``planner.mode`` parameter, else the scenarios' curvature."""
    data = run.data
    plans = own_plans(_mode(run, mode), run.xy(), data["plant.heading"],
                      data["localizer.measurement_id"], data["localizer.valid"],
                      data["localizer.distance"], data["localizer.bearing"],
                      data["planner.v_ref_left"], data["planner.v_ref_right"], stop_distance)
    return own_plan_rmse(run.xy(), plans)


def arrival_figures(run, reference, tolerance=ARRIVAL_TOLERANCE, stop_distance=0.0, mode=None):
    """Tables 1-3 and 8-9: distance, final error, arrival, path RMSEs, radii, turn, slip.

    ``tolerance`` and ``stop_distance`` define the arrival (:func:`.geometry.arrival_at_target`,
    the target being the source's final position); ``mode`` the planner whose own plans
    ``rmse_own_plan_m`` measures.
    """
    data, xy = run.data, run.xy()
    source = run.source_xy()
    arrival = arrival_at_target(data["time"], xy, source[-1], tolerance, stop_distance,
                                heading=data["plant.heading"])
    moving = np.hypot(*(xy - xy[0]).T) > 1e-3
    radius = data["planner.radius"]
    first_fix = np.nonzero((radius > 0) & (radius < 1e5))[0]
    speed_error = np.concatenate([
        (data["planner.v_ref_left"] - data["plant.rim_speed_left"])[moving],
        (data["planner.v_ref_right"] - data["plant.rim_speed_right"])[moving]])
    turn = first_heading_change(xy, data["plant.heading"])
    return {
        "distance_m": path_length(xy),
        "error_m": float(np.hypot(*(xy[-1] - source[-1]))),
        "settle_s": arrival_time(data["time"], xy, data["plant.heading"]),
        **arrival.figures(),
        "rmse_path_m": path_rmse(xy, reference),
        "rmse_own_plan_m": own_plan_figure(run, mode, stop_distance),
        "rmse_speed_m_s": (float(np.sqrt(np.mean(speed_error ** 2)))
                           if len(speed_error) else None),
        "radius_planner_m": float(radius[first_fix[0]]) if len(first_fix) else None,
        "radius_fit_m": (circle_fit_radius(xy[moving]) if moving.sum() >= 3 else None),
        "turn_deg": turn,
        "turn_error_deg": None if turn is None else abs(turn + 45.0),
        **slip_figures(run),
    }


def _segment_bounds(run, segments):
    """Sample ranges of the arcs: one, or split where the planned curvature changes sign."""
    n = len(run.data["time"])
    if segments == 1:
        return [(0, n)]
    curvature = run.data["planner.curvature"]
    turned = np.nonzero(curvature > 1e-6)[0]         # segment 2 turns left (Case 2)
    if len(turned) == 0:
        return [(0, n), (n, n)]
    return [(0, int(turned[0])), (int(turned[0]), n)]


def _plateau(reference):
    """The wheel reference's cruise value in a segment: the median of the samples where it is
    held (changes by < 0.1 mm/s per sample, far below a ramp's 8 mm/s at 0.4 m/s^2 and 20 ms)
    and not at rest; None if it is never held."""
    held = np.abs(np.diff(reference)) < 1e-4
    values = reference[1:][held & (np.abs(reference[1:]) > 1e-3)]
    return float(np.median(values)) if len(values) else None


def _ramp_slope(time, reference, speed, plateau):
    """|slope| of the rim speed over 10-90 % of the reference's first change to its plateau
    (from rest in segment 1, from the previous arc's speed in segment 2)."""
    change = plateau - reference[0]
    if abs(change) < 1e-3:
        return None                 # the segment starts at its cruise speed: no ramp
    progress = (reference - reference[0]) / change
    reached = np.nonzero(progress >= 0.9)[0]
    if len(reached) == 0:
        return None
    part = np.nonzero(progress[:reached[0] + 1] >= 0.1)[0]
    if len(part) < 3:
        return None
    return float(abs(np.polyfit(time[part], speed[part], 1)[0]))


def wheel_profile(run, segments=1):
    """Tables 6-7 from the simulated wheels: cruise speed, ramp acceleration, encoder distance.

    Returns
    -------
    list of dict
        One per segment, keys ``{left,right}_{cruise_m_s,ramp_m_s2,encoder_m}``.
    """
    data, time = run.data, run.data["time"]
    per_count = 2.0 * math.pi * NOMINAL_WHEEL_RADIUS / ENCODER_PPR
    profiles = []
    for start, stop in _segment_bounds(run, segments):
        figures = {}
        for side in ("left", "right"):
            reference = data[f"planner.v_ref_{side}"][start:stop]
            speed = data[f"plant.rim_speed_{side}"][start:stop]
            counts = data[f"plant.encoder_{side}"]
            if stop - start < 3:
                figures.update({f"{side}_cruise_m_s": None, f"{side}_ramp_m_s2": None,
                                f"{side}_encoder_m": None})
                continue
            plateau = _plateau(reference)
            if plateau is None:
                figures.update({f"{side}_cruise_m_s": None, f"{side}_ramp_m_s2": None})
            else:
                cruising = np.abs(reference - plateau) <= 0.01 * abs(plateau)
                figures[f"{side}_cruise_m_s"] = float(np.median(speed[cruising]))
                figures[f"{side}_ramp_m_s2"] = _ramp_slope(time[start:stop], reference, speed,
                                                           plateau)
            last = min(stop, len(counts)) - 1
            figures[f"{side}_encoder_m"] = float((counts[last] - counts[start]) * per_count)
        profiles.append(figures)
    return profiles


def fix_figures(run):
    """How well the localizer heard: range and bearing errors of the fixes, valid share."""
    data = run.data
    ids, valid = data["localizer.measurement_id"], data["localizer.valid"] > 0.5
    new = valid & (np.diff(ids, prepend=0.0) > 0)
    range_error = (data["localizer.distance"] - data["localizer.true_distance"])[new]
    bearing_error = np.degrees(np.angle(np.exp(1j * (data["localizer.bearing"]
                                                     - data["localizer.true_bearing"])[new])))
    sounding = np.nonzero(data["source.emitting"] > 0.5)[0]
    last = sounding[-1] if len(sounding) else len(ids) - 1
    attempts = data["localizer.fix_attempts"][last]
    return {
        "fix_range_rmse_m": (float(np.sqrt(np.mean(range_error ** 2)))
                             if len(range_error) else None),
        "fix_range_bias_m": float(range_error.mean()) if len(range_error) else None,
        "fix_bearing_rmse_deg": (float(np.sqrt(np.mean(bearing_error ** 2)))
                                 if len(bearing_error) else None),
        "fix_valid_fraction": float(ids[last] / attempts) if attempts > 0 else None,
    }


def tracking_figures(run, stop_distance, mode=None):
    """Sec. 6.2: gaps, path RMSEs (from the source's path, from the own plans), mute time,
    apexes, slip; ``mode`` as in :func:`own_plan_figure`."""
    data, xy = run.data, run.xy()
    source = run.source_xy()
    gap = np.hypot(*(xy - source).T)
    emitting = data["source.emitting"] > 0.5
    silent = np.nonzero(~emitting)[0]
    mute = float(data["time"][silent[0]]) if len(silent) else None
    stays_silent = bool(len(silent)) and not emitting[silent[0]:].any()
    # every 5th source sample (<= 2 cm apart at 0.2 m/s; chord error < 1e-4 m on the S-curve's
    # bends) keeps the exact polyline distance cheap
    reference = np.vstack([xy[:1], source[::5], source[-1:]])
    apexes = apex_offsets(source, xy)
    offsets = [a["inward_offset_m"] for a in apexes]
    return {
        "final_gap_m": float(gap[-1]),
        "final_gap_error_m": float(abs(gap[-1] - stop_distance)),
        "max_gap_m": float(gap.max()),
        "min_gap_m": float(gap.min()),
        "rmse_source_path_m": path_rmse(xy, reference),
        "rmse_own_plan_m": own_plan_figure(run, mode, stop_distance),
        "mute_s": mute,
        "stays_silent": 1.0 if stays_silent else 0.0,
        "settle_s": arrival_time(data["time"], xy, data["plant.heading"]),
        "inward_offset_m": (min(offsets) if offsets and None not in offsets else None),
        **slip_figures(run),
    }
