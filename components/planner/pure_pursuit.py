"""Pure pursuit baseline: re-aim the arc at the target from the odometry pose every step."""

import math

from .arc_drive import ARRIVED, arc_limits, arc_wheel_speeds
from .geometry import arc_curvature, arc_length, stop_arc_length

__all__ = ["PurePursuitMode"]


class PurePursuitMode:
    """Curvature ``2 sin(alpha) / L_d`` with the latest fix as the look-ahead point.

    ``alpha`` and ``L_d`` are the bearing and distance of the target from the current odometry
    pose, recomputed every step, so heading errors are corrected continuously instead of once
    per fix. The speed follows the same sampled trapezoid as the curvature mode, on the arc
    length left to the target. A target beside or behind the robot (``|alpha| > pi/2``) counts
    as passed and the robot stops.
    """

    name = "pure_pursuit"

    def __init__(self):
        self.curvature = 0.0
        self.length = 0.0
        self.turning = False
        self.wheel_arc_left = 0.0
        self.wheel_arc_right = 0.0

    def on_fix(self, planner, distance, bearing):
        """Nothing to plan: the next step aims at the new target."""

    def record_progress(self, distance_left, distance_right):
        """Progress is read from the odometry pose instead."""

    def remaining(self):
        """Centre arc length still to drive [m]."""
        return max(self.length, 0.0)

    def command(self, planner, step):
        """Wanted wheel speeds [m/s] for the next step."""
        self.length = 0.0
        if planner.has_target:
            distance, bearing = planner.odometry.polar_of(planner.target_x, planner.target_y)
            if (distance > max(planner.stop_distance, ARRIVED)
                    and abs(bearing) <= 0.5 * math.pi + 1e-9):
                self.curvature = arc_curvature(distance, bearing)
                self.length = (arc_length(distance, bearing)
                               - stop_arc_length(self.curvature, planner.stop_distance))
        arc = arc_limits(planner, self.curvature)
        # wheel_arc_lengths (Eq. 38) from the wheel factors arc_limits has just computed
        factor_left, factor_right = arc[0], arc[1]
        self.wheel_arc_left, self.wheel_arc_right = (factor_left * self.length,
                                                     factor_right * self.length)
        return arc_wheel_speeds(planner, planner.v_ref_left, planner.v_ref_right,
                                self.curvature, self.length, step, arc)

    def after_limit(self, fraction):
        """Pure pursuit needs no bookkeeping of blends."""
