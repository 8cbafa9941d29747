"""The SoundSource FMU: a thin pythonfmu slave around :class:`MovingSource`."""

import math

from ..common.slave import DefaultExperiment, SonotrackSlave, load_ranges
from .source import MovingSource

__all__ = ["SoundSource"]

_REAL_PARAMETERS = (
    ("v_max", "m/s", 0.2, "cruise speed along the path"),
    ("a_max", "m/s2", 0.2, "acceleration and deceleration along the path"),
    ("x0", "m", 0.0, "start x of the built-in paths (world frame, x right)"),
    ("y0", "m", 1.0, "start y of the built-in paths (world frame, y forward)"),
    ("heading0", "rad", 0.5 * math.pi, "start heading of the built-in paths, CCW from +x"),
    ("length", "m", 6.0, "forward extent of the straight and s_curve paths"),
    ("amplitude", "m", 0.5, "lateral peak of the s_curve path"),
    ("emit_period", "s", 0.01, "time between band-limited bursts"),
    ("start_delay", "s", 0.0, "time at rest before moving"),
    ("x1", "m", 0.0, "static path only: x of the second position (see switch_time)"),
    ("y1", "m", 0.0, "static path only: y of the second position (see switch_time)"),
    ("switch_time", "s", -1.0, "static path only: time the source moves to (x1, y1); < 0 never"),
)


class SoundSource(SonotrackSlave):
    """The moving master robot with its speaker; it has no inputs.

    After the step to ``t + h`` the outputs are the source's state at ``t + h``.
    """

    description = ("Moving sound source: straight, S-curve, static or CSV-waypoint path with a "
                   "trapezoidal speed profile; a burst every emit_period, mute at the end")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=35.0, step_size=0.01)
    valid_ranges = load_ranges("source")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.path = "straight"
        self.mute_at_end = True
        self.fault_schedule = ""
        for name, _, default, _ in _REAL_PARAMETERS:
            setattr(self, name, default)
        self.core = MovingSource()
        self._copy_outputs()

        self.output_real("x", "m", "source x, world frame")
        self.output_real("y", "m", "source y, world frame")
        self.output_real("vx", "m/s", "source velocity along x")
        self.output_real("vy", "m/s", "source velocity along y")
        self.output_boolean("emitting", "the source sounds (a burst every emit_period)")
        self.output_real("heading", "rad", "direction of travel, CCW from +x")
        self.output_real("path_progress", "m", "arc length travelled along the path")
        self.output_real("speed", "m/s", "speed along the path")
        self.output_integer("burst_count", "number of bursts started so far")
        self.output_real("last_burst_time", "s", "onset of the latest burst (-1 before the first)")
        self.parameter_string("path", "straight, s_curve, static, or a CSV file of waypoints x,y")
        self.parameter_boolean("mute_at_end", "fall silent when the end of the path is reached")
        self.parameter_string("fault_schedule", "faults this FMU applies (source_silent): a "
                              "JSON list of {kind, start, end} (docs/faults.md); empty: none")
        self.output_integer("faults_active", "faults of fault_schedule active now")
        for name, unit, _, text in _REAL_PARAMETERS:
            self.parameter_real(name, unit, text)

    def exit_initialization_mode(self):
        parameters = {name: float(getattr(self, name)) for name, _, _, _ in _REAL_PARAMETERS}
        self.core = MovingSource(path=str(self.path), mute_at_end=bool(self.mute_at_end),
                                 fault_schedule=str(self.fault_schedule), **parameters)
        self._copy_outputs()

    def do_step(self, current_time, step_size):
        if self.step_refused(step_size):
            return False
        self.core.advance_to(current_time + step_size)
        self._copy_outputs()
        return True

    def _copy_outputs(self):
        core = self.core
        self.x, self.y, self.vx, self.vy = core.x, core.y, core.vx, core.vy
        self.emitting = core.emitting
        self.heading = core.heading
        self.path_progress = core.progress
        self.speed = core.speed
        self.burst_count = core.burst_count
        self.last_burst_time = core.last_burst_time
        self.faults_active = core.faults_active
