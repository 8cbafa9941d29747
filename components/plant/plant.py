"""The robot plant core: two geared DC motors, wheels with traction, rigid body, encoders.

Integration scheme: every communication step is cut into equal internal substeps no longer
than ``max_substep`` (2 ms by default), and additionally at every encoder speed-sample
instant. Each substep is one step of ROS2, the two-stage, second-order Rosenbrock W-method of
Verwer et al. (1999) with ``gamma = 1 - 1/sqrt(2)``: the stiff couplings -- armature current
to wheel speed (L/R = 1 ms) and tyre force to wheel and body speed (time constants down to tens
of microseconds at low speed) -- enter the iteration matrix, the mild ones (Coriolis terms,
friction-circle cross terms, the slip normaliser's own derivative) are explicit. ROS2 is
second order for any such approximate Jacobian and L-stable on the modes it captures. The
linear system is solved by hand (per wheel elimination, then a 2x2 for forward speed and yaw
rate, and a scalar for the lateral speed), so a substep is a few hundred float operations and
allocates nothing.

The tyre law is stiff *and* strongly nonlinear near standstill and at the stick-slip
transition (its tangent stiffness drops from ``c N`` to almost zero within a few mm/s of slip),
where one linearisation per substep can overshoot into a spurious spinning wheel. So each
substep checks how far the tyre forces at its second stage lie from the linearisation it used;
if that defect, as a body speed change over the substep, exceeds ``substep_tolerance``, the
substep is redone as up to 16 equal pieces. A fast armature transient after a voltage step,
with the tyre in its linear range, does not trigger it. The decision depends only on the
state at the substep's start, so steps of 2 ms and 20 ms still give the same trajectory for
the same held inputs. Pose is advanced with the trapezoidal rule at the mid-step heading.
"""

import math

from ..common.errors import InputError
from ..common.faults import parse_schedule
from .encoder import WheelEncoder
from .faults import PlantFaults
from .odometry import EncoderOdometry
from .parameters import PlantParameters
from .traction import _LINEAR_SLIP, slip_ratio

__all__ = ["RobotPlantCore"]

_NS = 1_000_000_000
# Work bound of one communication step: integration substeps plus encoder samples. The valid
# ranges (step <= 1 s, max_substep >= 10 us, speed_window >= 0.1 ms) keep a step below
# 1.1e5; a core used directly with other values refuses a step above this bound instead of
# running for hours. Raise it here if a study really needs more work per step.
MAX_SUBSTEPS_PER_STEP = 200_000
# ROS2's L-stable choice with the smaller error constant (the other root is 1 + 1/sqrt 2).
_GAMMA = 1.0 - 1.0 / math.sqrt(2.0)
_MAX_PIECES = 16


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
            self._integrate(applied_left, applied_right, span,
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
        return (faults.supply(time, "left", p.v_supply), faults.supply(time, "right", p.v_supply),
                faults.encoder_keep(time, "left"), faults.encoder_keep(time, "right"))

    def _update_slip(self):
        p = self.parameters
        shift = self.half_track * self.yaw_rate
        self.slip_left = slip_ratio(p.wheel_radius * self.wheel_omega_left,
                                    self.speed - shift, p.slip_speed_floor)
        self.slip_right = slip_ratio(p.wheel_radius * self.wheel_omega_right,
                                     self.speed + shift, p.slip_speed_floor)

    def _integrate(self, voltage_left, voltage_right, span_ns, count):
        """Take ``count`` ROS2 substeps that together last ``span_ns`` nanoseconds.

        The hot loop of the plant, so it is written flat: state and constants live in locals
        for the whole span, the tyre law of :func:`.traction.traction_force` and the encoder
        count of :meth:`.WheelEncoder.turn` are inlined, and the linear system is solved by
        hand. Per substep, with ``W = M - gamma h A`` (``M`` the diagonal of inductances and
        inertias, ``A`` the stiff part of the Jacobian)::

            W k1 = f(z)
            W k2 = f(z + h k1) - 2 M k1
            z   += h (3 k1 + k2) / 2

        If the tyre forces at stage 2 differ from their linearisation in ``W`` by more than
        ``substep_tolerance`` (as ``h |defect| / m``), the substep is discarded (nothing has
        been written yet) and redone in pieces.

        ``W`` is factored once per substep: per wheel, the current and then the wheel speed are
        eliminated in favour of the contact point's ground speed ``u``
        (``k_i = a - c k_w``, ``k_w = p + q k_u``, rim force change ``alpha + beta k_u``),
        leaving a symmetric 2x2 in forward speed and yaw rate and a scalar for the lateral
        speed. ``c``, ``q``, ``beta`` and the 2x2 depend on ``W`` only; ``a``, ``p`` and
        ``alpha`` on the right-hand side.
        """
        prm = self.parameters
        radius = prm.wheel_radius
        half = self.half_track
        mass = prm.mass
        inertia = prm.yaw_inertia
        wheel_inertia = self.wheel_total_inertia
        inductance = prm.motor_inductance
        resistance = prm.motor_resistance
        emf = self.emf_per_wheel_speed
        torque_per_amp = self.drive_torque_per_amp
        friction = self.drive_friction
        floor = prm.slip_speed_floor
        stiffness = self.tyre_stiffness          # c N: force per unit slip at small slip
        # mu N per wheel: a low-friction patch (a fault) can lower one wheel's
        peak_left, peak_right = self.tyre_peak_left, self.tyre_peak_right
        stiffness_per_peak_left = stiffness / peak_left
        stiffness_per_peak_right = stiffness / peak_right
        # tanh is linear to round-off below
        linear_slip_left = _LINEAR_SLIP * peak_left / stiffness
        linear_slip_right = _LINEAR_SLIP * peak_right / stiffness
        tolerance2 = prm.substep_tolerance * prm.substep_tolerance
        radius2 = radius * radius
        two_mass = 2.0 * mass
        two_inertia = 2.0 * inertia
        two_wheel_inertia = 2.0 * wheel_inertia
        two_inductance = 2.0 * inductance
        hypot = math.hypot
        tanh = math.tanh
        cos = math.cos
        sin = math.sin
        floor_int = math.floor
        # State.
        i_left = self.current_left
        i_right = self.current_right
        w_left = self.wheel_omega_left
        w_right = self.wheel_omega_right
        v = self.speed
        wz = self.yaw_rate
        v_lat = self.lateral_slip_speed
        x = self.x
        y = self.y
        heading = self.heading
        left_encoder = self.left_encoder
        right_encoder = self.right_encoder
        counts_per_radian_left = left_encoder.counts_per_radian
        counts_per_radian_right = right_encoder.counts_per_radian
        phase_left = left_encoder.phase
        phase_right = right_encoder.phase
        count_left = left_encoder.count
        count_right = right_encoder.count
        per_count = left_encoder.distance_per_count
        advance_odometry = self.odometry.advance

        h = 0.0
        done = 0
        for k in range(1, count + 1):
            edge = span_ns * k // count
            grid_ns = edge - done
            done = edge
            pieces = 1
            piece = 0
            while piece < pieces:
                step_h = grid_ns / (pieces * _NS)
                if step_h != h:
                    h = step_h
                    g = _GAMMA * h
                    # Armature row: (L + g R) k_i + g E k_w = rhs.
                    inv_electric = 1.0 / (inductance + g * resistance)
                    c = g * emf * inv_electric
                    wheel_base = wheel_inertia + g * friction + g * torque_per_amp * c
                    g_torque = g * torque_per_amp
                    g_half = g * half
                    g_half2 = g_half * half
                    g_radius2 = g * radius2
                    half_h = 0.5 * h
                    h_per_mass2 = (h / mass) ** 2

                # ---- stage 1: rates and tyre stiffnesses at z ----
                # Left tyre (inlined traction_force; the slip scale's own derivative is
                # neglected in the Jacobian, as are the friction-circle cross terms).
                rim = radius * w_left
                ground = v - half * wz
                scale = rim if rim >= 0.0 else -rim      # max(|rim|, |ground|, floor)
                if ground > scale:
                    scale = ground
                elif -ground > scale:
                    scale = -ground
                if scale < floor:
                    scale = floor
                inv_scale = 1.0 / scale
                slip_long = (rim - ground) * inv_scale
                slip_lat = -v_lat * inv_scale
                slip = hypot(slip_long, slip_lat)
                if slip < linear_slip_left:
                    force_left = stiffness * slip_long
                    lat_left = stiffness * slip_lat
                    stiff_left = stiffness * inv_scale
                    lat_stiff = stiff_left
                else:
                    t = tanh(stiffness_per_peak_left * slip)
                    secant = peak_left * t / slip
                    tangent = stiffness * (1.0 - t * t)
                    share = slip_long * slip_long / (slip * slip)
                    force_left = secant * slip_long
                    lat_left = secant * slip_lat
                    stiff_left = (tangent * share + secant * (1.0 - share)) * inv_scale
                    lat_stiff = (tangent * (1.0 - share) + secant * share) * inv_scale
                # Right tyre.
                rim = radius * w_right
                ground = v + half * wz
                scale = rim if rim >= 0.0 else -rim      # max(|rim|, |ground|, floor)
                if ground > scale:
                    scale = ground
                elif -ground > scale:
                    scale = -ground
                if scale < floor:
                    scale = floor
                inv_scale = 1.0 / scale
                slip_long = (rim - ground) * inv_scale
                slip_lat = -v_lat * inv_scale
                slip = hypot(slip_long, slip_lat)
                if slip < linear_slip_right:
                    force_right = stiffness * slip_long
                    lat_right = stiffness * slip_lat
                    stiff_right = stiffness * inv_scale
                    lat_stiff += stiff_right
                else:
                    t = tanh(stiffness_per_peak_right * slip)
                    secant = peak_right * t / slip
                    tangent = stiffness * (1.0 - t * t)
                    share = slip_long * slip_long / (slip * slip)
                    force_right = secant * slip_long
                    lat_right = secant * slip_lat
                    stiff_right = (tangent * share + secant * (1.0 - share)) * inv_scale
                    lat_stiff += (tangent * (1.0 - share) + secant * share) * inv_scale

                # ---- factor W ----
                inv_den_left = 1.0 / (wheel_base + g_radius2 * stiff_left)
                inv_den_right = 1.0 / (wheel_base + g_radius2 * stiff_right)
                stiff_radius_left = stiff_left * radius
                stiff_radius_right = stiff_right * radius
                q_left = g * stiff_radius_left * inv_den_left
                q_right = g * stiff_radius_right * inv_den_right
                beta_left = stiff_left * (radius * q_left - 1.0)      # <= 0
                beta_right = stiff_right * (radius * q_right - 1.0)
                beta_sum = beta_left + beta_right
                m11 = mass - g * beta_sum
                m12 = -g_half * (beta_right - beta_left)
                m22 = inertia - g_half2 * beta_sum
                inv_det = 1.0 / (m11 * m22 - m12 * m12)
                inv_lat = 1.0 / (mass + g * lat_stiff)

                # ---- solve W k1 = f(z) ----
                a_left = (voltage_left - resistance * i_left - emf * w_left) * inv_electric
                a_right = (voltage_right - resistance * i_right - emf * w_right) * inv_electric
                p_left = (torque_per_amp * i_left - friction * w_left - radius * force_left
                          + g_torque * a_left) * inv_den_left
                p_right = (torque_per_amp * i_right - friction * w_right - radius * force_right
                           + g_torque * a_right) * inv_den_right
                alpha_left = stiff_radius_left * p_left
                alpha_right = stiff_radius_right * p_right
                rhs_speed = (force_left + force_right + mass * wz * v_lat
                             + g * (alpha_left + alpha_right))
                rhs_yaw = half * (force_right - force_left) + g_half * (alpha_right - alpha_left)
                k1_v = (m22 * rhs_speed - m12 * rhs_yaw) * inv_det
                k1_wz = (m11 * rhs_yaw - m12 * rhs_speed) * inv_det
                k1_w_left = p_left + q_left * (k1_v - half * k1_wz)
                k1_w_right = p_right + q_right * (k1_v + half * k1_wz)
                k1_i_left = a_left - c * k1_w_left
                k1_i_right = a_right - c * k1_w_right
                k1_lat = (lat_left + lat_right - mass * wz * v) * inv_lat

                # ---- stage 2: rates at z + h k1 ----
                stage1_left = force_left
                stage1_right = force_right
                stage1_lat = lat_left + lat_right
                s_i_left = i_left + h * k1_i_left
                s_i_right = i_right + h * k1_i_right
                s_w_left = w_left + h * k1_w_left
                s_w_right = w_right + h * k1_w_right
                s_v = v + h * k1_v
                s_wz = wz + h * k1_wz
                s_lat = v_lat + h * k1_lat
                rim = radius * s_w_left
                ground = s_v - half * s_wz
                scale = rim if rim >= 0.0 else -rim      # max(|rim|, |ground|, floor)
                if ground > scale:
                    scale = ground
                elif -ground > scale:
                    scale = -ground
                if scale < floor:
                    scale = floor
                inv_scale = 1.0 / scale
                slip_long = (rim - ground) * inv_scale
                slip_lat = -s_lat * inv_scale
                slip = hypot(slip_long, slip_lat)
                if slip < linear_slip_left:
                    force_left = stiffness * slip_long
                    lat_left = stiffness * slip_lat
                else:
                    secant = peak_left * tanh(stiffness_per_peak_left * slip) / slip
                    force_left = secant * slip_long
                    lat_left = secant * slip_lat
                rim = radius * s_w_right
                ground = s_v + half * s_wz
                scale = rim if rim >= 0.0 else -rim      # max(|rim|, |ground|, floor)
                if ground > scale:
                    scale = ground
                elif -ground > scale:
                    scale = -ground
                if scale < floor:
                    scale = floor
                inv_scale = 1.0 / scale
                slip_long = (rim - ground) * inv_scale
                slip_lat = -s_lat * inv_scale
                slip = hypot(slip_long, slip_lat)
                if slip < linear_slip_right:
                    force_right = stiffness * slip_long
                    lat_right = stiffness * slip_lat
                else:
                    secant = peak_right * tanh(stiffness_per_peak_right * slip) / slip
                    force_right = secant * slip_long
                    lat_right = secant * slip_lat

                # ---- solve W k2 = f(z + h k1) - 2 M k1 ----
                a_left = (voltage_left - resistance * s_i_left - emf * s_w_left
                          - two_inductance * k1_i_left) * inv_electric
                a_right = (voltage_right - resistance * s_i_right - emf * s_w_right
                           - two_inductance * k1_i_right) * inv_electric
                p_left = (torque_per_amp * s_i_left - friction * s_w_left - radius * force_left
                          - two_wheel_inertia * k1_w_left + g_torque * a_left) * inv_den_left
                p_right = (torque_per_amp * s_i_right - friction * s_w_right - radius * force_right
                           - two_wheel_inertia * k1_w_right + g_torque * a_right) * inv_den_right
                alpha_left = stiff_radius_left * p_left
                alpha_right = stiff_radius_right * p_right
                rhs_speed = (force_left + force_right + mass * s_wz * s_lat - two_mass * k1_v
                             + g * (alpha_left + alpha_right))
                rhs_yaw = (half * (force_right - force_left) - two_inertia * k1_wz
                           + g_half * (alpha_right - alpha_left))
                k2_v = (m22 * rhs_speed - m12 * rhs_yaw) * inv_det
                k2_wz = (m11 * rhs_yaw - m12 * rhs_speed) * inv_det
                k2_w_left = p_left + q_left * (k2_v - half * k2_wz)
                k2_w_right = p_right + q_right * (k2_v + half * k2_wz)
                k2_i_left = a_left - c * k2_w_left
                k2_i_right = a_right - c * k2_w_right
                k2_lat = (lat_left + lat_right - mass * s_wz * s_v - two_mass * k1_lat) * inv_lat

                if pieces == 1:
                    # How far the tyre forces at stage 2 are from the linearisation in W
                    # (zero for a linear tyre, however fast the armature transient), as the
                    # body speed change it would cause over h [m/s], squared.
                    defect_left = force_left - stage1_left - stiff_left * h * (
                        radius * k1_w_left - k1_v + half * k1_wz)
                    defect_right = force_right - stage1_right - stiff_right * h * (
                        radius * k1_w_right - k1_v - half * k1_wz)
                    defect_lat = lat_left + lat_right - stage1_lat + lat_stiff * h * k1_lat
                    error2 = h_per_mass2 * (defect_left * defect_left
                                            + defect_right * defect_right
                                            + defect_lat * defect_lat)
                    if error2 > tolerance2:
                        # The defect grows like h^2: split accordingly.
                        pieces = min(_MAX_PIECES,
                                     1 + int(math.sqrt(math.sqrt(error2 / tolerance2))))
                        continue
                piece += 1

                # ---- update: z += h (3 k1 + k2) / 2 ----
                i_left += half_h * (3.0 * k1_i_left + k2_i_left)
                i_right += half_h * (3.0 * k1_i_right + k2_i_right)
                d_w_left = half_h * (3.0 * k1_w_left + k2_w_left)
                d_w_right = half_h * (3.0 * k1_w_right + k2_w_right)
                d_v = half_h * (3.0 * k1_v + k2_v)
                d_wz = half_h * (3.0 * k1_wz + k2_wz)
                d_lat = half_h * (3.0 * k1_lat + k2_lat)

                # Pose and wheel angles: trapezoidal rule on the speeds, mid-step heading.
                turn = h * (wz + 0.5 * d_wz)
                forward = h * (v + 0.5 * d_v)
                sideways = h * (v_lat + 0.5 * d_lat)
                cos_mid = cos(heading + 0.5 * turn)
                sin_mid = sin(heading + 0.5 * turn)
                x += forward * cos_mid - sideways * sin_mid
                y += forward * sin_mid + sideways * cos_mid
                heading += turn
                # Encoders (inlined WheelEncoder.turn) and the odometry they feed.
                phase_left += h * (w_left + 0.5 * d_w_left) * counts_per_radian_left
                crossed_left = floor_int(phase_left)
                if crossed_left:
                    phase_left -= crossed_left
                    count_left += crossed_left
                phase_right += h * (w_right + 0.5 * d_w_right) * counts_per_radian_right
                crossed_right = floor_int(phase_right)
                if crossed_right:
                    phase_right -= crossed_right
                    count_right += crossed_right
                if crossed_left or crossed_right:
                    advance_odometry(crossed_left * per_count, crossed_right * per_count)

                w_left += d_w_left
                w_right += d_w_right
                v += d_v
                wz += d_wz
                v_lat += d_lat

        self.current_left = i_left
        self.current_right = i_right
        self.wheel_omega_left = w_left
        self.wheel_omega_right = w_right
        self.speed = v
        self.yaw_rate = wz
        self.lateral_slip_speed = v_lat
        self.x = x
        self.y = y
        self.heading = heading
        left_encoder.phase = phase_left
        right_encoder.phase = phase_right
        left_encoder.count = count_left
        right_encoder.count = count_right
