"""Figures of merit of a tracking run, computed from recorded traces."""

import numpy as np

__all__ = ["distance_to_polyline", "tracking_summary"]


def distance_to_polyline(points, polyline):
    """Shortest distance from each point to a polyline.

    Parameters
    ----------
    points : (n, 2) array
        Query points.
    polyline : (m, 2) array
        Vertices of the path, in order (m >= 1).

    Returns
    -------
    (n,) array
        Distance of each point to the nearest segment.
    """
    points = np.asarray(points, dtype=float)
    polyline = np.asarray(polyline, dtype=float)
    if len(polyline) == 1:
        return np.hypot(*(points - polyline[0]).T)
    a = polyline[:-1]
    segment = polyline[1:] - a
    length2 = np.einsum("ij,ij->i", segment, segment)
    length2 = np.where(length2 > 0, length2, 1.0)
    relative = points[:, None, :] - a[None, :, :]
    along = np.clip(np.einsum("nij,ij->ni", relative, segment) / length2, 0.0, 1.0)
    nearest = a[None, :, :] + along[..., None] * segment[None, :, :]
    return np.min(np.linalg.norm(points[:, None, :] - nearest, axis=2), axis=1)


def tracking_summary(time, robot_xy, source_xy, stop_distance):
    """Tracking figures of a run.

    Parameters
    ----------
    time : (n,) array
        Sample times in s.
    robot_xy, source_xy : (n, 2) arrays
        True robot and source positions at those times.
    stop_distance : float
        The distance at which the planner is meant to stop, in m.

    Returns
    -------
    dict
        ``final_distance_to_source_m``, ``final_position_error_m`` (|final distance -
        stop_distance|), ``min_distance_to_source_m`` and ``path_rmse_m``: the RMS distance of
        the robot's positions (once it has started to move) to the reference path, which runs
        from the robot's start to the source's start and then along the source's path.
    """
    robot_xy = np.asarray(robot_xy, dtype=float)
    source_xy = np.asarray(source_xy, dtype=float)
    distance = np.hypot(*(robot_xy - source_xy).T)
    moved = np.hypot(*(robot_xy - robot_xy[0]).T) > 1e-3
    on_path = robot_xy[moved] if moved.any() else robot_xy[-1:]
    # thinned so the polyline distance stays cheap: 500 vertices of a path of a few metres are
    # centimetres apart, and the chord error of that is far below a millimetre
    on_path = on_path[::max(1, len(on_path) // 3000)]
    path = source_xy[::max(1, len(source_xy) // 500)]
    if len(source_xy) and not np.array_equal(path[-1], source_xy[-1]):
        path = np.vstack([path, source_xy[-1:]])
    path = np.vstack([robot_xy[:1], path])
    deviation = distance_to_polyline(on_path, path)
    return {
        "final_distance_to_source_m": float(distance[-1]),
        "final_position_error_m": float(abs(distance[-1] - stop_distance)),
        "min_distance_to_source_m": float(distance.min()),
        "path_rmse_m": float(np.sqrt(np.mean(deviation ** 2))),
    }
