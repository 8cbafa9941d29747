"""Continuous-time equations of the robot plant: motors, gearboxes, wheels, tyres and body.

The body is the paper's Eqs. (29)-(30) written in the body frame and extended with tyre
traction: the wheels are separate rotating bodies driven by their motors, and the floor pushes
on each through a slip-dependent, friction-circle-limited force (:mod:`.traction`). The body may
therefore slide sideways (``lateral_speed``) when the centripetal demand exceeds what
friction can give. The centre of mass is taken on the axle midpoint, so each driven wheel
carries half the weight and the lateral forces exert no yaw moment (the ball caster is
free to swivel and carries no significant load).
"""

import math

from .traction import traction_force

__all__ = ["STATE_NAMES", "plant_rates", "COULOMB_SPEED", "coulomb_torque"]

# Motor-shaft speed [rad/s] over which the Coulomb torque changes sign (its tanh
# regularisation): 0.1 rad/s at the shaft is 0.43 mm/s at the rim, so a wheel held by
# stiction creeps at most (r COULOMB_SPEED / N) atanh(T / T_c), 0.24 mm/s at half the
# break-away torque, while the friction stays a smooth function the implicit integrator
# can linearise.
COULOMB_SPEED = 0.1


def coulomb_torque(coulomb_friction, shaft_speed):
    """Coulomb friction torque at the motor shaft [N m] for a shaft speed [rad/s]."""
    return coulomb_friction * math.tanh(shaft_speed / COULOMB_SPEED)

STATE_NAMES = (
    "current_left", "current_right", "wheel_omega_left", "wheel_omega_right",
    "speed", "yaw_rate", "lateral_speed", "x", "y", "heading",
)


def plant_rates(parameters, state, voltage_left, voltage_right, load_left=0.0, load_right=0.0):
    """Time derivatives of the plant state for held armature voltages.

    Parameters
    ----------
    parameters : PlantParameters
    state : sequence of float
        Values in the order of :data:`STATE_NAMES`: armature currents [A], wheel speeds
        [rad/s], forward speed [m/s], yaw rate [rad/s], lateral speed (left positive) [m/s],
        world position [m] and heading [rad].
    voltage_left, voltage_right : float
        Armature voltages [V] (already within the supply).
    load_left, load_right : float
        Load torques against each wheel's forward rotation [N m at the wheel].

    Returns
    -------
    list of float
        The derivatives, in the same order.

    Notes
    -----
    Per wheel (gear ratio ``N``, efficiency ``eta``, rim force ``F``)::

        L di/dt = V - R i - Ke N w
        J_eff dw/dt = eta N (Kt i - b N w - T_c tanh(N w / w_c)) - r F - T_load,
        J_eff = J_wheel + eta N^2 J_rotor

    Body, with half track ``a`` (the paper's Eq. (29) uses ``2a`` as the moment arm; each
    rim force acts at ``a`` from the centre)::

        m (dv/dt - yaw_rate * v_lat) = F_left + F_right
        m (dv_lat/dt + yaw_rate * v) = F_lat
        I d(yaw_rate)/dt = a (F_right - F_left)
    """
    p = parameters
    (i_left, i_right, w_left, w_right, v, yaw_rate, v_lat, _x, _y, heading) = state
    half_track = 0.5 * p.track_width
    wheel_load = 0.5 * p.mass * p.gravity
    drive = p.gear_efficiency * p.gear_ratio
    inertia = p.wheel_inertia + drive * p.gear_ratio * p.rotor_inertia
    rates = [0.0] * 10
    lateral_force = 0.0
    rim_forces = []
    for side, (voltage, current, omega, load) in enumerate(
            ((voltage_left, i_left, w_left, load_left),
             (voltage_right, i_right, w_right, load_right))):
        ground = v + (2 * side - 1) * half_track * yaw_rate
        rim = p.wheel_radius * omega
        scale = max(abs(rim), abs(ground), p.slip_speed_floor)
        force_long, force_lat, _, _ = traction_force(
            (rim - ground) / scale, -v_lat / scale, wheel_load, p.mu, p.slip_stiffness)
        rim_forces.append(force_long)
        lateral_force += force_lat
        rates[side] = (voltage - p.motor_resistance * current
                       - p.back_emf_constant * p.gear_ratio * omega) / p.motor_inductance
        rates[2 + side] = (drive * (p.torque_constant * current
                                    - p.motor_viscous_friction * p.gear_ratio * omega
                                    - coulomb_torque(p.coulomb_friction, p.gear_ratio * omega))
                           - p.wheel_radius * force_long - load) / inertia
    rates[4] = (rim_forces[0] + rim_forces[1]) / p.mass + yaw_rate * v_lat
    rates[5] = half_track * (rim_forces[1] - rim_forces[0]) / p.yaw_inertia
    rates[6] = lateral_force / p.mass - yaw_rate * v
    rates[7] = v * math.cos(heading) - v_lat * math.sin(heading)
    rates[8] = v * math.sin(heading) + v_lat * math.cos(heading)
    rates[9] = yaw_rate
    return rates
