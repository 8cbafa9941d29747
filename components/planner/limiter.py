"""Bounded-acceleration change of both wheel speeds on one time base."""

__all__ = ["limit_wheel_change"]


def limit_wheel_change(left, right, desired_left, desired_right, max_change):
    """Move both wheel speeds towards their targets by at most ``max_change`` each.

    Both wheels move by the same fraction of their remaining change, so they reach their
    targets in the same step and the curvature passes smoothly from the old ratio to the new
    one (the paper's Case 2) instead of one wheel arriving first.

    Parameters
    ----------
    left, right : float
        Wheel speeds held during the previous step [m/s].
    desired_left, desired_right : float
        Wanted wheel speeds [m/s].
    max_change : float
        Largest change of either wheel speed in one step [m/s] (``a_max * step``).

    Returns
    -------
    tuple of float
        ``(left, right, fraction)``: the new speeds and the fraction of the wanted change
        applied (1.0 when the targets were reached).
    """
    change_left = desired_left - left
    change_right = desired_right - right
    largest = abs(change_left)
    if abs(change_right) > largest:  # max() as a comparison: this runs every planner step
        largest = abs(change_right)
    if largest <= max_change * (1.0 + 1e-12):
        return desired_left, desired_right, 1.0
    fraction = max_change / largest
    return left + fraction * change_left, right + fraction * change_right, fraction
