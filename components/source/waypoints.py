"""Reading a source path from a CSV file of waypoints."""

import numpy as np

from ..common.errors import ParameterError

__all__ = ["read_waypoints", "WAYPOINT_LIMIT"]

# Largest |x| or |y| of a waypoint [m]: the same 10 km as the start pose's valid range
# (ranges.toml), far beyond any arena, and small enough that path lengths stay finite.
WAYPOINT_LIMIT = 10000.0


def read_waypoints(path):
    """Read waypoints ``x,y`` [m, world frame] from a CSV file, one per line.

    Blank lines and lines starting with ``#`` are skipped, and so is a first line that is not
    numeric (a header such as ``x,y``).

    Parameters
    ----------
    path : str
        File name.

    Returns
    -------
    numpy.ndarray
        Waypoints, shape (n, 2), with at least two points.

    Raises
    ------
    ParameterError
        If the file cannot be read, a row is not two finite numbers (naming the file and
        line), or fewer than two waypoints remain.
    """
    try:
        with open(path, encoding="utf-8") as stream:
            lines = stream.read().splitlines()
    except OSError as error:
        raise ParameterError(f"path = {path!r}: cannot read the waypoint file ({error.strerror})"
                             ) from error
    points = []
    seen_data = False
    for number, line in enumerate(lines, start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        fields = [field.strip() for field in text.split(",")]
        try:
            values = [float(field) for field in fields]
        except ValueError:
            if not seen_data:
                seen_data = True  # a header row such as "x,y"
                continue
            values = None
        seen_data = True
        if values is None or len(values) != 2 or not np.all(np.isfinite(values)):
            raise ParameterError(
                f"{path}, line {number}: {text!r} is not a waypoint; expected two finite "
                "numbers 'x,y' in metres")
        if max(abs(values[0]), abs(values[1])) > WAYPOINT_LIMIT:
            raise ParameterError(
                f"{path}, line {number}: {text!r} is outside the valid range "
                f"[-{WAYPOINT_LIMIT:g}, {WAYPOINT_LIMIT:g}] m of a waypoint coordinate")
        points.append(values)
    if len(points) < 2:
        raise ParameterError(f"{path}: has {len(points)} waypoint(s); a path needs at least 2 "
                             "(use path = 'static' for a source that stays put)")
    return np.array(points, dtype=float)
