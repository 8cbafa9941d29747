"""The paper's mode: one constant-curvature arc per fix, progress counted by the encoders."""

from .arc_drive import arc_limits, arc_wheel_speeds
from .geometry import RESOLVABLE_DISTANCE, arc_curvature, arc_length, stop_arc_length, wheel_arc_lengths

__all__ = ["CurvatureMode"]


class CurvatureMode:
    """Drive the arc of Eqs. (36)-(38) from each fix; blend to a new arc without speed steps.

    A fix (D, theta) gives ``kappa = 2 sin(theta) / D`` (Eq. 36) and the centre arc length
    ``s = D theta / sin(theta)`` (Eq. 37), shortened so the robot stops ``stop_distance`` from
    the target. Progress along it is the mean of the wheel distances measured since the fix.

    When a fix arrives while moving, the wheels pass from the old speed ratio to the new one
    with bounded acceleration (the paper's Case 2). The robot drifts off the planned arc during
    that blend, so once the new ratio is reached the arc is planned once more from the
    odometry pose to the same target.
    """

    name = "curvature"

    def __init__(self):
        self.curvature = 0.0
        self.length = 0.0
        self.progress = 0.0
        self.blending = False
        self.reaim_pending = False
        self.turning = False
        self.wheel_arc_left = 0.0
        self.wheel_arc_right = 0.0
        # arc_limits of the curvature, kept from plan to plan instead of recomputed each step
        self.arc = None

    def on_fix(self, planner, distance, bearing):
        """Plan the arc to a new fix seen from the current pose."""
        self._plan(planner, distance, bearing)
        self.reaim_pending = False

    def record_progress(self, distance_left, distance_right):
        """Add the wheel distances [m] measured over the last step."""
        self.progress += 0.5 * (distance_left + distance_right)

    def remaining(self):
        """Centre arc length still to drive [m]."""
        remaining = self.length - self.progress
        return 0.0 if remaining < 0.0 else remaining

    def command(self, planner, step):
        """Wanted wheel speeds [m/s] for the next step."""
        if self.reaim_pending and planner.has_target:
            self.reaim_pending = False
            self._plan(planner, *planner.odometry.polar_of(planner.target_x, planner.target_y))
        if self.arc is None:
            self.arc = arc_limits(planner, self.curvature)
        return arc_wheel_speeds(planner, planner.v_ref_left, planner.v_ref_right,
                                self.curvature, self.length - self.progress, step, self.arc)

    def after_limit(self, fraction):
        """Note whether the wheel-speed blend is still under way after limiting."""
        if fraction < 1.0:
            self.blending = True
        elif self.blending:
            self.blending = False
            self.reaim_pending = True

    def _plan(self, planner, distance, bearing):
        self.progress = 0.0
        if distance <= max(planner.stop_distance, RESOLVABLE_DISTANCE):
            # Already close enough (or closer than anything measurable, where 2 sin(theta) / D
            # overflows to inf): keep the present ratio and brake along it.
            self.length = 0.0
        else:
            self.curvature = arc_curvature(distance, bearing)
            self.length = (arc_length(distance, bearing)
                           - stop_arc_length(self.curvature, planner.stop_distance))
        self.wheel_arc_left, self.wheel_arc_right = wheel_arc_lengths(
            self.curvature, self.length, planner.track_width)
        self.arc = arc_limits(planner, self.curvature)
