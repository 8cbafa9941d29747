"""Each planner's own plan, rebuilt from a run's record, and how far the robot strayed from it.

A path metric against one fixed reference favours the planner whose path the reference is
(robot start -> source start -> source path is rotate-then-go's first leg, so the curvature
arc's designed bulge counted as error). Here each run is measured against the plan its own
planner had in force (``components/planner/``), laid from the robot's true pose:

- ``curvature``: every accepted fix ``(D, theta)`` (a new ``measurement_id`` with ``valid``
  true and ``D`` beyond the stop distance, as the planner takes it) makes a new plan: the arc
  tangent to the heading through the heard target, signed curvature ``2 sin(theta) / D``
  (Eq. 36). A fix at or inside the stop distance makes none: the robot brakes along the arc
  it is on.
- ``rotate_then_go``: a plan is one leg, turn on the spot then straight. A leg starts only at
  rest (fixes that arrive during a leg wait for its end), so a plan starts where the wheel
  references leave zero into a turn (equal and opposite references), or into a drive that
  does not follow a turn; it aims at the target of the latest accepted fix then.

The heard target is ``xy + D (cos(psi + theta), sin(psi + theta))`` from the true pose at
the fix (bearing left positive from the heading ``psi``, components/planner/geometry.py), so
a plan is what the planner meant, in the world frame; odometry, blending and wheel errors show
up as deviation. Each plan continues past its planned end along its own curve (the planner
brakes along it): an arc along its circle up to three quarters of a turn from its start, a
line as a ray; a point behind the start is measured to the start.

:func:`own_plan_rmse` is the RMS of the distance from the true path to the plan in force,
over arc length (each recorded segment weighted by its length, trapezoidal in the squared
distance), so a robot at rest or turning on the spot adds nothing and a robot that follows
its plans exactly scores 0 under either planner.
"""

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Plan", "accepted_fixes", "fix_target", "curvature_plans", "rotate_then_go_plans",
           "own_plans", "distance_to_plan", "own_plan_rmse"]

# Wheel references below this are at rest [m/s]: the planner holds exact zeros there.
_REST_REFERENCE = 1e-9
# A plan's arc is followed at most this far around its circle [rad]: a target abeam gives a
# half turn (bearing +-90 deg), braking along the circle adds little.
_ARC_SPAN = 1.5 * math.pi


@dataclass(frozen=True)
class Plan:
    """A planned path: from ``(x, y)`` in the direction ``heading`` [rad], with signed
    ``curvature`` [1/m] (left positive, 0 for a straight line), in force from sample
    ``start`` until the next plan starts."""

    start: int
    x: float
    y: float
    heading: float
    curvature: float


def accepted_fixes(measurement_id, valid, distance):
    """Sample indices at which the planner takes a new fix: ``measurement_id`` changed since
    the previous sample (from 0 before the first), ``valid`` true, ``distance`` >= 0."""
    ids = np.asarray(measurement_id, dtype=float)
    new = np.diff(ids, prepend=0.0) != 0.0
    return np.nonzero(new & (np.asarray(valid) > 0.5)
                      & (np.asarray(distance, dtype=float) >= 0.0))[0]


def fix_target(xy, heading, distance, bearing, index):
    """World coordinates of the target heard at sample ``index`` from the true pose."""
    direction = heading[index] + bearing[index]
    return (xy[index, 0] + distance[index] * math.cos(direction),
            xy[index, 1] + distance[index] * math.sin(direction))


def curvature_plans(xy, heading, fixes, distance, bearing, stop_distance=0.0):
    """The curvature planner's plans: an arc from each accepted fix beyond the stop distance."""
    plans = []
    for i in fixes:
        d = float(distance[i])
        if d <= max(stop_distance, 1e-9):
            continue
        plans.append(Plan(int(i), float(xy[i, 0]), float(xy[i, 1]), float(heading[i]),
                          2.0 * math.sin(float(bearing[i])) / d))
    return plans


def _episodes(v_ref_left, v_ref_right):
    """``(start, turning)`` of each run of samples with a non-zero wheel reference."""
    left, right = np.asarray(v_ref_left, dtype=float), np.asarray(v_ref_right, dtype=float)
    moving = (np.abs(left) > _REST_REFERENCE) | (np.abs(right) > _REST_REFERENCE)
    starts = np.nonzero(moving & ~np.concatenate(([False], moving[:-1])))[0]
    return [(int(s), bool(left[s] * right[s] < 0.0)) for s in starts]


def rotate_then_go_plans(xy, heading, fixes, distance, bearing, v_ref_left, v_ref_right,
                         stop_distance=0.0):
    """Rotate-then-go's plans: one straight leg from each leg start towards the target of the
    latest accepted fix then (see the module docstring)."""
    plans, previous_turning = [], False
    for start, turning in _episodes(v_ref_left, v_ref_right):
        leg_start = turning or not previous_turning
        previous_turning = turning
        if not leg_start:
            continue                     # the drive after this leg's turn
        heard = [i for i in fixes[fixes <= start] if distance[i] > max(stop_distance, 1e-9)]
        if not heard:
            continue
        tx, ty = fix_target(xy, heading, distance, bearing, heard[-1])
        x, y = float(xy[start, 0]), float(xy[start, 1])
        if math.hypot(tx - x, ty - y) == 0.0:
            continue
        plans.append(Plan(start, x, y, math.atan2(ty - y, tx - x), 0.0))
    return plans


def own_plans(mode, xy, heading, measurement_id, valid, distance, bearing, v_ref_left=None,
              v_ref_right=None, stop_distance=0.0):
    """The plans of the run's own planner ``mode`` (``curvature`` or ``rotate_then_go``)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    heading, distance, bearing = (np.asarray(a, dtype=float) for a in (heading, distance,
                                                                       bearing))
    fixes = accepted_fixes(measurement_id, valid, distance)
    if mode == "curvature":
        return curvature_plans(xy, heading, fixes, distance, bearing, stop_distance)
    if mode == "rotate_then_go":
        if v_ref_left is None or v_ref_right is None:
            raise ValueError("rotate_then_go plans need the wheel references (legs start at "
                             "rest)")
        return rotate_then_go_plans(xy, heading, fixes, distance, bearing, v_ref_left,
                                    v_ref_right, stop_distance)
    raise ValueError(f"mode = {mode!r}; valid choices: curvature, rotate_then_go")


def distance_to_plan(points, plan):
    """Distance [m] of each of ``points`` ``(m, 2)`` from a plan's path (module docstring)."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    return _distance_to_plans(points, plan.x, plan.y, plan.heading, plan.curvature)


def _distance_to_plans(points, x, y, heading, curvature):
    """:func:`distance_to_plan`, point by point: the plan's start ``(x, y)``, ``heading`` and
    ``curvature`` are scalars or one per point (one numpy pass for every plan of a run)."""
    x, y, heading, curvature = (np.broadcast_to(np.asarray(a, dtype=float), len(points))
                                for a in (x, y, heading, curvature))
    rx, ry = points[:, 0] - x, points[:, 1] - y
    to_start = np.hypot(rx, ry)
    ux, uy = np.cos(heading), np.sin(heading)
    straight = np.abs(curvature) < 1e-12
    # a line: across it ahead of the start, to the start behind it
    line = np.where(rx * ux + ry * uy >= 0.0, np.abs(ux * ry - uy * rx), to_start)
    # an arc (signed radius: the centre lies left for curvature > 0)
    radius = 1.0 / np.where(straight, 1.0, curvature)
    cx, cy = x - radius * uy, y + radius * ux
    fx, fy = points[:, 0] - cx, points[:, 1] - cy
    start_angle = np.arctan2(y - cy, x - cx)
    turned = np.mod(np.sign(curvature) * (np.arctan2(fy, fx) - start_angle), 2.0 * math.pi)
    on_arc = np.abs(np.hypot(fx, fy) - np.abs(radius))
    end_angle = start_angle + np.copysign(_ARC_SPAN, curvature)
    ex = cx + np.abs(radius) * np.cos(end_angle)
    ey = cy + np.abs(radius) * np.sin(end_angle)
    off_arc = np.minimum(to_start, np.hypot(points[:, 0] - ex, points[:, 1] - ey))
    return np.where(straight, line, np.where(turned <= _ARC_SPAN, on_arc, off_arc))


def own_plan_rmse(xy, plans):
    """RMS distance [m] of the path from the plan in force, over arc length.

    Segment ``j`` (samples ``j`` to ``j + 1``) is measured against the latest plan started at
    or before sample ``j``: ``sqrt(sum l_j (d_j^2 + d_{j+1}^2) / 2 / sum l_j)`` over the
    segments after the first plan. None if the robot did not move under any plan.

    Parameters
    ----------
    xy : (n, 2) array
        The true centre positions.
    plans : list of Plan
        In order of their start samples (:func:`own_plans`).
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    lengths = np.hypot(*np.diff(xy, axis=0).T)
    # every (plan, sample) pair at once: plan k measures samples start_k .. start_k+1
    # (the boundary sample twice, once as the end of k's segments, once as k+1's start)
    samples, owner = [], []
    for k, plan in enumerate(plans):
        last = plans[k + 1].start if k + 1 < len(plans) else len(xy) - 1
        if last > plan.start:
            samples.append(np.arange(plan.start, last + 1))
            owner.append(np.full(last + 1 - plan.start, k))
    if not samples:
        return None
    samples, owner = np.concatenate(samples), np.concatenate(owner)
    attribute = {name: np.array([getattr(p, name) for p in plans], dtype=float)[owner]
                 for name in ("x", "y", "heading", "curvature")}
    d = _distance_to_plans(xy[samples], **attribute)
    segment = owner[:-1] == owner[1:]            # both ends under one plan
    pieces = lengths[samples[:-1][segment]]
    weighted = float(np.sum(pieces * 0.5 * (d[:-1][segment] ** 2 + d[1:][segment] ** 2)))
    total = float(np.sum(pieces))
    if total == 0.0:
        return None
    return math.sqrt(weighted / total)
