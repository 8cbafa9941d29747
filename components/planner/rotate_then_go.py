"""The paper's baseline without curvature (Sec. 3.6, Table 1): turn on the spot, then go."""

import math

from ..common.trapezoid import next_speed
from .arc_drive import ARRIVED
from .geometry import RADIUS_STRAIGHT

__all__ = ["RotateThenGoMode"]

IDLE, TURN, DRIVE = 0, 1, 2


class RotateThenGoMode:
    """Turn on the spot towards the target, stop, then drive straight to it.

    Each leg has two rest-to-rest sampled trapezoids: the wheels at ``-+W`` until each has
    rolled ``|beta| L / 2`` (a heading change of ``beta``), then both at ``V`` over the distance
    to the target less ``stop_distance``. Progress comes from the measured wheel distances. A
    fix that arrives during a leg updates the target; the next leg starts from the odometry
    pose when this one has ended, because turning on the spot needs the robot at rest.
    """

    name = "rotate_then_go"

    def __init__(self):
        self.phase = IDLE
        self.direction = 1.0
        self.turn_length = 0.0
        self.drive_length = 0.0
        self.progress = 0.0
        self.pending = False
        self.curvature = 0.0
        self.turning = False
        self.wheel_arc_left = 0.0
        self.wheel_arc_right = 0.0

    def on_fix(self, planner, distance, bearing):
        """Start a leg now if at rest, else after the current one."""
        if self.phase == IDLE and planner.v_ref_left == 0.0 and planner.v_ref_right == 0.0:
            self._start_leg(planner)
        else:
            self.pending = True

    def record_progress(self, distance_left, distance_right):
        """Add the wheel distances [m] measured over the last step to the phase's progress."""
        if self.phase == TURN:
            self.progress += 0.5 * self.direction * (distance_right - distance_left)
        elif self.phase == DRIVE:
            self.progress += 0.5 * (distance_left + distance_right)

    def remaining(self):
        """Centre path length still to drive [m] (turning on the spot moves the centre by 0)."""
        if self.phase == DRIVE:
            return max(self.drive_length - self.progress, 0.0)
        return self.drive_length if self.phase == TURN else 0.0

    def command(self, planner, step):
        """Wanted wheel speeds [m/s] for the next step."""
        left, right = planner.v_ref_left, planner.v_ref_right
        at_rest = left == 0.0 and right == 0.0
        if self.phase == TURN and at_rest and self.turn_length - self.progress < ARRIVED:
            self._start_drive(planner)
        if self.phase == DRIVE and at_rest and self.drive_length - self.progress < ARRIVED:
            self.phase = IDLE
            if self.pending:
                self._start_leg(planner)
        self.turning = self.phase == TURN
        if self.phase == TURN:
            self.curvature = self.direction * RADIUS_STRAIGHT
            spin = next_speed(0.5 * self.direction * (right - left),
                              min(planner.v_cruise, planner.v_max),
                              _clean(self.turn_length - self.progress), planner.a_max, step)
            return -self.direction * spin, self.direction * spin
        self.curvature = 0.0
        if self.phase == DRIVE:
            speed = next_speed(0.5 * (left + right), min(planner.v_cruise, planner.v_max),
                               _clean(self.drive_length - self.progress), planner.a_max, step)
            return speed, speed
        return 0.0, 0.0

    def after_limit(self, fraction):
        """Legs start and end at rest, so the limiter never blends here."""

    def _start_leg(self, planner):
        self.pending = False
        distance, bearing = planner.odometry.polar_of(planner.target_x, planner.target_y)
        if distance <= planner.stop_distance:
            self.phase = IDLE
            self.drive_length = 0.0
            return
        self.phase = TURN
        self.direction = 1.0 if bearing >= 0.0 else -1.0
        self.turn_length = 0.5 * planner.track_width * abs(bearing)
        self.drive_length = distance - planner.stop_distance
        self.progress = 0.0
        self.wheel_arc_left = -self.direction * self.turn_length
        self.wheel_arc_right = self.direction * self.turn_length

    def _start_drive(self, planner):
        # Measure the straight leg from the pose the turn really reached.
        distance, _ = planner.odometry.polar_of(planner.target_x, planner.target_y)
        self.phase = DRIVE
        self.drive_length = max(distance - planner.stop_distance, 0.0)
        self.progress = 0.0
        self.wheel_arc_left = self.wheel_arc_right = self.drive_length


def _clean(remaining):
    return 0.0 if remaining < ARRIVED else remaining
