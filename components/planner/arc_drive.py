"""Wheel speeds that drive a constant-curvature arc with one trapezoid on both wheels."""

from ..common.trapezoid import next_speed
from .geometry import wheel_factors

__all__ = ["ARRIVED", "arc_limits", "arc_wheel_speeds"]

# Remaining distance [m] below which a path counts as driven; float rounding of the summed
# progress leaves about 1e-16 m, far below an encoder count.
ARRIVED = 1e-9


def arc_limits(limits, curvature):
    """Wheel factors and centre-speed bounds of an arc; they hold as long as its curvature.

    The centre's cruise speed and acceleration are reduced by the larger wheel factor so
    that the outer wheel keeps ``|v| <= v_max`` and ``|a| <= a_max`` (Eqs. 43-44).

    Parameters
    ----------
    limits : object
        Has ``track_width``, ``v_cruise``, ``v_max`` and ``a_max``.
    curvature : float
        Signed curvature of the arc [1/m], left positive.

    Returns
    -------
    tuple of float
        ``(factor_left, factor_right, centre_limit, centre_cruise, centre_a_max)``: the
        Eq. (41)-(42) factors, the largest centre speed the outer wheel allows [m/s], and the
        centre's cruise speed [m/s] and acceleration [m/s^2].
    """
    factor_left, factor_right = wheel_factors(curvature, limits.track_width)
    scale = max(abs(factor_left), abs(factor_right))
    centre_limit = limits.v_max / scale
    return (factor_left, factor_right, centre_limit, min(limits.v_cruise, centre_limit),
            limits.a_max / scale)


def arc_wheel_speeds(limits, left, right, curvature, remaining, step, arc=None):
    """Next wheel speeds along an arc: a sampled trapezoid on the centre, scaled per wheel.

    Both wheels are the centre speed ``V`` times their Eq. (41)-(42) factors, so their ratio,
    and with it the curvature, holds while ``V`` accelerates, cruises and brakes (Sec. 4.1),
    within the bounds of :func:`arc_limits`.

    Parameters
    ----------
    limits : object
        Has ``track_width``, ``v_cruise``, ``v_max`` and ``a_max``.
    left, right : float
        Wheel speeds held during the previous step [m/s].
    curvature : float
        Signed curvature of the arc [1/m], left positive.
    remaining : float
        Centre arc length still to drive [m].
    step : float
        Hold time of the next speeds [s].
    arc : tuple, optional
        ``arc_limits(limits, curvature)``, from a caller that keeps it while the curvature
        holds (it is computed here otherwise).

    Returns
    -------
    tuple of float
        ``(v_left, v_right)`` [m/s].
    """
    factor_left, factor_right, centre_limit, cruise, centre_a_max = (
        arc_limits(limits, curvature) if arc is None else arc)
    if remaining < ARRIVED:
        remaining = 0.0
    centre = next_speed(0.5 * (left + right), cruise, remaining, centre_a_max, step)
    # A new, sharper arc lowers the centre speed the outer wheel allows; the trapezoid would
    # only brake towards it, so clamp here and let the wheel limiter spread the change.
    if centre_limit < centre:  # min() as a comparison: this runs every planner step
        centre = centre_limit
    return factor_left * centre, factor_right * centre
