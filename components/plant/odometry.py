"""Dead reckoning from encoder counts alone, as the robot's own MCU would compute it."""

import math

__all__ = ["EncoderOdometry"]


class EncoderOdometry:
    """Pose integrated from wheel travel increments, assuming rolling without slip.

    Each increment is taken as an arc: the chord is travelled along the mean heading, which
    is exact for a constant-curvature piece.

    Parameters
    ----------
    x, y, heading : float
        Start pose [m, m, rad].
    track_width : float
        [m].

    Attributes
    ----------
    x, y, heading : float
        Estimated pose; heading is not wrapped, so it stays continuous.
    """

    def __init__(self, x, y, heading, track_width):
        self.x = x
        self.y = y
        self.heading = heading
        self.track_width = track_width

    def advance(self, distance_left, distance_right):
        """Move by the wheel travel increments ``distance_left``, ``distance_right`` [m]."""
        turn = (distance_right - distance_left) / self.track_width
        mean = 0.5 * (distance_left + distance_right)
        if turn == 0.0:
            chord = mean
        else:
            chord = mean * math.sin(0.5 * turn) / (0.5 * turn)
        middle = self.heading + 0.5 * turn
        self.x += chord * math.cos(middle)
        self.y += chord * math.sin(middle)
        self.heading += turn
