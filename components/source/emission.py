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

    def emitting(self, t):
        """Whether the source sounds at time ``t`` [s]."""
        return t < self.mute_time

    def burst_count(self, t):
        """Number of bursts started up to and including time ``t`` [s]."""
        last = min(t, math.nextafter(self.mute_time, -math.inf))
        if last < 0.0:
            return 0
        # t_k = k * h and n * period need not round alike; a relative guard keeps
        # a burst due exactly at t from being missed.
        return int(math.floor(last / self.emit_period * (1.0 + 1e-12) + 1e-9)) + 1

    def last_burst_time(self, t):
        """Onset [s] of the latest burst at time ``t``, or -1 before the first one."""
        count = self.burst_count(t)
        return (count - 1) * self.emit_period if count > 0 else -1.0
