"""Differential-drive kinematics (paper Eqs. (30)-(31))."""

import math

__all__ = ["body_velocity", "turn_radius"]


def body_velocity(wheel_speed_left, wheel_speed_right, track_width):
    """Forward speed [m/s] and yaw rate [rad/s] of a differential drive rolling without slip.

    Parameters
    ----------
    wheel_speed_left, wheel_speed_right : float
        Rim speeds of the wheels [m/s].
    track_width : float
        Distance between the wheel contact points [m].

    Returns
    -------
    tuple of float
        ``(v, yaw_rate)``, yaw rate counter-clockwise positive.
    """
    return (0.5 * (wheel_speed_left + wheel_speed_right),
            (wheel_speed_right - wheel_speed_left) / track_width)


def turn_radius(wheel_speed_left, wheel_speed_right, track_width):
    """Signed radius of the path of the axle midpoint, Eq. (31): ``(L/2)(vR+vL)/(vR-vL)``.

    Positive for a left (counter-clockwise) turn; ``inf`` when the wheel speeds are equal.
    """
    difference = wheel_speed_right - wheel_speed_left
    if difference == 0.0:
        return math.inf
    return 0.5 * track_width * (wheel_speed_right + wheel_speed_left) / difference
