"""Arc geometry of the paper's curvature planner (Sec. 3.3-3.4, Eqs. 36-42).

Sign convention: bearing ``theta`` is measured from the robot's heading, counter-clockwise
(left) positive, so the paper's "45 deg to the right" is ``theta = -pi/4``. Curvature ``kappa``
has the same sign: positive turns left. The paper's radius (Eq. 36) is ``R = 1 / |kappa|``.
"""

import math

__all__ = [
    "RADIUS_STRAIGHT",
    "RESOLVABLE_DISTANCE",
    "arc_curvature",
    "arc_length",
    "stop_arc_length",
    "wheel_factors",
    "wheel_arc_lengths",
    "radius_of",
]

# Finite stand-in for the infinite radius of a straight path (kappa = 0 is the exact statement):
# FMI Reals may carry inf, but CSV recorders, plots and SSP tools handle a finite value better.
RADIUS_STRAIGHT = 1.0e6

# A fix nearer than this is at the target: far below the encoders' 0.52 mm per count and the
# localizer's resolution, and large enough that 2 sin(theta) / D stays finite (a subnormal D
# overflowed the curvature to inf and the wheel speeds to NaN).
RESOLVABLE_DISTANCE = 1.0e-9


def arc_curvature(distance, bearing):
    """Signed curvature [1/m] of the arc through a target, tangent to the heading (Eq. 36).

    Eq. (36) gives ``R = D / (2 cos(90 deg - theta)) = D / (2 sin theta)``; its inverse
    ``kappa = 2 sin(theta) / D`` is finite at ``theta = 0`` (a straight line, no division by
    zero) and gives the semicircle ``R = D / 2`` at ``theta = +-pi/2`` (Sec. 3.3.1).

    Parameters
    ----------
    distance : float
        Distance to the target [m], > 0.
    bearing : float
        Bearing of the target [rad], left positive.
    """
    return 2.0 * math.sin(bearing) / distance


def arc_length(distance, bearing):
    """Length [m] of the arc through the target (Eq. 37), ``s = R * 2 theta = D theta / sin theta``.

    The arc turns the heading by ``2 theta``; for ``theta -> 0`` the length tends to ``D``.
    """
    theta = abs(bearing)
    if theta < 1e-6:
        # Series of theta / sin(theta); exact to double precision below 1e-6 rad.
        return distance * (1.0 + theta * theta / 6.0)
    return distance * theta / math.sin(theta)


def stop_arc_length(curvature, stop_distance):
    """Arc length [m] before the target at which the straight-line gap is ``stop_distance``.

    On a circle of radius ``R`` a chord ``c`` spans the arc ``2 R asin(c / (2 R))``; for a
    straight line it is ``c`` itself.
    """
    if stop_distance <= 0.0:
        return 0.0
    half_chord = 0.5 * stop_distance * abs(curvature)
    if half_chord < 1e-9:
        return stop_distance
    return 2.0 * math.asin(min(half_chord, 1.0)) / abs(curvature)


def wheel_factors(curvature, track_width):
    """Wheel speeds per unit centre speed ``(v_L / V, v_R / V)`` on an arc (Eqs. 41-42).

    ``v_R = (1 + (L/2)/R) V`` and ``v_L = (1 - (L/2)/R) V`` with a signed ``1/R = kappa``.
    """
    half = 0.5 * track_width * curvature
    return 1.0 - half, 1.0 + half


def wheel_arc_lengths(curvature, centre_length, track_width):
    """Distances [m] the left and right wheels cover along a centre arc (Eq. 38).

    ``s_{L,R} = (R -+ L/2) * 2 theta``, which is the centre length scaled by the wheel factors.
    """
    factor_left, factor_right = wheel_factors(curvature, track_width)
    return factor_left * centre_length, factor_right * centre_length


def radius_of(curvature):
    """Unsigned radius [m] of an arc, ``1/|kappa|``, capped at :data:`RADIUS_STRAIGHT`."""
    magnitude = abs(curvature)
    if magnitude * RADIUS_STRAIGHT <= 1.0:
        return RADIUS_STRAIGHT
    return 1.0 / magnitude
