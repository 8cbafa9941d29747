"""Tracking figures of a run: how close the robot came to the source and how well it kept to
the source's path.

:func:`tracking_summary` reads a row source (:mod:`orchestrator.run.summary`: the rows kept
while recording, or ``results.csv`` read back in chunks) in two passes: the first counts the
rows and keeps the running minimum and the last distance, the second picks the thinned points
the path deviation is measured on. Memory is bounded by a chunk and the thinned point counts
(about 3,000 robot points and 500 path vertices, at most twice that), not by the run's length,
and the figures do not depend on how the rows are chunked.

:func:`distance_to_polyline` is the project's one point-to-polyline distance (the studies'
path geometry, :mod:`orchestrator.reproduce.geometry`, uses it too).
"""

import numpy as np

from orchestrator.system.sonotrack import SONOTRACK

__all__ = ["distance_to_polyline", "source_distance", "tracking_summary"]

# Points per block in distance_to_polyline: its temporaries are block x segments floats.
_POINT_BLOCK = 512
# The reference path and the robot's positions are thinned to about these many vertices.
_PATH_VERTICES = 500
_ROBOT_POINTS = 3000
_MOVED = 1e-3  # m from the start: the robot has started to move


def distance_to_polyline(points, polyline):
    """Shortest distance from each point to a polyline.

    Parameters
    ----------
    points : (n, 2) array_like
        Query points (n may be 0).
    polyline : (m, 2) array_like
        Vertices of the path, in order (m >= 1; a single vertex is a point).

    Returns
    -------
    (n,) numpy.ndarray
        Distance of each point to the nearest segment.

    Examples
    --------
    >>> distance_to_polyline([[0.0, 1.5], [4.0, 6.0]], [[-1.0, 0.0], [1.0, 0.0], [1.0, 2.0]])
    array([1., 5.])
    """
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    polyline = np.asarray(polyline, dtype=float).reshape(-1, 2)
    if len(polyline) == 1:
        return np.hypot(*(points - polyline[0]).T)
    ax, ay = polyline[:-1, 0], polyline[:-1, 1]
    ux, uy = np.diff(polyline[:, 0]), np.diff(polyline[:, 1])
    length2 = ux * ux + uy * uy
    length2 = np.where(length2 > 0, length2, 1.0)   # a repeated vertex: its own distance
    result = np.empty(len(points))
    # x and y apart, (points x segments) temporaries in blocks of points: a few MB each, and
    # about a fifth of the work of (points x segments x 2) arrays and a norm along their axis
    for first in range(0, len(points), _POINT_BLOCK):
        block = points[first:first + _POINT_BLOCK]
        dx = block[:, 0, None] - ax
        dy = block[:, 1, None] - ay
        along = dx * ux
        along += dy * uy
        along /= length2
        np.clip(along, 0.0, 1.0, out=along)
        dx -= along * ux
        dy -= along * uy
        dx *= dx
        dy *= dy
        dx += dy
        result[first:first + _POINT_BLOCK] = np.sqrt(dx.min(axis=1))
    return result


def source_distance(chunk):
    """Distance [m] from the robot to the source in each row of a chunk.

    Parameters
    ----------
    chunk : dict of str to numpy.ndarray
        Rows holding :attr:`~orchestrator.system.sonotrack.SonotrackSystem.position_columns`.

    Returns
    -------
    numpy.ndarray
    """
    (robot_x, robot_y), (source_x, source_y) = SONOTRACK.robot_position, SONOTRACK.source_position
    return np.hypot(chunk[robot_x] - chunk[source_x], chunk[robot_y] - chunk[source_y])


def tracking_summary(rows, stop_distance):
    """Tracking figures of a run.

    Parameters
    ----------
    rows : row source
        The run's rows (:class:`~orchestrator.run.summary.RowTrace` or
        :class:`~orchestrator.run.summary.ResultRows`), holding the robot's and the
        source's true positions.
    stop_distance : float
        The distance at which the planner is meant to stop, in m.

    Returns
    -------
    dict
        ``final_distance_to_source_m``, ``final_position_error_m`` (|final distance -
        stop_distance|), ``min_distance_to_source_m`` and ``path_rmse_m``: the RMS distance of
        the robot's positions (once it has started to move) to the reference path, which runs
        from the robot's start to the source's start and then along the source's path. Empty
        if there are no rows.
    """
    robot_columns, source_columns = SONOTRACK.robot_position, SONOTRACK.source_position

    def chunks():
        for chunk in rows.chunks(robot_columns + source_columns):
            yield (chunk, np.column_stack([chunk[c] for c in robot_columns]),
                   np.column_stack([chunk[c] for c in source_columns]))

    count = moved_count = 0
    start = last_robot = None
    final_distance, min_distance = None, np.inf
    for chunk, robot, _ in chunks():
        if start is None:
            start = robot[0].copy()
        distance = source_distance(chunk)
        min_distance = np.minimum(min_distance, distance.min())   # NaN stays NaN
        final_distance = distance[-1]
        moved_count += int(np.count_nonzero(np.hypot(*(robot - start).T) > _MOVED))
        count += len(robot)
        last_robot = robot[-1:].copy()
    if count == 0:
        return {}

    # thinned so the polyline distance stays cheap: 500 vertices of a path of a few metres are
    # centimetres apart, and the chord error of that is far below a millimetre
    path_every = max(1, count // _PATH_VERTICES)
    robot_every = max(1, moved_count // _ROBOT_POINTS)
    path_parts, robot_parts = [], []
    seen = moved_seen = 0
    last_source = None
    for _, robot, source in chunks():
        path_parts.append(source[(-seen) % path_every::path_every].copy())
        moved = np.hypot(*(robot - start).T) > _MOVED
        on_path = robot[moved]
        robot_parts.append(on_path[(-moved_seen) % robot_every::robot_every].copy())
        seen += len(robot)
        moved_seen += len(on_path)
        last_source = source[-1:].copy()
    path = np.concatenate(path_parts)
    if not np.array_equal(path[-1], last_source[0]):
        path = np.vstack([path, last_source])
    path = np.vstack([start[None, :], path])
    on_path = np.concatenate(robot_parts) if moved_count else last_robot
    deviation = distance_to_polyline(on_path, path)
    return {
        "final_distance_to_source_m": float(final_distance),
        "final_position_error_m": float(abs(final_distance - stop_distance)),
        "min_distance_to_source_m": float(min_distance),
        "path_rmse_m": float(np.sqrt(np.mean(deviation ** 2))),
    }
