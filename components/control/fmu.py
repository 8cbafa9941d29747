"""The WheelController FMU: a thin pythonfmu slave around :class:`WheelSpeedController`."""

from ..common.slave import DefaultExperiment, SonotrackSlave, load_ranges
from .controller import DEFAULTS, WheelSpeedController

# Start value of the supply_voltage input: above any v_supply in range, so an unconnected
# input leaves the limit at v_supply.
SUPPLY_NOT_MEASURED = 1000.0

__all__ = ["WheelController"]

_REAL_PARAMETERS = (
    ("kp_min", "1", "FGS-PD smallest proportional gain (Kp' = 0), on e = v_ref - v_meas"),
    ("kp_max", "1", "FGS-PD largest proportional gain (Kp' = 1)"),
    ("kd_min", "1", "FGS-PD smallest derivative gain (Kd' = 0)"),
    ("kd_max", "1", "FGS-PD largest derivative gain (Kd' = 1)"),
    ("pid_kp", "1", "PID proportional gain on e / e_range"),
    ("pid_ki", "Hz", "PID integral gain on the time integral of e / e_range"),
    ("pid_kd", "1", "PID derivative gain on de / de_range"),
    ("pd_kp", "1", "fixed-PD proportional gain on e / e_range"),
    ("pd_kd", "1", "fixed-PD derivative gain on de / de_range"),
    ("e_range", "m/s", "speed error at the edge of the normalised universe"),
    ("de_range", "m/s2", "error rate at the edge of the normalised universe"),
    ("v_supply", "V", "output voltage limit +-v_supply"),
    ("derivative_time_constant", "s", "time constant of the derivative low-pass"),
    ("volts_per_speed", "V.s/m",
     "steady-state motor voltage per rim speed; scales feedforward and PD output"),
    ("trim_ki", "Hz", "integral trim of fgs_pd and pd on the integral of e / e_range "
                      "(0: pure PD)"),
)


class WheelController(SonotrackSlave):
    """Speed controller of one wheel: FGS-PD (the paper), PID (its CPID baseline) or fixed PD.

    voltage = clip(volts_per_speed * (v_ref [feedforward] + e_range * (kp e/e_range +
    kd de/de_range [+ ki integral])), +-v_supply), with e = v_ref - v_meas.
    """

    description = ("Wheel-speed controller: fuzzy gain-scheduled PD (Zhao-Tomizuka-Isaka rules), "
                   "PID baseline or fixed PD, with motor-model feedforward")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=10.0, step_size=0.02)
    valid_ranges = load_ranges("control")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.v_ref = 0.0
        self.v_meas = 0.0
        # Not connected, the measured supply never limits: v_supply does (as before).
        self.supply_voltage = SUPPLY_NOT_MEASURED
        self.mode = DEFAULTS["mode"]
        self.fuzzy_method = DEFAULTS["fuzzy_method"]
        self.feedforward = DEFAULTS["feedforward"]
        for name, _, _ in _REAL_PARAMETERS:
            setattr(self, name, DEFAULTS[name])
        self.core = WheelSpeedController()
        self.voltage = 0.0
        self.kp = self.core.kp
        self.kd = self.core.kd
        self.error = 0.0
        self.error_rate = 0.0

        self.input_real("v_ref", "m/s", "reference rim speed of the wheel")
        self.input_real("v_meas", "m/s", "measured rim speed of the wheel (from the encoder)")
        self.input_real("supply_voltage", "V", "measured supply voltage of the motor driver; "
                        "the output and the anti-windup are limited to min(v_supply, it); "
                        f"start value {SUPPLY_NOT_MEASURED:g} V: not measured")
        # No direct feedthrough: every output is computed in do_step and held until the next
        # one, so setting v_ref or v_meas changes no output before the next step.
        self.output_real("voltage", "V", "armature voltage command")
        self.output_real("kp", "1", "proportional gain used in the last step")
        self.output_real("kd", "1", "derivative gain used in the last step")
        self.output_real("error", "m/s", "speed error v_ref - v_meas")
        self.output_real("error_rate", "m/s2", "filtered time derivative of the error")
        self.parameter_string("mode", "control law: fgs_pd, pid or pd")
        self.parameter_string("fuzzy_method",
                              "FGS-PD defuzzification: weighted (Eqs. 51-52) or mamdani (COG)")
        self.parameter_boolean("feedforward", "add volts_per_speed * v_ref to the output")
        for name, unit, text in _REAL_PARAMETERS:
            self.parameter_real(name, unit, text)

    def exit_initialization_mode(self):
        parameters = {name: float(getattr(self, name)) for name, _, _ in _REAL_PARAMETERS}
        parameters.update(mode=str(self.mode), fuzzy_method=str(self.fuzzy_method),
                          feedforward=bool(self.feedforward))
        self.core = WheelSpeedController(**parameters)
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
