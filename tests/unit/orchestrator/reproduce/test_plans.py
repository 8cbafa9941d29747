"""The path metric against each planner's own plan, on synthetic runs with known answers."""

import math

import numpy as np
import pytest

from orchestrator.reproduce.geometry import path_length
from orchestrator.reproduce.plans import (Plan, accepted_fixes, distance_to_plan,
                                          own_plan_rmse, own_plans)

DT, V, FIX_EVERY = 0.02, 0.3, 5          # 20 ms samples, 0.3 m/s, a fix every 100 ms


def moving_target(t):
    """A source that starts 1 m away, 45 deg to the right, and drives on at 0.18 m/s."""
    return np.array([math.sqrt(0.5) + 0.1 * t, math.sqrt(0.5) + 0.15 * t])


class Record:
    """Samples of a synthetic run: pose, fixes (held between fixes), wheel references."""

    def __init__(self, fix_every=FIX_EVERY):
        self.fix_every = fix_every
        self.xy, self.heading, self.ids, self.distance, self.bearing = [], [], [], [], []
        self.left, self.right = [], []
        self.fix_id, self.heard = 0, (0.0, 0.0)

    def add(self, x, y, h, left=0.0, right=0.0, target=None):
        n = len(self.xy)
        if n % self.fix_every == 0:            # a fix from the true pose, exact
            target = moving_target(n * DT) if target is None else target
            dx, dy = target[0] - x, target[1] - y
            self.fix_id += 1
            bearing = math.atan2(dy, dx) - h
            self.heard = (math.hypot(dx, dy), math.atan2(math.sin(bearing), math.cos(bearing)))
        self.xy.append((x, y))
        self.heading.append(h)
        self.ids.append(self.fix_id)
        self.distance.append(self.heard[0])
        self.bearing.append(self.heard[1])
        self.left.append(left)
        self.right.append(right)

    def rmse(self, mode, stop_distance=0.0):
        plans = own_plans(mode, self.xy, self.heading, self.ids, np.ones(len(self.ids)),
                          self.distance, self.bearing, self.left, self.right, stop_distance)
        return own_plan_rmse(self.xy, plans), plans


def test_a_curvature_run_that_follows_each_new_arc_exactly_scores_zero():
    run, (x, y, h) = Record(), (0.0, 0.0, 0.5 * math.pi)
    kappa = 0.0
    for n in range(200):                       # 4 s, 40 fixes, the target moving throughout
        run.add(x, y, h, V, V)
        if n % FIX_EVERY == 0:                 # the planner's new arc (Eq. 36)
            kappa = 2.0 * math.sin(run.bearing[-1]) / run.distance[-1]
        s = V * DT                             # drive exactly along the arc
        x += (math.sin(h + kappa * s) - math.sin(h)) / kappa
        y -= (math.cos(h + kappa * s) - math.cos(h)) / kappa
        h += kappa * s
    rmse, plans = run.rmse("curvature")
    assert len(plans) == 40 and rmse == pytest.approx(0.0, abs=1e-9)
    # the same path judged as rotate-then-go's (one straight leg) is far off its plan
    assert run.rmse("rotate_then_go")[0] > 0.05


def test_a_rotate_then_go_run_that_follows_each_leg_exactly_scores_zero():
    run, (x, y, h) = Record(), (0.0, 0.0, 0.5 * math.pi)
    for _ in range(5):                         # stand, then five legs
        run.add(x, y, h)
    legs = 0
    while legs < 4:
        start = len(run.ids)                   # the leg starts at the next sample, aimed
        target = moving_target((start - start % FIX_EVERY) * DT)   # at the latest fix then
        direction = math.atan2(target[1] - y, target[0] - x)
        turn = math.atan2(math.sin(direction - h), math.cos(direction - h))
        for k in range(1, 11):                 # turn on the spot: centre still
            w = math.copysign(0.1, turn)
            run.add(x, y, h + turn * k / 10.0, -w, w)
        h = direction
        run.add(x, y, h)                       # the turn has ended: one step at rest
        for _ in range(25):                    # then straight at V along the heading
            run.add(x, y, h, V, V)
            x, y = x + V * DT * math.cos(h), y + V * DT * math.sin(h)
        run.add(x, y, h)                       # the leg ends at rest
        legs += 1
    rmse, plans = run.rmse("rotate_then_go")
    assert len(plans) == 4 and rmse == pytest.approx(0.0, abs=1e-12)
    assert all(p.curvature == 0.0 for p in plans)


def _offset_rmse(d, length):
    """RMS over arc length of a path that steps sideways by d, then runs d off its plan
    for ``length``: the step counts d^2 / 2 over its length d (trapezoid)."""
    return d * math.sqrt((0.5 * d + length) / (d + length))


def test_a_straight_leg_offset_by_a_known_amount():
    d, run = 0.02, Record(fix_every=10 ** 6)                   # one fix, at the start
    run.add(0.0, 0.0, 0.5 * math.pi, target=(0.0, 2.0))        # fix: 2 m straight ahead
    run.add(0.0, 0.0, 0.5 * math.pi, V, V)                     # the leg starts here
    for k in range(101):                                       # 1 m, d to the right
        run.add(d, 0.01 * k, 0.5 * math.pi, V, V, target=(0.0, 2.0))
    rmse, plans = run.rmse("rotate_then_go")
    assert plans == [Plan(1, 0.0, 0.0, 0.5 * math.pi, 0.0)]
    assert rmse == pytest.approx(_offset_rmse(d, 1.0), rel=1e-12)


def test_an_arc_offset_by_a_known_amount():
    # the paper's start: the target 2 m away, 45 deg right; R = 1.414 m about (1.414, 0)
    d, radius = 0.03, math.sqrt(2.0)
    centre = np.array([radius, 0.0])
    run = Record(fix_every=10 ** 6)                             # one fix, at the start
    run.add(0.0, 0.0, 0.5 * math.pi, target=(math.sqrt(2.0), math.sqrt(2.0)))
    angles = np.linspace(math.pi, 0.5 * math.pi, 400)           # clockwise, a quarter turn
    for a in angles:                                            # d outside the planned arc
        x, y = centre + (radius + d) * np.array([math.cos(a), math.sin(a)])
        run.add(x, y, a - 0.5 * math.pi, target=(math.sqrt(2.0), math.sqrt(2.0)))
    rmse, plans = run.rmse("curvature")
    assert len(plans) == 1 and plans[0].curvature == pytest.approx(-1.0 / radius)
    arc = path_length(np.array(run.xy[1:]))
    assert rmse == pytest.approx(_offset_rmse(d, arc), rel=1e-9)


def test_distance_to_a_plan_past_its_ends():
    line = Plan(0, 0.0, 0.0, 0.0, 0.0)
    assert distance_to_plan([[2.0, 0.5], [-3.0, 4.0]], line) == pytest.approx([0.5, 5.0])
    circle = Plan(0, 0.0, 0.0, 0.5 * math.pi, 1.0)               # left turn about (-1, 0)
    points = [[-1.0, 1.5], [-2.0, 0.0], [-1.0, -1.0], [0.5, -0.5]]
    # a half turn, three quarters (the end), and behind the start (to the start point)
    assert distance_to_plan(points, circle) == pytest.approx(
        [0.5, 0.0, 0.0, math.hypot(0.5, 0.5)])


def test_accepted_fixes_and_refusals():
    ids, valid, distance = [0, 0, 1, 1, 2, 3, 3], [0, 0, 1, 1, 0, 1, 1], [0, 0, 2, 2, 2, -1, -1]
    assert list(accepted_fixes(ids, valid, distance)) == [2]
    with pytest.raises(ValueError, match="valid choices"):
        own_plans("pure_pursuit", [[0, 0]], [0], [0], [0], [0], [0])
    with pytest.raises(ValueError, match="wheel references"):
        own_plans("rotate_then_go", [[0, 0]], [0], [0], [0], [0], [0])
    assert own_plan_rmse([[0.0, 0.0], [0.0, 0.0]], []) is None
