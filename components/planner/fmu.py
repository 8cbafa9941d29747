"""The CurvaturePlanner FMU: a thin pythonfmu slave around :class:`TargetPlanner`."""

from ..common.errors import InputError
from ..common.slave import DefaultExperiment, SonotrackSlave, load_ranges
from .geometry import RADIUS_STRAIGHT
from .planner import FIX_NEGATIVE, TargetPlanner

__all__ = ["CurvaturePlanner"]


class CurvaturePlanner(SonotrackSlave):
    """Wheel-speed references that drive the robot to each heard fix along one arc.

    The references computed from the inputs at ``t`` are the outputs after the step to
    ``t + h`` and are meant to be held until the next step; no output feeds through directly.
    """

    description = ("Curvature planner (Sec. 3.3-3.4): one constant-curvature arc per fix with "
                   "trapezoidal wheel speeds on one time base; rotate_then_go and pure_pursuit "
                   "baselines")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=15.0, step_size=0.02)
    valid_ranges = load_ranges("planner")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.core = TargetPlanner()
        self.v_ref_left = 0.0
        self.v_ref_right = 0.0
        self.radius = RADIUS_STRAIGHT
        self.curvature = 0.0
        self.arc_remaining = 0.0
        self.state = 0
        self.target_x = 0.0
        self.target_y = 0.0
        self.wheel_arc_left = 0.0
        self.wheel_arc_right = 0.0
        self.rejected_fixes = 0
        self.fix_age = 0.0
        self.fix_timed_out = False
        self.wheel_faults = 0
        self.odometry_faults = 0
        self.stop_reason = 0
        self.bearing_discrepancy = 0.0
        self.bearing_bound = 0.0

        self.declare_inputs()
        self.output_real("v_ref_left", "m/s", "left wheel speed reference, held to the next step")
        self.output_real("v_ref_right", "m/s", "right wheel speed reference, held to the next step")
        self.output_real("radius", "m", f"radius of the path driven (Eq. 36); {RADIUS_STRAIGHT:g} "
                         "when straight, 0 when turning on the spot")
        self.output_real("curvature", "1/m", "signed curvature of the path driven, left positive; "
                         f"+-{RADIUS_STRAIGHT:g} when turning on the spot")
        self.output_real("arc_remaining", "m", "centre path length still to drive on this plan")
        self.output_integer("state", "0 idle, 1 moving, 2 stopping, 3 turning on the spot")
        self.output_real("target_x", "m", "target x in the odometry frame (start pose: origin, +y)")
        self.output_real("target_y", "m", "target y in the odometry frame")
        self.output_real("wheel_arc_left", "m", "left wheel distance of the current plan (Eq. 38)")
        self.output_real("wheel_arc_right", "m",
                         "right wheel distance of the current plan (Eq. 38)")
        self.output_integer("rejected_fixes", "fixes the plausibility gate rejected so far")
        self.output_real("fix_age", "s", "time since the last accepted fix (0 before the first)")
        self.output_boolean("fix_timed_out", "no accepted fix for fix_timeout: driving out "
                            "the last arc at half speed, or stopped at its end")
        self.output_integer("wheel_faults", "times the wheel check stopped the robot")
        self.output_integer("odometry_faults", "times the odometry check stopped the robot "
                            "(fix bearings drifting from the odometry's prediction)")
        self.output_real("bearing_discrepancy", "rad", "odometry check: latest fix's bearing "
                         "minus the odometry's prediction from the previous fix (0 when off)")
        self.output_real("bearing_bound", "rad", "odometry check: the discrepancy a source at "
                         "max_target_speed and the fix noise explain (0 when off)")
        self.output_integer("stop_reason", "why the references are held at 0: 0 they are not, "
                            "1 wheel check, 2 odometry check")
        self.declare_parameters()
        # distance and bearing mean something only while valid is true.
        self._bounds_valid = self.input_bounds(("distance", "bearing", "measurement_id",
                                                "wheel_speed_left", "wheel_speed_right"))
        self._bounds_invalid = self.input_bounds(("measurement_id", "wheel_speed_left",
                                                  "wheel_speed_right"))

    def exit_initialization_mode(self):
        self.core = TargetPlanner(**self.parameter_values())

    def do_step(self, current_time, step_size):
        left, right = self.wheel_speed_left, self.wheel_speed_right
        valid, distance, bearing = self.valid, self.distance, self.bearing
        if self.inputs_refused(self._bounds_valid if valid else self._bounds_invalid) or \
                self.step_refused(step_size):
            return False
        core = self.core
        try:
            self.v_ref_left, self.v_ref_right = core.update(
                current_time, step_size, left, right, self.measurement_id, valid, distance,
                bearing)
        except InputError as exc:
            return self.refuse("bearing", bearing, str(exc))
        if core.fix_outcome == FIX_NEGATIVE:
            self.log_once(f"negative fix {self.measurement_id}",
                          f"fix {self.measurement_id}: distance = {distance!r} m is "
                          "negative; fix ignored")
        mode = core.mode
        self.radius = core.radius
        self.curvature = mode.curvature
        self.arc_remaining = mode.remaining()
        self.state = core.state
        self.target_x, self.target_y = core.target_x, core.target_y
        self.wheel_arc_left = mode.wheel_arc_left
        self.wheel_arc_right = mode.wheel_arc_right
        self.rejected_fixes = core.rejected_fixes
        self.fix_age = current_time - core.last_accepted_time if core.has_target else 0.0
        self.fix_timed_out = core.timed_out
        self.wheel_faults = core.wheel_faults
        self.odometry_faults = core.odometry_faults
        self.stop_reason = core.stop_reason
        check = core.odometry_check
        if check is not None:
            self.bearing_discrepancy = check.last_discrepancy
            self.bearing_bound = check.last_bound
        return True
