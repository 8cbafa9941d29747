"""The moving sound source: a path, a trapezoidal speed profile along it and its bursts."""

import math

from ..common.errors import ParameterError
from ..common.faults import parse_schedule
from ..common.trapezoid import TrapezoidProfile
from .emission import BurstSchedule
from .paths import make_path

_EDGE = 1e-6

__all__ = ["MovingSource"]


class MovingSource:
    """The master robot with its speaker, moving along a path from rest to rest.

    After ``start_delay`` it accelerates at ``a_max`` to ``v_max`` along the path's arc length
    and decelerates to stop exactly at the path's end. It sounds a burst every ``emit_period``
    from time 0; with ``mute_at_end`` it falls silent when it reaches the end (as in the paper,
    to avoid a collision). A static source has no end and never mutes.

    Parameters
    ----------
    path : str
        ``"straight"``, ``"s_curve"``, ``"static"`` or a CSV file of waypoints.
    v_max, a_max : float
        Speed [m/s] and acceleration [m/s^2] limits, > 0.
    x0, y0, heading0 : float
        Start pose of the built-in paths [m, m, rad].
    length : float
        Forward extent of ``straight`` and ``s_curve`` [m].
    amplitude : float
        Lateral peak of ``s_curve`` [m].
    emit_period : float
        Time between bursts [s], > 0.
    mute_at_end : bool
        Fall silent at the end of the path.
    start_delay : float
        Time at rest before moving [s], >= 0.
    x1, y1, switch_time : float
        ``static`` path only: at ``switch_time`` [s] the source stands at (x1, y1) [m]
        instead, as a second target (the paper's dynamic Case 2). A negative ``switch_time``
        (the default) keeps the source at its start for ever.
    """

    # The fault schedule is set from parameters and never changes: not part of the state.
    STATE_CONSTANTS = ("silences",)

    def __init__(self, path="straight", v_max=0.2, a_max=0.2, x0=0.0, y0=1.0,
                 heading0=0.5 * math.pi, length=6.0, amplitude=0.5, emit_period=0.01,
                 mute_at_end=True, start_delay=0.0, x1=0.0, y1=0.0, switch_time=-1.0,
                 fault_schedule=""):
        if not (math.isfinite(emit_period) and emit_period > 0.0):
            raise ParameterError(f"emit_period = {emit_period!r}: must be a finite number > 0")
        if not (math.isfinite(start_delay) and start_delay >= 0.0):
            raise ParameterError(f"start_delay = {start_delay!r}: must be a finite number >= 0")
        for name, value in (("x1", x1), ("y1", y1), ("switch_time", switch_time)):
            if not math.isfinite(value):
                raise ParameterError(f"{name} = {value!r}: must be a finite number")
        if switch_time >= 0.0 and path != "static":
            raise ParameterError(f"switch_time = {switch_time!r} applies to path 'static' only, "
                                 f"not {path!r}; set switch_time < 0 for other paths")
        # source_silent faults: no bursts on [start, end), the path goes on.
        self.silences = parse_schedule(fault_schedule, "SoundSource").faults
        self.faults_active = 0
        self.second_position = (float(x1), float(y1))
        self.switch_time = float(switch_time)
        self.path = make_path(path, x0, y0, heading0, length, amplitude)
        self.profile = TrapezoidProfile(self.path.length, v_max, a_max)
        self.start_delay = float(start_delay)
        self.end_time = self.start_delay + self.profile.duration
        moving = self.path.length > 0.0
        self.bursts = BurstSchedule(emit_period,
                                    self.end_time if (mute_at_end and moving) else math.inf)
        self.time = 0.0
        self.progress = 0.0
        self.speed = 0.0
        self.x, self.y = self.path.position(0.0)
        self.heading = math.atan2(*reversed(self.path.tangent(0.0)))
        self.vx = self.vy = 0.0
        self.emitting = True
        self.burst_count = 0
        self.last_burst_time = -1.0
        self.advance_to(0.0)

    def advance_to(self, t):
        """Set the outputs to their values at time ``t`` [s]."""
        elapsed = t - self.start_delay
        self.time = float(t)
        progress, speed = self.profile.distance_and_speed(elapsed)
        self.progress, self.speed = progress, speed
        x, y, tangent_x, tangent_y = self.path.pose(progress)
        if 0.0 <= self.switch_time <= t:
            x, y = self.second_position
        self.x, self.y = x, y
        self.heading = math.atan2(tangent_y, tangent_x)
        self.vx, self.vy = speed * tangent_x, speed * tangent_y
        self.emitting, self.burst_count, self.last_burst_time = self.bursts.state(t)
        if self.silences:
            self._silence(t)

    def _silence(self, t):
        """Take the bursts of the silent stretches up to ``t`` out of the outputs."""
        bursts = self.bursts
        self.faults_active = 0
        for silence in self.silences:
            if silence.start > t:
                continue
            # 1 us before an edge: BurstSchedule's rounding guard counts an onset a few ulps
            # early, and no two onsets are that close.
            before = bursts.state(silence.start - _EDGE)
            last = min(t, silence.end - _EDGE)
            self.burst_count -= bursts.state(last)[1] - before[1]
            if silence.active(t):
                self.faults_active += 1
                self.emitting = False
                self.last_burst_time = before[2]
