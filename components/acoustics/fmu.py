"""The AcousticLocalizer FMU: a thin pythonfmu slave around :class:`LocalizerCore`."""

from ..common.errors import InputError
from ..common.slave import DefaultExperiment, Fmi2Status, SonotrackSlave, load_ranges
from .localizer import LocalizerCore
from .room import LeftRoomError

__all__ = ["AcousticLocalizer"]


class AcousticLocalizer(SonotrackSlave):
    """Three-microphone array and TDOA estimator: one fix per ``fix_period`` while emitting.

    A fix uses the inputs at the start of the step whose interval holds the fix instant and
    appears at the end of that step; no output feeds through directly. Between fixes, and
    after a failed attempt, the last valid fix is held (``valid`` false after a failure).
    """

    description = ("Acoustic localizer (Sec. 2): synthesises three microphone records of the "
                   "source's chirp (fractional delays, 1/r, noise, 10-bit ADC) and estimates "
                   "range and bearing by band-limited GCC and the exact near-field geometry; "
                   "free field, or a shoebox room (image sources, moving source and array)")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=10.0, step_size=0.01)
    valid_ranges = load_ranges("acoustics")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.core = LocalizerCore()
        self._copy_outputs()  # the core's "no fix yet" values

        self.declare_inputs()
        self.output_real("distance", "m", "range of the last valid fix from the robot reference "
                         "point (the array centre when array_offset = 0)")
        self.output_real("bearing", "rad", "bearing of the last valid fix, relative to the "
                         "heading, left (CCW) positive")
        self.output_boolean("valid", "the latest fix attempt gave a valid fix")
        self.output_real("tdoa_12", "s", "t1 - t2 of the last valid fix (M1 left, M2 centre)")
        self.output_real("tdoa_23", "s", "t3 - t2 of the last valid fix (M3 right)")
        self.output_integer("measurement_id", "number of valid fixes so far; +1 per new fix")
        self.output_real("peak_quality", "1", "weaker pair's in-band correlation coefficient "
                         "at the latest attempt")
        self.output_integer("fix_status", "latest attempt: 0 ok, 1 not emitting, 2 behind, "
                            "3 too close, 4 beyond max_range, 5 no onset, 6 weak peak, "
                            "7 lag at +-l/c, 8 inconsistent delays, 9 estimate beyond max_range, "
                            "10 dead microphone, 11 clipped microphone, 12 fix lost")
        self.output_integer("fix_attempts", "fix attempts so far, valid or not; with "
                            "fix_status, the reason of each")
        self.output_integer("faults_active", "faults of fault_schedule active at the latest "
                            "attempt")
        self.output_real("true_distance", "m", "true range at the latest attempt (for plots)")
        self.output_real("true_bearing", "rad", "true bearing at the latest attempt (for plots)")
        self.declare_parameters()

    def exit_initialization_mode(self):
        self.core = LocalizerCore(**self.parameter_values())

    def do_step(self, current_time, step_size):
        if self.inputs_refused() or self.step_refused(step_size):
            return False
        core = self.core
        try:
            attempted = core.step(current_time, step_size, self.source_x, self.source_y,
                                  self.emitting, self.robot_x, self.robot_y, self.robot_heading)
        except LeftRoomError as exc:
            # Not a bad input value but the end of what the room can model: say where, stop.
            self.log(f"{self.instance_name}: {exc}", Fmi2Status.error)
            return False
        except InputError as exc:
            return self.refuse("source/robot position", None, str(exc))
        if not attempted:
            return True
        if core.missed_instants:
            self.log_once("missed", f"step_size {step_size!r} s exceeds fix_period "
                          f"{core.settings.fix_period!r} s: some fix instants are skipped")
        self._copy_outputs()
        return True

    def _copy_outputs(self):
        core = self.core
        self.distance, self.bearing, self.valid = core.distance, core.bearing, core.valid
        self.tdoa_12, self.tdoa_23 = core.tdoa_12, core.tdoa_23
        self.measurement_id = core.measurement_id
        self.peak_quality = core.peak_quality
        self.fix_status = core.fix_status
        self.true_distance, self.true_bearing = core.true_distance, core.true_bearing
        self.faults_active = core.faults_active
        self.fix_attempts = core.fix_attempts
