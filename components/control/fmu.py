"""The WheelController FMU: a thin pythonfmu slave around :class:`WheelSpeedController`."""

from ..common.slave import DefaultExperiment, SonotrackSlave, load_ranges
from .controller import WheelSpeedController

__all__ = ["WheelController"]


class WheelController(SonotrackSlave):
    """Speed controller of one wheel: FGS-PD (the paper), PID (its CPID baseline) or fixed PD.

    With e = v_ref - v_meas and g = volts_per_speed, in the default form (``form``)
    voltage = clip(g (v_ref + acceleration_feedforward dv_ref/dt) [feedforward] +
    g gain_scale (kp e + kd derivative_time de) + g integral_gain integral(e), +-v_supply),
    the integral emptied while v_ref = 0; in the paper form
    voltage = clip(g (v_ref [feedforward] + e_range (kp e/e_range + kd de/de_range +
    trim_ki integral(e/e_range))), +-v_supply). The PID mode is the paper's CPID.
    """

    description = ("Wheel-speed controller: fuzzy gain-scheduled PD (Zhao-Tomizuka-Isaka rules), "
                   "PID baseline or fixed PD, with motor-model feedforward; default or paper form")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=10.0, step_size=0.02)
    valid_ranges = load_ranges("control")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.core = WheelSpeedController()
        self.voltage = 0.0
        self.kp = self.core.kp
        self.kd = self.core.kd
        self.error = 0.0
        self.error_rate = 0.0

        self.declare_inputs()
        # No direct feedthrough: every output is computed in do_step and held until the next
        # one, so setting v_ref or v_meas changes no output before the next step.
        self.output_real("voltage", "V", "armature voltage command")
        self.output_real("kp", "1", "proportional gain used in the last step")
        self.output_real("kd", "1", "derivative gain used in the last step")
        self.output_real("error", "m/s", "speed error v_ref - v_meas")
        self.output_real("error_rate", "m/s2", "filtered time derivative of the error")
        self.declare_parameters()

    def exit_initialization_mode(self):
        self.core = WheelSpeedController(**self.parameter_values())
        self.kp = self.core.kp
        self.kd = self.core.kd

    def do_step(self, current_time, step_size):
        if self.inputs_refused() or self.step_refused(step_size):
            return False
        core = self.core
        self.voltage = core.step(self.v_ref, self.v_meas, step_size, self.supply_voltage)
        self.kp = core.kp
        self.kd = core.kd
        self.error = core.error
        self.error_rate = core.error_rate
        return True
