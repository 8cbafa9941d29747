"""Figures of merit of a tracking run, computed from recorded traces.

:func:`tracking_summary` takes whole arrays; :func:`tracking_summary_from_csv` computes the
same figures (bit for bit) from a ``results.csv`` read in bounded chunks, so a run's memory
does not grow with its simulated time.
"""

import numpy as np

__all__ = ["distance_to_polyline", "tracking_summary", "tracking_summary_from_csv"]

# Points per block in distance_to_polyline: its temporaries are block x segments x 2 floats.
_POINT_BLOCK = 512
# The reference path and the robot's positions are thinned to about these many vertices.
_PATH_VERTICES = 500
_ROBOT_POINTS = 3000
_MOVED = 1e-3  # m from the start: the robot has started to move
_TRACE_COLUMNS = ("plant.x", "plant.y", "source.x", "source.y")


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
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    polyline = np.asarray(polyline, dtype=float)
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
    moved = np.hypot(*(robot_xy - robot_xy[0]).T) > _MOVED
    on_path = robot_xy[moved] if moved.any() else robot_xy[-1:]
    # thinned so the polyline distance stays cheap: 500 vertices of a path of a few metres are
    # centimetres apart, and the chord error of that is far below a millimetre
    on_path = on_path[::max(1, len(on_path) // _ROBOT_POINTS)]
    path = source_xy[::max(1, len(source_xy) // _PATH_VERTICES)]
    if len(source_xy) and not np.array_equal(path[-1], source_xy[-1]):
        path = np.vstack([path, source_xy[-1:]])
    path = np.vstack([robot_xy[:1], path])
    return _figures(distance[-1], distance.min(), on_path, path, stop_distance)


def _figures(final_distance, min_distance, on_path, path, stop_distance):
    deviation = distance_to_polyline(on_path, path)
    return {
        "final_distance_to_source_m": float(final_distance),
        "final_position_error_m": float(abs(final_distance - stop_distance)),
        "min_distance_to_source_m": float(min_distance),
        "path_rmse_m": float(np.sqrt(np.mean(deviation ** 2))),
    }


def tracking_summary_from_csv(path, stop_distance, chunk_rows=None):
    """:func:`tracking_summary` of a ``results.csv``, read twice in chunks of bounded size.

    The first pass counts the rows and the rows where the robot has moved and keeps the
    running minimum and the last distance; the second picks the same thinned points as
    :func:`tracking_summary` does from whole arrays. Memory is bounded by ``chunk_rows`` and
    the thinned point counts (about 3,000 robot points and 500 path vertices, at most twice
    that), not by the run's length.

    Parameters
    ----------
    path : path-like
        A results file with the columns ``plant.x``, ``plant.y``, ``source.x``, ``source.y``.
    stop_distance : float
        The distance at which the planner is meant to stop, in m.
    chunk_rows : int, optional
        Rows parsed at a time (default :data:`orchestrator.run.results.DEFAULT_CHUNK_ROWS`).

    Returns
    -------
    dict
        As :func:`tracking_summary`; empty if the file holds no complete row.
    """
    from orchestrator.run.results import DEFAULT_CHUNK_ROWS, iter_result_chunks

    chunk_rows = chunk_rows or DEFAULT_CHUNK_ROWS

    def chunks():
        for chunk in iter_result_chunks(path, _TRACE_COLUMNS, chunk_rows):
            robot = np.column_stack([chunk["plant.x"], chunk["plant.y"]])
            source = np.column_stack([chunk["source.x"], chunk["source.y"]])
            yield robot, source

    rows = moved_rows = 0
    start = last_robot = None
    final_distance, min_distance = None, np.inf
    for robot, source in chunks():
        if start is None:
            start = robot[0].copy()
        distance = np.hypot(*(robot - source).T)
        min_distance = min(min_distance, distance.min())
        final_distance = distance[-1]
        moved_rows += int(np.count_nonzero(np.hypot(*(robot - start).T) > _MOVED))
        rows += len(robot)
        last_robot = robot[-1:].copy()
    if rows == 0:
        return {}

    path_every = max(1, rows // _PATH_VERTICES)
    robot_every = max(1, moved_rows // _ROBOT_POINTS)
    path_parts, robot_parts = [], []
    seen = moved_seen = 0
    last_source = None
    for robot, source in chunks():
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
    on_path = np.concatenate(robot_parts) if moved_rows else last_robot
    return _figures(final_distance, min_distance, on_path, path, stop_distance)
