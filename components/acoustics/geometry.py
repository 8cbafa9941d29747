"""Exact geometry of the three-microphone line array carried across the robot's front.

M1 sits on the robot's left, M2 (the array centre) in the middle, M3 on its right, ``l`` apart;
the array centre is ``array_offset`` ahead of the robot's reference point along the heading.
Bearings are counter-clockwise (left) positive, relative to the heading.

A real array is not exactly that: each microphone may sit ``(along, across)`` off its nominal
place, ``along`` the array line towards the robot's left and ``across`` it forward (the
``offsets`` of :func:`microphone_positions` and :func:`microphone_ranges`). The sound reaches
the true positions; the estimators assume the nominal ones.
"""

import math

import numpy as np

__all__ = ["microphone_positions", "microphone_ranges", "source_in_array_frame", "exact_tdoas",
           "robot_polar"]


def microphone_positions(robot_x, robot_y, robot_heading, mic_spacing, array_offset=0.0,
                         offsets=None):
    """Return the world positions of M1, M2, M3.

    Parameters
    ----------
    robot_x, robot_y : float
        Robot reference point [m].
    robot_heading : float
        Heading [rad], counter-clockwise from +x.
    mic_spacing : float
        Distance ``l`` between adjacent microphones [m].
    array_offset : float, optional
        Array centre ahead of the reference point along the heading [m].
    offsets : sequence of (float, float), optional
        Per microphone M1, M2, M3: ``(along, across)`` off its nominal place [m], along the
        array line towards the robot's left and across it forward. Default: none.

    Returns
    -------
    numpy.ndarray
        Shape (3, 2): rows M1 (left), M2 (centre), M3 (right).
    """
    forward = np.array([np.cos(robot_heading), np.sin(robot_heading)])
    left = np.array([-forward[1], forward[0]])
    centre = np.array([robot_x, robot_y]) + array_offset * forward
    nominal = np.stack([centre + mic_spacing * left, centre, centre - mic_spacing * left])
    if offsets is None:
        return nominal
    offsets = np.asarray(offsets, dtype=float)
    return nominal + offsets[:, :1] * left + offsets[:, 1:] * forward


def microphone_ranges(source_x, source_y, robot_x, robot_y, robot_heading, mic_spacing,
                      array_offset=0.0, offsets=None):
    """Return the ranges from a source to M1, M2, M3 (floats; one geometry).

    The numbers of ``np.hypot`` from the source to :func:`microphone_positions`, by the same
    arithmetic in Python scalars. ``offsets`` as there.

    Returns
    -------
    list of float
        ``[R1, R2, R3]`` [m].
    """
    # math.cos and math.sin give np.cos's and np.sin's bits (glibc's, both); np.hypot and
    # math.hypot differ in the last bit.
    cos_h, sin_h = math.cos(robot_heading), math.sin(robot_heading)
    centre_x = robot_x + array_offset * cos_h
    centre_y = robot_y + array_offset * sin_h
    left_x, left_y = mic_spacing * -sin_h, mic_spacing * cos_h
    mic_x = [centre_x + left_x, centre_x, centre_x - left_x]
    mic_y = [centre_y + left_y, centre_y, centre_y - left_y]
    if offsets is not None:
        # A zero offset adds zero, which changes no bit of the nominal positions.
        for mic, (along, across) in enumerate(offsets):
            mic_x[mic] += along * -sin_h + across * cos_h
            mic_y[mic] += along * cos_h + across * sin_h
    return np.hypot([source_x - x for x in mic_x], [source_y - y for y in mic_y]).tolist()


def source_in_array_frame(source_x, source_y, robot_x, robot_y, robot_heading, array_offset=0.0):
    """Return the source's coordinates ahead of and left of the array centre M2.

    Returns
    -------
    tuple of float
        ``(forward, left)`` [m]; the source is in front of the array when ``forward > 0``.
    """
    dx = source_x - robot_x
    dy = source_y - robot_y
    cos_h, sin_h = np.cos(robot_heading), np.sin(robot_heading)
    forward = cos_h * dx + sin_h * dy - array_offset
    left = -sin_h * dx + cos_h * dy
    return forward, left


def exact_tdoas(distance, bearing, mic_spacing, speed_of_sound):
    """Return the exact delays ``(tdoa_12, tdoa_23)`` of a source at ``distance``, ``bearing`` from M2.

    ``tdoa_12 = t1 - t2`` and ``tdoa_23 = t3 - t2`` (the paper's Eq. 1: ``R3 = D + c*dt_23``).
    Works elementwise on arrays.

    Parameters
    ----------
    distance : float or array_like
        Range ``D`` from the array centre M2 [m].
    bearing : float or array_like
        Bearing from the array's broadside, left positive [rad].
    mic_spacing, speed_of_sound : float
        ``l`` [m] and ``c`` [m/s].

    Returns
    -------
    tuple of numpy.ndarray
        ``(tdoa_12, tdoa_23)`` [s].
    """
    distance = np.asarray(distance, dtype=float)
    bearing = np.asarray(bearing, dtype=float)
    cross = 2.0 * distance * mic_spacing * np.sin(bearing)
    base = distance**2 + mic_spacing**2
    range_1 = np.sqrt(base - cross)
    range_3 = np.sqrt(base + cross)
    return (range_1 - distance) / speed_of_sound, (range_3 - distance) / speed_of_sound


def robot_polar(distance, bearing, array_offset):
    """Move a fix ``(distance, bearing)`` from the array centre to the robot's reference point.

    The planner works about the wheel axle, so the outputs refer to the point the array is
    mounted ``array_offset`` ahead of. Elementwise on arrays.

    Returns
    -------
    tuple
        ``(distance, bearing)`` from the reference point [m, rad].
    """
    forward = array_offset + distance * np.cos(bearing)
    left = distance * np.sin(bearing)
    return np.hypot(forward, left), np.arctan2(left, forward)


def _source_in_array_frame_one(source_x, source_y, robot_x, robot_y, robot_heading,
                               array_offset):
    """:func:`source_in_array_frame` for floats, in Python floats (the same bits)."""
    dx = source_x - robot_x
    dy = source_y - robot_y
    cos_h, sin_h = math.cos(robot_heading), math.sin(robot_heading)
    return cos_h * dx + sin_h * dy - array_offset, -sin_h * dx + cos_h * dy


def _robot_polar_one(distance, bearing, array_offset):
    """:func:`robot_polar` for floats, in Python floats (the same bits)."""
    forward = array_offset + distance * math.cos(bearing)
    left = distance * math.sin(bearing)
    # np.hypot and np.arctan2, not math's: their results differ in the last bit.
    return float(np.hypot(forward, left)), float(np.arctan2(left, forward))
