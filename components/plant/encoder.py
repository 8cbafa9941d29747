"""Incremental wheel encoder with a windowed count-difference speed estimate."""

import math

__all__ = ["WheelEncoder"]


class WheelEncoder:
    """Counts of one wheel's encoder and the speed an MCU would compute from them.

    The count is ``floor`` of the wheel angle in counts; the fraction of a count not yet
    reached is kept in ``phase`` so a saved state resumes exactly. Every ``speed_window``
    the controller timer differences the count ("M method"): the speed is held between
    samples and is quantised in steps of one count per window.

    Parameters
    ----------
    counts_per_revolution : int
        Counts per wheel revolution.
    wheel_radius : float
        [m]; converts counts to distance.

    Attributes
    ----------
    count : int
        Counts since start (signed, forward positive).
    phase : float
        Fraction of the next count already turned, in [0, 1).
    count_at_sample : int
        ``count`` at the last speed sample.
    speed : float
        Rim speed from the last window [m/s].
    distance_per_count : float
        [m].
    """

    def __init__(self, counts_per_revolution, wheel_radius):
        self.counts_per_radian = counts_per_revolution / (2.0 * math.pi)
        self.distance_per_count = 2.0 * math.pi * wheel_radius / counts_per_revolution
        self.count = 0
        self.phase = 0.0
        self.count_at_sample = 0
        self.speed = 0.0
        self.lost = 0
        self.carry = 0.0

    def turn(self, angle):
        """Advance the wheel by ``angle`` [rad]; return the whole counts crossed (signed)."""
        self.phase += angle * self.counts_per_radian
        crossed = math.floor(self.phase)
        if crossed:
            self.phase -= crossed
            self.count += crossed
        return crossed

    def sample(self, window, keep=1.0):
        """Take the windowed speed sample at the end of a window of ``window`` seconds.

        ``keep`` < 1 is a faulty encoder (docs/faults.md): only that fraction of the window's
        counts reach the counter (whole counts; the fraction carries over), 0 freezes it.
        """
        crossed = self.count - self.count_at_sample
        self.count_at_sample = self.count
        if keep != 1.0:
            kept = crossed * keep + self.carry
            counted = math.floor(kept)
            self.carry = kept - counted
            self.lost += crossed - counted
            crossed = counted
        self.speed = crossed * self.distance_per_count / window

    @property
    def reported_count(self):
        """The count the MCU sees: true counts less those a faulty encoder lost."""
        return self.count - self.lost
