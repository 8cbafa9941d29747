"""Tyre-floor traction: slip of a wheel and the friction-circle force it transmits."""

import math

__all__ = ["slip_ratio", "traction_force"]

# Below this combined slip the force law is linear to machine precision (tanh z = z - z^3/3).
_LINEAR_SLIP = 1e-9


def slip_ratio(rim_speed, ground_speed, speed_floor):
    """Longitudinal slip ratio ``(r w - u) / max(|r w|, |u|, speed_floor)``.

    Parameters
    ----------
    rim_speed : float
        Wheel rim speed ``r w`` [m/s].
    ground_speed : float
        Forward speed of the contact point over the floor [m/s].
    speed_floor : float
        Normaliser at standstill [m/s].

    Returns
    -------
    float
        Positive while driving (the wheel turns faster than it travels), negative while
        braking, 0 when rolling; within [-1, 1] while rim and ground speed have the same sign,
        up to +-2 when the wheel spins against the direction of travel.
    """
    scale = max(abs(rim_speed), abs(ground_speed), speed_floor)
    return (rim_speed - ground_speed) / scale


def traction_force(slip_long, slip_lat, normal_force, mu, slip_stiffness):
    """Force one tyre transmits for a combined slip, saturating on the friction circle.

    The force points along the slip vector with magnitude ``mu N tanh(c s / mu)``, where
    ``s`` is the length of the slip vector and ``c`` the slip stiffness per newton: linear
    (``c N s``) for small slip and never more than ``mu N``, in any direction.

    Parameters
    ----------
    slip_long, slip_lat : float
        Longitudinal slip ratio and lateral slip (lateral contact speed over the same scale,
        sign chosen so the force opposes the sliding).
    normal_force : float
        Load on the wheel [N].
    mu : float
        Friction coefficient.
    slip_stiffness : float
        Initial slope of force over slip per newton of load.

    Returns
    -------
    tuple of float
        ``(force_long, force_lat, stiffness_long, stiffness_lat)``: the force components [N]
        and their derivatives with respect to their own slip component [N], which the plant's
        linearly implicit integrator needs.
    """
    peak = mu * normal_force
    stiffness = slip_stiffness * normal_force
    slip = math.hypot(slip_long, slip_lat)
    if slip * stiffness < _LINEAR_SLIP * peak:
        return stiffness * slip_long, stiffness * slip_lat, stiffness, stiffness
    t = math.tanh(stiffness * slip / peak)
    secant = peak * t / slip
    tangent = stiffness * (1.0 - t * t)
    share_long = slip_long * slip_long / (slip * slip)
    share_lat = 1.0 - share_long
    return (secant * slip_long, secant * slip_lat,
            tangent * share_long + secant * share_lat,
            tangent * share_lat + secant * share_long)
