"""Sec. 6.2's following figures, with bounds that belong to neither the planner nor the paper.

A follower *keeps up* when, over the second half of the source's travel (from the moment the
source has covered half its path until it mutes), its median gap to the source is below the
gap it started with: it has closed in and stays closed in while the source drives on. It
*keeps to the source's lane* when, over the same window, its RMS distance from the source's
lane is below one body length (0.35 m, Table 11): a follower farther off than its own length
drives beside the source's path, not on it. The lane is the source's own path extended
backwards along its first heading (a follower still behind the source's start is measured
across the lane, not by the gap along it). It does *not collide* while the centres
stay more than one body length apart. None of these bounds uses the planner's parameters
(its speeds, ramps or stop distance), so each can fail for any planner.
"""

import numpy as np

from orchestrator.reproduce.geometry import distance_to_polyline

__all__ = ["BODY_LENGTH", "LANE_BEHIND", "source_lane", "following_figures"]

BODY_LENGTH = 0.35              # m, Table 11: centres closer than this means a collision
LANE_BEHIND = 10.0              # m, farther than any start in the 7 x 7 m room


def source_lane(source_xy, behind=LANE_BEHIND):
    """The source's path as a polyline, extended ``behind`` m backwards along its first
    heading; every 5th sample (<= 2 cm apart at 0.2 m/s; chord error < 1e-4 m on the
    S-curve's bends) keeps the exact polyline distance cheap."""
    path = np.vstack([source_xy[::5], source_xy[-1:]])
    steps = np.diff(path, axis=0)
    moved = np.nonzero(np.hypot(*steps.T) > 0.0)[0]
    if not len(moved):
        return path
    first = steps[moved[0]] / np.hypot(*steps[moved[0]])
    return np.vstack([path[:1] - behind * first, path])


def _second_half(source_xy, emitting):
    """Samples from the source's half-way point (by arc length) until it mutes."""
    steps = np.hypot(*np.diff(source_xy, axis=0).T)
    travelled = np.concatenate([[0.0], np.cumsum(steps)])
    sounding = np.nonzero(emitting)[0]
    end = int(sounding[-1]) + 1 if len(sounding) else len(travelled)
    if end < 2 or travelled[end - 1] <= 0.0:
        return np.zeros(len(travelled), dtype=bool)
    window = travelled >= 0.5 * travelled[end - 1]
    window[end:] = False
    return window


def following_figures(time, robot_xy, source_xy, emitting):
    """Gap and lane figures of one Sec. 6.2 run.

    Parameters
    ----------
    time : array (n,)
    robot_xy, source_xy : arrays (n, 2)
        True centres, same samples.
    emitting : array (n,) of bool
        True while the source sounds.

    Returns
    -------
    dict
        ``start_gap_m``, ``late_gap_m`` (median gap over the window), ``lane_rms_m`` (RMS
        distance of the robot from the source's lane over the window), ``min_gap_m``; the
        window's figures are None if the source never moved.
    """
    robot_xy, source_xy = np.asarray(robot_xy, float), np.asarray(source_xy, float)
    gap = np.hypot(*(robot_xy - source_xy).T)
    window = _second_half(source_xy, np.asarray(emitting, bool))
    out = {"start_gap_m": float(gap[0]), "min_gap_m": float(gap.min()),
           "late_gap_m": None, "lane_rms_m": None}
    if window.sum() >= 2:
        out["late_gap_m"] = float(np.median(gap[window]))
        distance = distance_to_polyline(robot_xy[window], source_lane(source_xy))
        out["lane_rms_m"] = float(np.sqrt(np.mean(np.square(distance))))
    return out
