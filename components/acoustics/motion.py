"""Where the source and the robot were: the localizer's record of its inputs over recent time.

In a room, a burst's sound reaches the microphones by paths up to the time cut long (tenths of
a second), so the source's position at each burst's emission instant is needed, not only the
latest. The localizer keeps the inputs of every step (time, source position, ``emitting``,
robot pose) as long as they can still matter and interpolates linearly between them. Between
two samples one communication step apart (10 ms in the shipped scenarios) linear
interpolation is off by at most ``a h^2 / 8``: 2.5 um for the source's 0.2 m/s^2.

Before the first sample the bodies are taken to be where they were at the first sample and the
source silent (nothing sounded before the run started).
"""

import numpy as np

__all__ = ["PoseHistory"]

# Columns of a sample.
TIME, SOURCE_X, SOURCE_Y, EMITTING, ROBOT_X, ROBOT_Y, HEADING = range(7)


class PoseHistory:
    """The inputs of the latest steps, oldest first, kept for ``horizon`` seconds.

    Parameters
    ----------
    horizon : float
        How far back samples are needed [s]; one older sample is kept to interpolate from.

    Attributes
    ----------
    samples : list of tuple
        ``(time, source_x, source_y, emitting, robot_x, robot_y, robot_heading)``; part of the
        FMU state.
    """

    def __init__(self, horizon):
        self.horizon = float(horizon)
        self.samples = []

    def record(self, time, source_x, source_y, emitting, robot_x, robot_y, robot_heading):
        """Append the inputs at ``time`` (a repeated time replaces the sample) and drop old ones."""
        sample = (float(time), float(source_x), float(source_y), 1.0 if emitting else 0.0,
                  float(robot_x), float(robot_y), float(robot_heading))
        samples = self.samples
        # A host that retries a step (after restoring a state) sends the same time again.
        while samples and samples[-1][TIME] >= sample[TIME]:
            samples.pop()
        samples.append(sample)
        oldest = sample[TIME] - self.horizon
        while len(samples) > 2 and samples[1][TIME] <= oldest:
            samples.pop(0)

    def table(self):
        """The samples as an array (n, 7)."""
        return np.array(self.samples, dtype=float)

    @staticmethod
    def source_at(table, times):
        """Source positions (len(times), 2) at ``times``, linear between samples, held outside."""
        return np.stack([np.interp(times, table[:, TIME], table[:, SOURCE_X]),
                         np.interp(times, table[:, TIME], table[:, SOURCE_Y])], axis=-1)

    @staticmethod
    def source_point(table, time):
        """The source position ``(x, y)`` at one instant as :meth:`source_at` gives it (floats)."""
        return (float(np.interp(time, table[:, TIME], table[:, SOURCE_X])),
                float(np.interp(time, table[:, TIME], table[:, SOURCE_Y])))

    @staticmethod
    def emitting_at(table, times):
        """Whether the source sounded at ``times``: the latest sample at or before each (False before the first)."""
        index = np.searchsorted(table[:, TIME], times, side="right") - 1
        return (index >= 0) & (table[np.maximum(index, 0), EMITTING] > 0.5)

    @staticmethod
    def latest_two(table):
        """The robot's last two poses ``((t, x, y, heading), (t, x, y, heading))``; equal if one sample."""
        last = table[-1]
        previous = table[-2] if len(table) > 1 else last
        return ((previous[TIME], previous[ROBOT_X], previous[ROBOT_Y], previous[HEADING]),
                (last[TIME], last[ROBOT_X], last[ROBOT_Y], last[HEADING]))
