"""When the source sounds: periodic bursts while it emits, silence after the end if muted."""

import math

__all__ = ["BurstSchedule"]


class BurstSchedule:
    """Bursts at ``n * emit_period`` from the start until the mute time (if any).

    Parameters
    ----------
    emit_period : float
        Time between burst onsets [s] (10 ms in the paper), > 0.
    mute_time : float
        Time from which the source is silent [s]; ``math.inf`` for never.
    """

    def __init__(self, emit_period, mute_time=math.inf):
        self.emit_period = float(emit_period)
        self.mute_time = float(mute_time)
        # The latest instant a burst can start: silence begins at mute_time itself.
        self.last_onset = math.nextafter(self.mute_time, -math.inf)

    def emitting(self, t):
        """Whether the source sounds at time ``t`` [s]."""
        return t < self.mute_time

    def burst_count(self, t):
        """Number of bursts started up to and including time ``t`` [s]."""
        return self.state(t)[1]

    def last_burst_time(self, t):
        """Onset [s] of the latest burst at time ``t``, or -1 before the first one."""
        return self.state(t)[2]

    def state(self, t):
        """:meth:`emitting`, :meth:`burst_count` and :meth:`last_burst_time` at ``t``, at once.

        Returns
        -------
        tuple
            ``(emitting, burst_count, last_burst_time)``.

        Examples
        --------
        >>> BurstSchedule(0.01, mute_time=1.0).state(0.5)
        (True, 51, 0.5)
        """
        last = self.last_onset if self.last_onset < t else t
        if last < 0.0:
            return t < self.mute_time, 0, -1.0
        # t_k = k * h and n * period need not round alike; a relative guard keeps
        # a burst due exactly at t from being missed.
        count = int(math.floor(last / self.emit_period * (1.0 + 1e-12) + 1e-9)) + 1
        return t < self.mute_time, count, (count - 1) * self.emit_period
