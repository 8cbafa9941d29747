"""The RobotPlant FMU: a thin pythonfmu slave around :class:`RobotPlantCore`."""

from ..common.slave import DefaultExperiment, SonotrackSlave, load_ranges
from .parameters import PlantParameters
from .plant import RobotPlantCore

__all__ = ["RobotPlant"]

# Output port -> (unit, description, core attribute). Every output is a state or a function of
# the state, so none depends directly on the inputs.
_REAL_OUTPUTS = (
    ("x", "m", "true x of the axle midpoint"),
    ("y", "m", "true y of the axle midpoint"),
    ("heading", "rad", "true heading, counter-clockwise from +x, not wrapped"),
    ("wheel_speed_left", "m/s", "left rim speed from encoder counts over speed_window"),
    ("wheel_speed_right", "m/s", "right rim speed from encoder counts over speed_window"),
    ("odom_x", "m", "x from encoder-only odometry"),
    ("odom_y", "m", "y from encoder-only odometry"),
    ("odom_heading", "rad", "heading from encoder-only odometry"),
    ("slip_left", "1", "longitudinal slip ratio of the left wheel"),
    ("slip_right", "1", "longitudinal slip ratio of the right wheel"),
    ("lateral_slip_speed", "m/s", "sideways sliding speed of the body, left positive"),
    ("speed", "m/s", "true forward speed of the body"),
    ("yaw_rate", "rad/s", "true yaw rate, counter-clockwise positive"),
    ("rim_speed_left", "m/s", "true left rim speed r*omega"),
    ("rim_speed_right", "m/s", "true right rim speed r*omega"),
    ("current_left", "A", "left armature current"),
    ("current_right", "A", "right armature current"),
)
_SUPPLY_OUTPUTS = (
    ("supply_voltage_left", "left", "supply voltage of the left motor driver for the next "
     "step (v_supply, or lower while a supply_sag is on): the battery monitor"),
    ("supply_voltage_right", "right", "supply voltage of the right motor driver for the next "
     "step"),
)
_INTEGER_OUTPUTS = (
    ("encoder_left", "left encoder count (728 per wheel revolution by default)"),
    ("encoder_right", "right encoder count"),
)
_INPUTS = ("voltage_left", "voltage_right")


class RobotPlant(SonotrackSlave):
    """Two geared DC motors, wheels with slip, rigid body, encoders and odometry."""

    description = ("Differential-drive robot: 12 V geared DC motors (IG-32PGM 14:1 class), "
                   "friction-circle traction with longitudinal and lateral slip, "
                   "728-count encoders, encoder odometry beside the true pose")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=10.0, step_size=0.01)
    valid_ranges = load_ranges("plant")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.core = RobotPlantCore(PlantParameters())
        self._publish()

        self.declare_inputs()
        for name, unit, text in _REAL_OUTPUTS:
            self.output_real(name, unit, text)
        for name, _, text in _SUPPLY_OUTPUTS:
            self.output_real(name, "V", text)
        for name, text in _INTEGER_OUTPUTS:
            self.output_integer(name, text)
        self.declare_parameters()
        self.output_integer("faults_active", "faults of fault_schedule active in the last step")

    def exit_initialization_mode(self):
        values = self.parameter_values()
        fault_schedule = values.pop("fault_schedule")
        self.core = RobotPlantCore(PlantParameters(**values), fault_schedule=fault_schedule)
        self._publish()

    def do_step(self, current_time, step_size):
        if self.inputs_refused() or self.step_refused(step_size):
            return False
        supply = self.core.parameters.v_supply
        for port in _INPUTS:
            value = getattr(self, port)
            if abs(value) > supply:
                self.log_once(f"clamp {port}", f"input {port} = {value!r} V exceeds the supply "
                              f"+-{supply!r} V; clamped (further clamping is not logged)")
        self.core.step(self.voltage_left, self.voltage_right, step_size)
        self._publish()
        return True

    def _publish(self):
        core = self.core
        for name, _, _ in _REAL_OUTPUTS:
            setattr(self, name, getattr(core, name))
        self.encoder_left = core.encoder_left
        self.encoder_right = core.encoder_right
        self.faults_active = core.faults_active
        nominal = core.parameters.v_supply
        for name, wheel, _ in _SUPPLY_OUTPUTS:
            setattr(self, name, core.faults.supply(core.time, wheel, nominal)
                    if core.faults else nominal)
