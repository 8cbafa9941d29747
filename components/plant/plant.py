"""The robot plant core: two geared DC motors, wheels with traction, rigid body, encoders.

:class:`RobotPlantCore` holds the state, checks and clamps the inputs, applies the fault
schedule, cuts every communication step at the encoder speed-sample instants and samples the
encoders there. The numerics of a span between two samples -- ROS2 Rosenbrock substeps with
the tyre law and the encoder counts inlined -- live in :mod:`.integrator`.
"""

import math

from ..common.errors import InputError
from ..common.faults import parse_schedule
from .dynamics import COULOMB_SPEED
from .encoder import WheelEncoder
from .faults import PlantFaults
from .integrator import _NS, integrate_span
from .odometry import EncoderOdometry
from .parameters import PlantParameters
from .traction import slip_ratio

__all__ = ["RobotPlantCore"]

# Work bound of one communication step: integration substeps plus encoder samples. The valid
# ranges (step <= 1 s, max_substep >= 10 us, speed_window >= 0.1 ms) keep a step below
# 1.1e5; a core used directly with other values refuses a step above this bound instead of
# running for hours. Raise it here if a study really needs more work per step.
MAX_SUBSTEPS_PER_STEP = 200_000


class RobotPlantCore:
    """Two-wheeled robot driven by armature voltages; :mod:`.integrator` has the method.

    Parameters
    ----------
    parameters : PlantParameters, optional
        Defaults to the paper's robot. Validated here; the core keeps its own copy.

    Attributes
    ----------
    x, y, heading : float
        True pose of the axle midpoint [m, m, rad]; heading CCW from +x, not wrapped.
    speed, lateral_slip_speed, yaw_rate : float
        Body-frame forward and lateral (left positive) speed [m/s], yaw rate [rad/s].
    current_left, current_right : float
        Armature currents [A].
    wheel_omega_left, wheel_omega_right : float
        True wheel angular speeds [rad/s].
    slip_left, slip_right : float
        Longitudinal slip ratios at the end of the last step.
    voltage_left, voltage_right : float
        Voltages applied in the last step, after clamping to the supply [V].
    clamped : bool
        Whether the last step's input voltages were clamped.
    left_encoder, right_encoder : WheelEncoder
    odometry : EncoderOdometry
    time_ns : int
        Simulated time since start [ns].

    Examples
    --------
    >>> core = RobotPlantCore()
    >>> for _ in range(100):
    ...     core.step(6.0, 6.0, 0.01)
    """

    # The fault schedule is set from parameters and never changes: not part of the state.
    STATE_CONSTANTS = ("faults",)

    def __init__(self, parameters=None, fault_schedule=""):
        p = PlantParameters(**vars(parameters)) if parameters is not None else PlantParameters()
        self.faults = PlantFaults(parse_schedule(fault_schedule, "RobotPlant"))
        self.faults_active = 0
        self.parameters = p.validate()
        self.max_substep_ns = max(1, round(p.max_substep * _NS))
        self.window_ns = max(1, round(p.speed_window * _NS))
        # Derived constants, hoisted out of the substep.
        self.half_track = 0.5 * p.track_width
        self.wheel_load = 0.5 * p.mass * p.gravity
        self.tyre_peak = p.mu * self.wheel_load
        self.tyre_peak_left = self.tyre_peak_right = self.tyre_peak
        self.tyre_stiffness = p.slip_stiffness * self.wheel_load
        self.drive_torque_per_amp = p.gear_efficiency * p.gear_ratio * p.torque_constant
        self.drive_friction = p.gear_efficiency * p.gear_ratio ** 2 * p.motor_viscous_friction
        self.emf_per_wheel_speed = p.back_emf_constant * p.gear_ratio
        self.wheel_total_inertia = (p.wheel_inertia
                                    + p.gear_efficiency * p.gear_ratio ** 2 * p.rotor_inertia)
        # Coulomb friction at the wheel: eta N T_c tanh(N w / COULOMB_SPEED)
        self.coulomb_wheel_torque = p.gear_efficiency * p.gear_ratio * p.coulomb_friction
        self.coulomb_shaft_per_wheel = p.gear_ratio / COULOMB_SPEED
        # load torque against each wheel's forward rotation (the load_torque fault) [N m]
        self.load_torque_left = 0.0
        self.load_torque_right = 0.0
        self.current_left = 0.0
        self.current_right = 0.0
        self.wheel_omega_left = 0.0
        self.wheel_omega_right = 0.0
        self.speed = 0.0
        self.yaw_rate = 0.0
        self.lateral_slip_speed = 0.0
        self.x = p.x0
        self.y = p.y0
        self.heading = p.heading0
        self.slip_left = 0.0
        self.slip_right = 0.0
        self.voltage_left = 0.0
        self.voltage_right = 0.0
        self.clamped = False
        self.left_encoder = WheelEncoder(p.encoder_ppr, p.wheel_radius)
        self.right_encoder = WheelEncoder(p.encoder_ppr, p.wheel_radius)
        self.odometry = EncoderOdometry(p.x0, p.y0, p.heading0, p.track_width)
        self.time_ns = 0
        self.window_elapsed_ns = 0

    # ----- outputs derived from state ----------------------------------------------------
    @property
    def time(self):
        """Simulated time since start [s]."""
        return self.time_ns / _NS

    @property
    def encoder_left(self):
        """Left encoder count the MCU sees (int; a faulty encoder loses some)."""
        return self.left_encoder.reported_count

    @property
    def encoder_right(self):
        """Right encoder count the MCU sees (int)."""
        return self.right_encoder.reported_count

    @property
    def wheel_speed_left(self):
        """Left rim speed from encoder counts over the last speed window [m/s]."""
        return self.left_encoder.speed

    @property
    def wheel_speed_right(self):
        """Right rim speed from encoder counts over the last speed window [m/s]."""
        return self.right_encoder.speed

    @property
    def rim_speed_left(self):
        """True left rim speed ``r w`` [m/s]."""
        return self.parameters.wheel_radius * self.wheel_omega_left

    @property
    def rim_speed_right(self):
        """True right rim speed ``r w`` [m/s]."""
        return self.parameters.wheel_radius * self.wheel_omega_right

    @property
    def odom_x(self):
        """Encoder-only odometry x [m]."""
        return self.odometry.x

    @property
    def odom_y(self):
        """Encoder-only odometry y [m]."""
        return self.odometry.y

    @property
    def odom_heading(self):
        """Encoder-only odometry heading [rad]."""
        return self.odometry.heading

    # ----- stepping ----------------------------------------------------------------------
    def step(self, voltage_left, voltage_right, step_size):
        """Advance by ``step_size`` seconds with the armature voltages held.

        Parameters
        ----------
        voltage_left, voltage_right : float
            Armature voltages [V]; clamped to +-``v_supply`` (``clamped`` tells).
        step_size : float
            Communication step [s], > 0; resolved to whole nanoseconds.

        Raises
        ------
        InputError
            A voltage is NaN or infinite, or the step is not positive; the state is unchanged.
        """
        if not math.isfinite(voltage_left):
            raise InputError(f"RobotPlant input voltage_left = {voltage_left!r} is not finite")
        if not math.isfinite(voltage_right):
            raise InputError(f"RobotPlant input voltage_right = {voltage_right!r} is not finite")
        step_ns = round(step_size * _NS) if math.isfinite(step_size) else 0
        if step_ns <= 0:
            raise InputError(f"RobotPlant step_size = {step_size!r} must be > 0 "
                             "(at least 1 ns)")
        work = -(-step_ns // self.max_substep_ns) + step_ns // self.window_ns + 1
        if work > MAX_SUBSTEPS_PER_STEP:
            raise InputError(f"RobotPlant step_size = {step_size!r} s needs {work} substeps "
                             f"(max_substep = {self.parameters.max_substep!r} s, speed_window "
                             f"= {self.parameters.speed_window!r} s), more than "
                             f"MAX_SUBSTEPS_PER_STEP = {MAX_SUBSTEPS_PER_STEP}; take a shorter "
                             "step or a longer max_substep / speed_window")
        supply_left = supply_right = self.parameters.v_supply
        keep_left = keep_right = 1.0
        if self.faults:
            supply_left, supply_right, keep_left, keep_right = self._apply_faults()
        applied_left = min(supply_left, max(-supply_left, voltage_left))
        applied_right = min(supply_right, max(-supply_right, voltage_right))
        self.clamped = applied_left != voltage_left or applied_right != voltage_right
        self.voltage_left = applied_left
        self.voltage_right = applied_right

        remaining = step_ns
        while remaining > 0:
            span = min(remaining, self.window_ns - self.window_elapsed_ns)
            integrate_span(self, applied_left, applied_right, span,
                           -(-span // self.max_substep_ns))
            remaining -= span
            self.time_ns += span
            self.window_elapsed_ns += span
            if self.window_elapsed_ns == self.window_ns:
                window = self.window_ns / _NS
                self.left_encoder.sample(window, keep_left)
                self.right_encoder.sample(window, keep_right)
                self.window_elapsed_ns = 0
        self._update_slip()

    def _apply_faults(self):
        """Set each tyre's friction peak; return the supplies and encoder fractions, per wheel."""
        p, faults, time = self.parameters, self.faults, self.time
        self.faults_active = faults.count_active(time)
        left_x, left_y = -math.sin(self.heading), math.cos(self.heading)  # unit vector left
        half = self.half_track
        self.tyre_peak_left = self.wheel_load * faults.friction(
            time, "left", self.x + half * left_x, self.y + half * left_y, p.mu)
        self.tyre_peak_right = self.wheel_load * faults.friction(
            time, "right", self.x - half * left_x, self.y - half * left_y, p.mu)
        self.load_torque_left = faults.load_torque(time, "left")
        self.load_torque_right = faults.load_torque(time, "right")
        return (faults.supply(time, "left", p.v_supply), faults.supply(time, "right", p.v_supply),
                faults.encoder_keep(time, "left"), faults.encoder_keep(time, "right"))

    def _update_slip(self):
        p = self.parameters
        shift = self.half_track * self.yaw_rate
        self.slip_left = slip_ratio(p.wheel_radius * self.wheel_omega_left,
                                    self.speed - shift, p.slip_speed_floor)
        self.slip_right = slip_ratio(p.wheel_radius * self.wheel_omega_right,
                                     self.speed + shift, p.slip_speed_floor)
