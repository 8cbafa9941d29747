"""The SoundSource FMU: a thin pythonfmu slave around :class:`MovingSource`."""

from ..common.slave import DefaultExperiment, SonotrackSlave, load_ranges
from .source import MovingSource

__all__ = ["SoundSource"]


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
        # faults_active sits between parameters so that every value reference stays as published
        self.declare_parameters("path", "mute_at_end", "fault_schedule")
        self.output_integer("faults_active", "faults of fault_schedule active now")
        self.declare_parameters()

    def exit_initialization_mode(self):
        self.core = MovingSource(**self.parameter_values())
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
