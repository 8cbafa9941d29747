"""The robot plant core: two geared DC motors, wheels with traction, rigid body, encoders.

Integration scheme: every communication step is cut into equal internal substeps no longer
than ``max_substep`` (1 ms by default), and additionally at every encoder speed-sample
instant. Each substep is one linearly implicit (Rosenbrock-Euler, W-method) step: the stiff
couplings -- armature current to wheel speed (L/R = 1 ms) and tyre force to wheel and body
speed (time constants down to tens of microseconds at low speed) -- are taken implicitly, the
mild ones (Coriolis terms, friction-circle cross terms) explicitly. The linear system is solved
by hand (per wheel elimination, then a 2x2 for forward speed and yaw rate, and a scalar for
the lateral speed), so a substep is a few hundred float operations and allocates no arrays.
The scheme is L-stable on the stiff modes, so any communication step is stable; because
substeps depend only on ``max_substep``, steps of 1 ms and 20 ms give the same trajectory for
the same held inputs. Pose is advanced with the trapezoidal rule at the mid-step heading.
"""

import math

from ..common.errors import InputError
from .encoder import WheelEncoder
from .odometry import EncoderOdometry
from .parameters import PlantParameters
from .traction import slip_ratio, traction_force

__all__ = ["RobotPlantCore"]

_NS = 1_000_000_000


class RobotPlantCore:
    """Two-wheeled robot driven by armature voltages; see the module docstring for the method.

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

    def __init__(self, parameters=None):
        p = PlantParameters(**vars(parameters)) if parameters is not None else PlantParameters()
        self.parameters = p.validate()
        self.max_substep_ns = max(1, round(p.max_substep * _NS))
        self.window_ns = max(1, round(p.speed_window * _NS))
        # Derived constants, hoisted out of the substep.
        self.half_track = 0.5 * p.track_width
        self.wheel_load = 0.5 * p.mass * p.gravity
        self.drive_torque_per_amp = p.gear_efficiency * p.gear_ratio * p.torque_constant
        self.drive_friction = p.gear_efficiency * p.gear_ratio ** 2 * p.motor_viscous_friction
        self.emf_per_wheel_speed = p.back_emf_constant * p.gear_ratio
        self.wheel_total_inertia = (p.wheel_inertia
                                    + p.gear_efficiency * p.gear_ratio ** 2 * p.rotor_inertia)
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
        """Left encoder count (int)."""
        return self.left_encoder.count

    @property
    def encoder_right(self):
        """Right encoder count (int)."""
        return self.right_encoder.count

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
        supply = self.parameters.v_supply
        applied_left = min(supply, max(-supply, voltage_left))
        applied_right = min(supply, max(-supply, voltage_right))
        self.clamped = applied_left != voltage_left or applied_right != voltage_right
        self.voltage_left = applied_left
        self.voltage_right = applied_right

        remaining = step_ns
        while remaining > 0:
            span = min(remaining, self.window_ns - self.window_elapsed_ns)
            count = -(-span // self.max_substep_ns)
            done = 0
            for k in range(1, count + 1):
                edge = span * k // count
                self._substep(applied_left, applied_right, (edge - done) / _NS)
                done = edge
            remaining -= span
            self.time_ns += span
            self.window_elapsed_ns += span
            if self.window_elapsed_ns == self.window_ns:
                window = self.window_ns / _NS
                self.left_encoder.sample(window)
                self.right_encoder.sample(window)
                self.window_elapsed_ns = 0
        self._update_slip()

    def _update_slip(self):
        p = self.parameters
        shift = self.half_track * self.yaw_rate
        self.slip_left = slip_ratio(p.wheel_radius * self.wheel_omega_left,
                                    self.speed - shift, p.slip_speed_floor)
        self.slip_right = slip_ratio(p.wheel_radius * self.wheel_omega_right,
                                     self.speed + shift, p.slip_speed_floor)

    def _wheel(self, h, voltage, current, omega, ground_speed):
        """Eliminate one wheel's current and speed from the linearly implicit step.

        Returns the rim force, lateral force and lateral stiffness/scale at the start of the
        substep, and the coefficients of ``d_omega = p + q d_u``, ``d_i = a - c d_omega`` and
        ``d_force = alpha + beta d_u`` (``d_u``: change of the contact point's ground speed).
        """
        prm = self.parameters
        radius = prm.wheel_radius
        rim = radius * omega
        scale = max(abs(rim), abs(ground_speed), prm.slip_speed_floor)
        force_long, force_lat, stiff_long, stiff_lat = traction_force(
            (rim - ground_speed) / scale, -self.lateral_slip_speed / scale,
            self.wheel_load, prm.mu, prm.slip_stiffness)
        stiff_long /= scale
        # Armature row: (1 + h R/L) di + h (Ke N / L) dw = h di/dt.
        electric = 1.0 + h * prm.motor_resistance / prm.motor_inductance
        a = h * (voltage - prm.motor_resistance * current - self.emf_per_wheel_speed * omega) \
            / (prm.motor_inductance * electric)
        c = h * self.emf_per_wheel_speed / (prm.motor_inductance * electric)
        torque = (self.drive_torque_per_amp * current - self.drive_friction * omega
                  - radius * force_long)
        denominator = (self.wheel_total_inertia + h * self.drive_friction
                       + h * radius * radius * stiff_long + h * self.drive_torque_per_amp * c)
        p = h * (torque + self.drive_torque_per_amp * a) / denominator
        q = h * radius * stiff_long / denominator
        alpha = stiff_long * radius * p
        beta = stiff_long * (radius * q - 1.0)
        return force_long, force_lat, stiff_lat / scale, p, q, a, c, alpha, beta

    def _substep(self, voltage_left, voltage_right, h):
        prm = self.parameters
        mass = prm.mass
        inertia = prm.yaw_inertia
        half = self.half_track
        v = self.speed
        yaw_rate = self.yaw_rate
        v_lat = self.lateral_slip_speed
        omega_left = self.wheel_omega_left
        omega_right = self.wheel_omega_right
        (force_left, lat_left, lat_stiff_left, p_left, q_left, a_left, c_left,
         alpha_left, beta_left) = self._wheel(h, voltage_left, self.current_left, omega_left,
                                              v - half * yaw_rate)
        (force_right, lat_right, lat_stiff_right, p_right, q_right, a_right, c_right,
         alpha_right, beta_right) = self._wheel(h, voltage_right, self.current_right,
                                                omega_right, v + half * yaw_rate)
        # Forward speed and yaw rate: a symmetric positive definite 2x2 (beta <= 0).
        beta_sum = beta_left + beta_right
        beta_diff = beta_right - beta_left
        m11 = mass - h * beta_sum
        m12 = -h * half * beta_diff
        m22 = inertia - h * half * half * beta_sum
        g_speed = h * (force_left + force_right + mass * yaw_rate * v_lat
                       + alpha_left + alpha_right)
        g_yaw = h * half * (force_right - force_left + alpha_right - alpha_left)
        determinant = m11 * m22 - m12 * m12
        d_speed = (g_speed * m22 - m12 * g_yaw) / determinant
        d_yaw = (m11 * g_yaw - m12 * g_speed) / determinant
        d_omega_left = p_left + q_left * (d_speed - half * d_yaw)
        d_omega_right = p_right + q_right * (d_speed + half * d_yaw)
        d_lat = h * (lat_left + lat_right - mass * yaw_rate * v) \
            / (mass + h * (lat_stiff_left + lat_stiff_right))

        self.current_left += a_left - c_left * d_omega_left
        self.current_right += a_right - c_right * d_omega_right
        self.wheel_omega_left = omega_left + d_omega_left
        self.wheel_omega_right = omega_right + d_omega_right
        self.speed = v + d_speed
        self.yaw_rate = yaw_rate + d_yaw
        self.lateral_slip_speed = v_lat + d_lat

        # Pose and wheel angles: trapezoidal rule on the speeds, mid-step heading.
        heading_mid = self.heading + 0.25 * h * (2.0 * yaw_rate + d_yaw)
        forward = h * (v + 0.5 * d_speed)
        sideways = h * (v_lat + 0.5 * d_lat)
        cos_mid = math.cos(heading_mid)
        sin_mid = math.sin(heading_mid)
        self.x += forward * cos_mid - sideways * sin_mid
        self.y += forward * sin_mid + sideways * cos_mid
        self.heading += h * (yaw_rate + 0.5 * d_yaw)
        crossed_left = self.left_encoder.turn(h * (omega_left + 0.5 * d_omega_left))
        crossed_right = self.right_encoder.turn(h * (omega_right + 0.5 * d_omega_right))
        if crossed_left or crossed_right:
            per_count = self.left_encoder.distance_per_count
            self.odometry.advance(crossed_left * per_count, crossed_right * per_count)
