"""Path geometry of a run: length, arc-length resampling, ideal paths, fitted circles, arrival.

The figures a study measures on a recorded path (used by :mod:`orchestrator.reproduce`):
path length, the RMS distance of a path from a reference polyline sampled by arc length, the
ideal tangent-arc path of the curvature planner through its targets (Eq. 36), the radius of
a least-squares circle, the time from which the robot stays at rest, the arrival at a target
(:func:`arrival_at_target`: first at rest near it), and the inward offset of a follower's path
at the apexes of an S-curve.
"""

import math
from dataclasses import dataclass

import numpy as np

from components.common.errors import ConfigError
from orchestrator.run.metrics import distance_to_polyline  # the one polyline distance

__all__ = ["REST_POSITION", "REST_HEADING", "REST_SETTLE", "RESAMPLE_SPACING",
           "ARRIVAL_TOLERANCE", "REST_SPEED", "REST_HOLD", "Arrival", "path_length",
           "resample_path", "distance_to_polyline", "path_rmse", "tangent_arc_path",
           "circle_fit_radius", "arrival_time", "arrival_at_target", "apex_offsets"]

# "Arrived": the true pose stays within 5 mm and 0.01 rad (0.6 deg) of the final pose for at
# least the last second. A wheel rocking by one encoder count (0.52 mm) at standstill stays far
# inside; a creep of 0.02 rad/s (seen with a standstill limit cycle) leaves the band in 0.5 s.
REST_POSITION = 0.005           # m
REST_HEADING = 0.01             # rad
REST_SETTLE = 1.0               # s
RESAMPLE_SPACING = 0.005        # m; path RMSE samples the path every 5 mm of arc length
# Arrival at a target (arrival_at_target). "At rest": over REST_HOLD the centre stays within
# REST_SPEED x REST_HOLD = 5 mm of where it was (a mean speed under 1 cm/s: 2.5 % of the
# 0.4 m/s cruise, under half an encoder count of 0.52 mm per 20 ms sample) and, where the
# heading is given, the heading within REST_HEADING. Net motion over the hold, not the
# instantaneous wheel speed: at standstill the wheels rock by one count with rim speeds up to
# 13 mm/s (measured in the study's runs) while the centre stays put. 0.5 s is longer than the
# body's mechanical time constant (0.39 s, docs/plant.md) and a reversal cannot pass for rest:
# braking at the planner's 0.4 m/s^2 moves the centre 50 mm in the 0.5 s after it stops.
ARRIVAL_TOLERANCE = 0.10        # m; the callers' default (see measures.arrival_figures)
REST_SPEED = 0.01               # m/s
REST_HOLD = 0.5                 # s


def path_length(xy):
    """Length [m] of a polyline given as an ``(n, 2)`` array of points (0 for n < 2)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    if len(xy) < 2:
        return 0.0
    return float(np.sum(np.hypot(*np.diff(xy, axis=0).T)))


def resample_path(xy, spacing):
    """Points every ``spacing`` metres of arc length along a polyline (ends included).

    Resampling by arc length weights each piece of the path by its length, not by the time
    spent on it, so a robot at rest or ramping slowly does not dominate a path RMSE.
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    if not spacing > 0:
        raise ConfigError(f"spacing = {spacing!r}: must be a number > 0")
    cumulative = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))))
    if len(xy) < 2 or cumulative[-1] == 0.0:
        return xy[:1].copy()
    keep = np.concatenate(([True], np.diff(cumulative) > 0))
    xy, cumulative = xy[keep], cumulative[keep]
    count = max(2, int(math.ceil(cumulative[-1] / spacing)) + 1)
    s = np.linspace(0.0, cumulative[-1], count)
    return np.column_stack([np.interp(s, cumulative, xy[:, 0]), np.interp(s, cumulative, xy[:, 1])])


def path_rmse(xy, reference, spacing=RESAMPLE_SPACING):
    """RMS distance [m] of a path from a reference polyline, sampled by arc length.

    Parameters
    ----------
    xy : (n, 2) array
        The driven path (e.g. the robot's true positions over time).
    reference : (m, 2) array
        The ideal path as a polyline (see :func:`tangent_arc_path`).
    spacing : float
        Arc-length spacing [m] of the samples of ``xy``.
    """
    samples = resample_path(xy, spacing)
    return float(np.sqrt(np.mean(distance_to_polyline(samples, reference) ** 2)))


def tangent_arc_path(start, heading, targets, points_per_arc=4001):
    """Polyline of the ideal curvature path: tangent arcs through successive targets.

    From the pose ``(start, heading)``, the arc tangent to the heading through the first
    target has signed curvature ``kappa = 2 sin(theta) / D`` (Eq. 36) and turns the heading by
    ``2 theta``; the next arc starts there with that heading. A target straight ahead gives a
    segment.

    Parameters
    ----------
    start : (2,) sequence
        Start point [m].
    heading : float
        Start heading [rad], counter-clockwise from +x.
    targets : sequence of (2,) sequences
        Points the path passes through, in order.
    points_per_arc : int
        Vertices per arc; 4001 keeps the chord error of a 0.7 m arc under 1e-7 m.

    Returns
    -------
    (m, 2) array
    """
    x, y = (float(v) for v in start)
    pieces = [np.array([[x, y]])]
    for tx, ty in targets:
        dx, dy = tx - x, ty - y
        distance = math.hypot(dx, dy)
        if distance == 0.0:
            continue
        theta = math.atan2(dy, dx) - heading
        theta = math.atan2(math.sin(theta), math.cos(theta))
        kappa = 2.0 * math.sin(theta) / distance
        if abs(kappa) < 1e-12:
            pieces.append(np.array([[tx, ty]]))
        else:
            radius = 1.0 / kappa      # signed: the centre lies to the left for kappa > 0
            cx, cy = x - radius * math.sin(heading), y + radius * math.cos(heading)
            angles = np.linspace(0.0, 2.0 * theta, points_per_arc)[1:]
            # a point at heading h on the circle: centre + radius (sin h, -cos h)
            h = heading + angles
            pieces.append(np.column_stack([cx + radius * np.sin(h), cy - radius * np.cos(h)]))
        heading = heading + 2.0 * theta
        x, y = float(tx), float(ty)
    return np.vstack(pieces)


def circle_fit_radius(xy):
    """Radius [m] of the least-squares circle through points (Kasa's algebraic fit).

    Solves ``x^2 + y^2 + a x + b y + c = 0`` in the least-squares sense; exact for points on
    a circle. Returns ``inf`` for collinear points.
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    if len(xy) < 3:
        return math.inf
    x, y = xy[:, 0], xy[:, 1]
    # centring first keeps the normal equations well conditioned for large radii
    mx, my = x.mean(), y.mean()
    u, v = x - mx, y - my
    spread = np.linalg.svd(np.column_stack([u, v]), compute_uv=False)
    if spread[0] == 0.0 or spread[1] <= 1e-9 * spread[0]:
        return math.inf             # collinear: the normal equations are singular
    system = np.column_stack([u, v, np.ones_like(u)])
    (a, b, c), *_ = np.linalg.lstsq(system, -(u * u + v * v), rcond=None)
    radius2 = 0.25 * (a * a + b * b) - c
    scale = max(float(np.max(np.hypot(u, v))), 1e-12)
    if radius2 <= 0 or math.sqrt(radius2) > 1e6 * scale:
        return math.inf
    return float(math.sqrt(radius2))


def arrival_time(time, xy, heading, position_tolerance=REST_POSITION,
                 heading_tolerance=REST_HEADING, settle=REST_SETTLE):
    """Time [s] from which the robot stays at its final pose, or None if it did not settle.

    The robot has arrived at the earliest sample time from which its position stays within
    ``position_tolerance`` of the final position and its heading within ``heading_tolerance``
    of the final heading. Net displacement is used, not sample-to-sample speed, so that a
    standstill limit cycle of one encoder count (a wheel rocking by a fraction of a mm) does
    not count as driving, while a slow creep or a late correcting leg does.

    Parameters
    ----------
    time : (n,) array
        Sample times [s].
    xy : (n, 2) array
        True centre positions [m].
    heading : (n,) array
        True heading [rad].
    position_tolerance : float
        Radius [m] around the final position.
    heading_tolerance : float
        Band [rad] around the final heading.
    settle : float
        The robot must have stayed put at least this long [s] before the end of the record,
        else it has not arrived (the run was too short, or it creeps).

    Returns
    -------
    float or None
        The arrival time; 0.0 if it never moved.
    """
    time = np.asarray(time, dtype=float)
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    heading = np.unwrap(np.asarray(heading, dtype=float))
    if len(time) < 2:
        return None
    away = ((np.hypot(*(xy - xy[-1]).T) > position_tolerance)
            | (np.abs(heading - heading[-1]) > heading_tolerance))
    outside = np.nonzero(away)[0]
    if len(outside) == 0:
        return 0.0
    arrived = float(time[outside[-1] + 1]) if outside[-1] + 1 < len(time) else None
    if arrived is None or time[-1] - arrived < settle:
        return None
    return arrived


@dataclass(frozen=True)
class Arrival:
    """When and how a robot arrived at its target (None fields when it never did).

    Attributes
    ----------
    arrived : bool
    time : float or None
        The first sample time at which it was within the tolerance and at rest [s].
    error : float or None
        ``|distance to the target - stop distance|`` at that time [m].
    drift : float or None
        Distance from the arrival position to the final position [m]: creep after arrival.
    """

    arrived: bool
    time: object = None
    error: object = None
    drift: object = None

    def figures(self):
        """``arrived`` (1.0 / 0.0), ``arrival_s``, ``error_at_arrival_m``,
        ``drift_after_arrival_m``: the per-run figures of :mod:`.measures`."""
        return {"arrived": 1.0 if self.arrived else 0.0, "arrival_s": self.time,
                "error_at_arrival_m": self.error, "drift_after_arrival_m": self.drift}


def arrival_at_target(time, xy, target, tolerance=ARRIVAL_TOLERANCE, stop_distance=0.0,
                      heading=None, rest_speed=REST_SPEED, hold=REST_HOLD,
                      heading_tolerance=REST_HEADING):
    """First time the robot is within ``tolerance`` of where it should stop, and at rest.

    At sample ``i`` the robot has arrived if, for every sample ``j`` with
    ``time[i] <= time[j] <= time[i] + hold``: its distance to the target differs from
    ``stop_distance`` by at most ``tolerance``, its centre lies within ``rest_speed * hold``
    of ``xy[i]`` and (if ``heading`` is given) its heading within ``heading_tolerance`` of
    ``heading[i]``; the record must cover the whole hold. An overshoot that turns back is
    not an arrival (the centre does not stay put at the turn), nor a pass through the
    tolerance at speed; a robot that creeps on after arriving is reported by its drift.

    Parameters
    ----------
    time : (n,) array
        Sample times [s].
    xy : (n, 2) array
        True centre positions [m].
    target : (2,) or (n, 2) array
        The target, fixed or per sample [m].
    tolerance : float
        Band [m] around the stop distance (the caller's; the planner may stop short).
    stop_distance : float
        Distance [m] from the target at which the planner means to stop.
    heading : (n,) array, optional
        True heading [rad]; with it, turning on the spot is not rest.
    rest_speed, hold, heading_tolerance : float
        The rest test (see the module constants).

    Returns
    -------
    Arrival
    """
    time = np.asarray(time, dtype=float)
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    target = np.broadcast_to(np.asarray(target, dtype=float), xy.shape)
    if len(time) < 2:
        return Arrival(False)
    error = np.abs(np.hypot(*(xy - target).T) - stop_distance)
    turned = None if heading is None else np.unwrap(np.asarray(heading, dtype=float))
    ok = error <= tolerance
    ends = np.searchsorted(time, time + hold - 1e-9 * max(hold, 1.0), side="left")
    ok &= ends < len(time)                    # the record covers the hold
    radius = rest_speed * hold
    longest = int(np.max(ends[ok] - np.nonzero(ok)[0])) if ok.any() else 0
    index = np.arange(len(time))
    for k in range(1, longest + 1):
        if not ok.any():
            break
        j = np.minimum(index + k, len(time) - 1)
        inside = index + k <= ends
        still = ((error[j] <= tolerance) & (np.hypot(*(xy[j] - xy).T) <= radius))
        if turned is not None:
            still &= np.abs(turned[j] - turned) <= heading_tolerance
        ok &= still | ~inside
    arrived = np.nonzero(ok)[0]
    if len(arrived) == 0:
        return Arrival(False)
    i = int(arrived[0])
    return Arrival(True, float(time[i]), float(error[i]), float(np.hypot(*(xy[-1] - xy[i]))))


def apex_offsets(source_xy, robot_xy, min_lateral=0.05):
    """Signed offsets of the robot's path inside the source's path at the source's apexes.

    The source's forward axis runs from its first to its last point; its lateral offset
    (left positive) from that axis has a largest and a smallest value, the apexes of an
    S-curve. At each apex with ``|lateral| >= min_lateral`` the robot's lateral offset at the
    same forward coordinate (linear interpolation at its first crossing) is compared with it.

    Returns
    -------
    list of dict
        Per apex: ``forward_m``, ``source_lateral_m``, ``robot_lateral_m`` (None if the robot
        never got there) and ``inward_offset_m`` = sign(source lateral) (source lateral - robot
        lateral): positive when the robot is nearer the start line, i.e. inside the curve (at
        an apex the path's centre of curvature lies towards the start line).
    """
    source_xy = np.asarray(source_xy, dtype=float).reshape(-1, 2)
    robot_xy = np.asarray(robot_xy, dtype=float).reshape(-1, 2)
    start = source_xy[0]
    axis = source_xy[-1] - start
    length = float(np.hypot(*axis))
    if length == 0.0:
        return []
    forward_unit = axis / length

    def frame(points):
        relative = points - start
        forward = relative @ forward_unit
        lateral = forward_unit[0] * relative[:, 1] - forward_unit[1] * relative[:, 0]
        return forward, lateral

    source_forward, source_lateral = frame(source_xy)
    robot_forward, robot_lateral = frame(robot_xy)
    apexes = []
    for index in sorted({int(np.argmax(source_lateral)), int(np.argmin(source_lateral))}):
        lateral = float(source_lateral[index])
        if abs(lateral) < min_lateral:
            continue
        forward = float(source_forward[index])
        crossing = np.nonzero((robot_forward[:-1] <= forward) & (robot_forward[1:] > forward))[0]
        robot_at = None
        if len(crossing):
            i = int(crossing[0])
            fraction = (forward - robot_forward[i]) / (robot_forward[i + 1] - robot_forward[i])
            step = robot_lateral[i + 1] - robot_lateral[i]
            robot_at = float(robot_lateral[i] + fraction * step)
        apexes.append({
            "forward_m": forward,
            "source_lateral_m": lateral,
            "robot_lateral_m": robot_at,
            "inward_offset_m": (None if robot_at is None
                                else math.copysign(1.0, lateral) * (lateral - robot_at)),
        })
    return apexes
