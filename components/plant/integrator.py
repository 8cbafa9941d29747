"""ROS2 Rosenbrock substeps of the robot plant over one span of held voltages.

Each substep is one step of ROS2, the two-stage, second-order Rosenbrock W-method of Verwer
et al. (1999) with ``gamma = 1 - 1/sqrt(2)``: the stiff couplings (armature current to wheel
speed, L/R = 1 ms; tyre force to wheel and body speed, down to tens of microseconds near
standstill) enter the iteration matrix, the mild ones (Coriolis, friction-circle cross terms,
the slip normaliser's derivative) stay explicit. The linear system is solved by hand, so a
substep is a few hundred float operations and allocates nothing. Because the tyre law is
strongly nonlinear at the stick-slip knee, a substep whose stage-2 tyre forces stray from
their linearisation by more than ``substep_tolerance`` (as a body speed change) is redone as
up to 16 equal pieces; the decision depends only on the state at the substep's start, so 2 ms
and 20 ms communication steps give the same trajectory. Pose and wheel angles use the
trapezoidal rule at the mid-step heading. Rationale and measured accuracy: docs/plant.md.
"""

import math

from .traction import _LINEAR_SLIP

__all__ = ["integrate_span"]

_NS = 1_000_000_000  # nanoseconds per second; time is counted in integer ns
# ROS2's L-stable choice with the smaller error constant (the other root is 1 + 1/sqrt 2).
_GAMMA = 1.0 - 1.0 / math.sqrt(2.0)
_MAX_PIECES = 16


def integrate_span(core, voltage_left, voltage_right, span_ns, count):
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

    Parameters
    ----------
    core : RobotPlantCore
        Its state (currents, wheel and body speeds, pose, encoder phases and counts,
        odometry) is read at the start of the span and written back at its end.
    voltage_left, voltage_right : float
        Armature voltages held over the span, already clamped [V].
    span_ns : int
        Length of the span [ns]; it ends at or before the next encoder speed sample.
    count : int
        Number of equal grid substeps (each may be split further, see above).
    """
    prm = core.parameters
    radius = prm.wheel_radius
    half = core.half_track
    mass = prm.mass
    inertia = prm.yaw_inertia
    wheel_inertia = core.wheel_total_inertia
    inductance = prm.motor_inductance
    resistance = prm.motor_resistance
    emf = core.emf_per_wheel_speed
    torque_per_amp = core.drive_torque_per_amp
    friction = core.drive_friction
    # Coulomb friction (eta N T_c tanh(N w / w_c) at the wheel) and the loads: explicit
    # torques, the Coulomb slope joins W so that stiction at rest stays stable
    coulomb = core.coulomb_wheel_torque
    coulomb_rate = core.coulomb_shaft_per_wheel
    load_left, load_right = core.load_torque_left, core.load_torque_right
    floor = prm.slip_speed_floor
    stiffness = core.tyre_stiffness          # c N: force per unit slip at small slip
    # mu N per wheel: a low-friction patch (a fault) can lower one wheel's
    peak_left, peak_right = core.tyre_peak_left, core.tyre_peak_right
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
    i_left = core.current_left
    i_right = core.current_right
    w_left = core.wheel_omega_left
    w_right = core.wheel_omega_right
    v = core.speed
    wz = core.yaw_rate
    v_lat = core.lateral_slip_speed
    x = core.x
    y = core.y
    heading = core.heading
    left_encoder = core.left_encoder
    right_encoder = core.right_encoder
    counts_per_radian_left = left_encoder.counts_per_radian
    counts_per_radian_right = right_encoder.counts_per_radian
    phase_left = left_encoder.phase
    phase_right = right_encoder.phase
    count_left = left_encoder.count
    count_right = right_encoder.count
    per_count = left_encoder.distance_per_count
    advance_odometry = core.odometry.advance

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
            extra_left, extra_right = load_left, load_right
            base_left = base_right = wheel_base
            if coulomb:
                t = tanh(coulomb_rate * w_left)
                extra_left += coulomb * t
                base_left += g * coulomb * coulomb_rate * (1.0 - t * t)
                t = tanh(coulomb_rate * w_right)
                extra_right += coulomb * t
                base_right += g * coulomb * coulomb_rate * (1.0 - t * t)
            inv_den_left = 1.0 / (base_left + g_radius2 * stiff_left)
            inv_den_right = 1.0 / (base_right + g_radius2 * stiff_right)
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
                      - extra_left + g_torque * a_left) * inv_den_left
            p_right = (torque_per_amp * i_right - friction * w_right - radius * force_right
                       - extra_right + g_torque * a_right) * inv_den_right
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
            extra_left, extra_right = load_left, load_right
            if coulomb:
                extra_left += coulomb * tanh(coulomb_rate * s_w_left)
                extra_right += coulomb * tanh(coulomb_rate * s_w_right)
            a_left = (voltage_left - resistance * s_i_left - emf * s_w_left
                      - two_inductance * k1_i_left) * inv_electric
            a_right = (voltage_right - resistance * s_i_right - emf * s_w_right
                       - two_inductance * k1_i_right) * inv_electric
            p_left = (torque_per_amp * s_i_left - friction * s_w_left - radius * force_left
                      - extra_left - two_wheel_inertia * k1_w_left
                      + g_torque * a_left) * inv_den_left
            p_right = (torque_per_amp * s_i_right - friction * s_w_right - radius * force_right
                       - extra_right - two_wheel_inertia * k1_w_right
                       + g_torque * a_right) * inv_den_right
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

    core.current_left = i_left
    core.current_right = i_right
    core.wheel_omega_left = w_left
    core.wheel_omega_right = w_right
    core.speed = v
    core.yaw_rate = wz
    core.lateral_slip_speed = v_lat
    core.x = x
    core.y = y
    core.heading = heading
    left_encoder.phase = phase_left
    right_encoder.phase = phase_right
    left_encoder.count = count_left
    right_encoder.count = count_right
