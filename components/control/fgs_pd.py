"""Eq. (50): from normalised fuzzy gains to the PD gains."""

from ..common.errors import ParameterError

__all__ = ["scheduled_gain", "check_gain_range", "PAPER_TO_OURS"]

# The paper's numbers (error y - r, negative gains) on our convention (error r - y, positive
# gains). "min"/"max" are by magnitude: Kp' = 1 (Big) gives |Kp| = 4, the high gain far from
# the reference that Zhao-Tomizuka-Isaka's tables ask for. See docs/control.md.
PAPER_TO_OURS = {"kp_min": 3.0, "kp_max": 4.0, "kd_min": 0.3, "kd_max": 2.0}


def scheduled_gain(normalised, gain_min, gain_max):
    """Eq. (50): ``K = (K_max - K_min) K' + K_min``.

    Parameters
    ----------
    normalised : float
        ``K'`` in [0, 1] from the fuzzy system.
    gain_min, gain_max : float
        The gain at ``K' = 0`` and at ``K' = 1``.

    Returns
    -------
    float
    """
    return (gain_max - gain_min) * normalised + gain_min


def check_gain_range(name, gain_min, gain_max):
    """Raise :class:`ParameterError` unless ``0 <= gain_min <= gain_max`` (finite).

    Parameters
    ----------
    name : str
        ``"kp"`` or ``"kd"``; the message names ``<name>_min`` and ``<name>_max``.
    gain_min, gain_max : float
    """
    if not (0.0 <= gain_min <= gain_max < float("inf")):
        raise ParameterError(
            f"{name}_min = {gain_min!r}, {name}_max = {gain_max!r}: need "
            f"0 <= {name}_min <= {name}_max on the error convention e = v_ref - v_meas "
            f"(the paper's negative ranges map to positive ones, e.g. {name}_min = "
            f"{PAPER_TO_OURS[name + '_min']}, {name}_max = {PAPER_TO_OURS[name + '_max']})")
