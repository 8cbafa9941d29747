"""Dead reckoning from measured wheel speeds, the only motion sensor the paper's robot uses.

The odometry frame matches the world frame at the start: the robot at (0, 0) facing +y,
heading counter-clockwise from +x (pi/2 at the start).
"""

import math

__all__ = ["Odometry"]


class Odometry:
    """Pose estimate of a differential-drive robot integrated from its wheel speeds.

    Parameters
    ----------
    track_width : float
        Distance between the wheel contact points [m].
    """

    def __init__(self, track_width):
        self.track_width = float(track_width)
        self.x = 0.0
        self.y = 0.0
        self.heading = 0.5 * math.pi

    def advance(self, wheel_speed_left, wheel_speed_right, duration):
        """Move the pose along the arc driven at constant wheel speeds for ``duration`` [s].

        The exact circular arc is used, so a robot whose wheels really held these speeds is
        tracked without integration error.
        """
        speed = 0.5 * (wheel_speed_left + wheel_speed_right)
        turn = (wheel_speed_right - wheel_speed_left) / self.track_width * duration
        heading = self.heading
        end_heading = heading + turn
        if -1e-9 < turn < 1e-9:
            # Second-order expansion of the arc about its midpoint heading.
            mid = heading + 0.5 * turn
            self.x += speed * duration * math.cos(mid)
            self.y += speed * duration * math.sin(mid)
        else:
            radius = speed * duration / turn
            self.x += radius * (math.sin(end_heading) - math.sin(heading))
            self.y -= radius * (math.cos(end_heading) - math.cos(heading))
        self.heading = end_heading

    def point_at(self, distance, bearing):
        """Odometry-frame coordinates of a point seen at ``distance`` [m] and ``bearing`` [rad]."""
        direction = self.heading + bearing
        return self.x + distance * math.cos(direction), self.y + distance * math.sin(direction)

    def polar_of(self, x, y):
        """Distance [m] and bearing [rad] in (-pi, pi] of an odometry-frame point."""
        dx, dy = x - self.x, y - self.y
        bearing = math.atan2(dy, dx) - self.heading
        bearing = math.atan2(math.sin(bearing), math.cos(bearing))
        return math.hypot(dx, dy), bearing
