"""Source paths parametrised by arc length: straight, S-curve, static point, waypoints.

Built-in paths start at the start pose ``(x0, y0, heading0)`` and extend ``length`` metres
forward along ``heading0``. With the defaults, (0, 1) heading +y and 6 m, the source covers
the 0-7 m arena of the paper ahead of the robot at the origin.

The S-curve adds a lateral offset, left positive, to the forward coordinate ``u``::

    w(u) = A * (16 / (3 sqrt 3)) * sin^3(pi u / l) * cos(pi u / l),   0 <= u <= l

which is ``+A`` at ``u = l/3``, ``-A`` at ``u = 2l/3`` and has zero value and slope at both
ends, so the source starts and ends heading along ``heading0``.
"""

import bisect
import math

import numpy as np

from ..common.errors import ParameterError
from .waypoints import read_waypoints

__all__ = ["PolylinePath", "SCurvePath", "make_path", "BUILT_IN_PATHS"]

BUILT_IN_PATHS = ("straight", "s_curve", "static")

# Samples of the S-curve's arc-length table; cubic Hermite interpolation of u(s) between them
# keeps the arc-length parametrisation exact to ~1e-10 for amplitudes up to a metre.
_S_CURVE_SAMPLES = 1001


class _Path:
    """What every path offers: :meth:`pose`, and position and tangent read from it."""

    def pose(self, s):
        """``(x, y, tangent_x, tangent_y)`` at arc length ``s`` [m]."""
        raise NotImplementedError

    def position(self, s):
        """Point [m] at arc length ``s`` [m] (clamped to the path)."""
        x, y, _, _ = self.pose(s)
        return x, y

    def tangent(self, s):
        """Unit direction of travel at arc length ``s`` (on a polyline: of the segment that
        starts there)."""
        _, _, tangent_x, tangent_y = self.pose(s)
        return tangent_x, tangent_y


class PolylinePath(_Path):
    """Straight segments through waypoints; a single point is a static path.

    Parameters
    ----------
    points : array_like
        Waypoints, shape (n, 2), n >= 1 [m].
    heading : float
        Heading reported for a single point [rad].
    """

    def __init__(self, points, heading=0.5 * math.pi):
        points = np.asarray(points, dtype=float).reshape(-1, 2)
        # Zero-length segments have no direction; drop repeated waypoints.
        keep = np.ones(len(points), dtype=bool)
        keep[1:] = np.any(np.diff(points, axis=0) != 0.0, axis=1)
        self.points = points[keep]
        segments = np.diff(self.points, axis=0)
        self.segment_lengths = np.hypot(segments[:, 0], segments[:, 1])
        self.cumulative = np.concatenate(([0.0], np.cumsum(self.segment_lengths)))
        self.length = float(self.cumulative[-1])
        self.heading = float(heading)
        # Plain-float copies for the per-step look-ups: numpy on scalars costs microseconds.
        self._xs = self.points[:, 0].tolist()
        self._ys = self.points[:, 1].tolist()
        self._segment_lengths = self.segment_lengths.tolist()
        self._cumulative = self.cumulative.tolist()
        self._last_segment = len(self._segment_lengths) - 1
        self._heading_cos, self._heading_sin = math.cos(self.heading), math.sin(self.heading)

    def pose(self, s):
        """Point [m] and unit direction of travel at arc length ``s`` [m], in one look-up.

        Returns
        -------
        tuple of float
            ``(x, y, tangent_x, tangent_y)``; see :meth:`position` and :meth:`tangent`.
        """
        xs, ys = self._xs, self._ys
        if len(xs) == 1:
            return xs[0], ys[0], self._heading_cos, self._heading_sin
        cumulative = self._cumulative
        i = bisect.bisect_right(cumulative, s) - 1
        i = 0 if i < 0 else (self._last_segment if i > self._last_segment else i)
        segment_length = self._segment_lengths[i]
        dx, dy = xs[i + 1] - xs[i], ys[i + 1] - ys[i]
        s = 0.0 if s < 0.0 else (self.length if self.length < s else s)
        fraction = (s - cumulative[i]) / segment_length
        return (xs[i] + fraction * dx, ys[i] + fraction * dy,
                dx / segment_length, dy / segment_length)


class SCurvePath(_Path):
    """The S-curve of the module docstring, parametrised by arc length.

    Parameters
    ----------
    x0, y0, heading0 : float
        Start pose [m, m, rad].
    length : float
        Forward extent ``l`` [m], > 0.
    amplitude : float
        Lateral peak ``A`` [m].
    """

    def __init__(self, x0, y0, heading0, length, amplitude):
        self.x0, self.y0, self.heading0 = float(x0), float(y0), float(heading0)
        self.forward_length = float(length)
        self.amplitude = float(amplitude)
        self.u_table = np.linspace(0.0, self.forward_length, _S_CURVE_SAMPLES)
        # 3-point Gauss-Legendre on each interval: arc length exact to ~1e-13 m.
        lower, width = self.u_table[:-1], np.diff(self.u_table)
        pieces = np.zeros_like(width)
        for node, weight in ((-math.sqrt(0.6), 5 / 9), (0.0, 8 / 9), (math.sqrt(0.6), 5 / 9)):
            u = lower + 0.5 * width * (1.0 + node)
            pieces += 0.5 * width * weight * np.hypot(1.0, self._slope(u))
        self.s_table = np.concatenate(([0.0], np.cumsum(pieces)))
        # du/ds at the nodes, for cubic Hermite interpolation of u(s): linear interpolation
        # would make the speed along the path wobble by ~0.1 % between nodes.
        self.du_ds_table = 1.0 / np.hypot(1.0, self._slope(self.u_table))
        self.length = float(self.s_table[-1])
        # plain-float copies for the per-step look-ups: numpy on scalars costs microseconds
        self._s_list = self.s_table.tolist()
        self._u_list = self.u_table.tolist()
        self._du_ds_list = self.du_ds_table.tolist()
        self._last_interval = len(self._s_list) - 2
        self._heading_cos, self._heading_sin = math.cos(self.heading0), math.sin(self.heading0)
        # The leading factors of the offset and its slope, multiplied in the same order as
        # written out in full, so that hoisting them changes no bit of the result.
        self._offset_gain = _PEAK_GAIN * self.amplitude
        self._slope_gain = _PEAK_GAIN * self.amplitude * math.pi / self.forward_length

    def _slope(self, u):
        phase = np.pi * np.asarray(u) / self.forward_length
        # d/du of sin^3 cos = (pi/l) sin^2 (3 cos^2 - sin^2)
        return (_PEAK_GAIN * self.amplitude * np.pi / self.forward_length
                * np.sin(phase) ** 2 * (3.0 * np.cos(phase) ** 2 - np.sin(phase) ** 2))

    def pose(self, s):
        """Point [m] and unit direction of travel at arc length ``s`` [m], in one look-up.

        Returns
        -------
        tuple of float
            ``(x, y, tangent_x, tangent_y)``; see :meth:`position` and :meth:`tangent`.
        """
        # u(s): cubic Hermite interpolation in the arc-length table (written out here, not
        # called, because this runs every source step).
        s_list, u_list, du_ds = self._s_list, self._u_list, self._du_ds_list
        s = 0.0 if s < 0.0 else (self.length if self.length < s else s)
        i = bisect.bisect_right(s_list, s) - 1
        if i > self._last_interval:
            i = self._last_interval
        width = s_list[i + 1] - s_list[i]
        t = (s - s_list[i]) / width
        t2 = t * t
        t3 = t2 * t
        u = ((2 * t3 - 3 * t2 + 1) * u_list[i]
             + (t3 - 2 * t2 + t) * width * du_ds[i]
             + (-2 * t3 + 3 * t2) * u_list[i + 1]
             + (t3 - t2) * width * du_ds[i + 1])
        phase = math.pi * u / self.forward_length
        sine, cosine = math.sin(phase), math.cos(phase)
        offset = self._offset_gain * sine ** 3 * cosine
        # d/du of sin^3 cos = (pi/l) sin^2 (3 cos^2 - sin^2)
        slope = self._slope_gain * sine * sine * (3.0 * cosine * cosine - sine * sine)
        norm = math.hypot(1.0, slope)
        c, d = self._heading_cos, self._heading_sin
        return (self.x0 + u * c - offset * d, self.y0 + u * d + offset * c,
                (c - slope * d) / norm, (d + slope * c) / norm)


_PEAK_GAIN = 16.0 / (3.0 * math.sqrt(3.0))


def make_path(path, x0=0.0, y0=1.0, heading0=0.5 * math.pi, length=6.0, amplitude=0.5):
    """Build the path named by the ``path`` parameter.

    Parameters
    ----------
    path : str
        ``"straight"``, ``"s_curve"``, ``"static"`` or the name of a CSV file of waypoints
        ``x,y`` in the world frame (the start pose is then ignored).
    x0, y0, heading0 : float
        Start pose of the built-in paths [m, m, rad].
    length : float
        Forward extent of ``straight`` and ``s_curve`` [m].
    amplitude : float
        Lateral peak of ``s_curve`` [m].

    Raises
    ------
    ParameterError
        If ``path`` is neither a built-in name nor a readable CSV file, or the geometry is
        invalid.
    """
    for name, value in (("x0", x0), ("y0", y0), ("heading0", heading0),
                        ("amplitude", amplitude)):
        if not math.isfinite(value):
            raise ParameterError(f"{name} = {value!r}: must be finite")
    if path == "static":
        return PolylinePath([(x0, y0)], heading0)
    if path in ("straight", "s_curve") and not (math.isfinite(length) and length > 0.0):
        raise ParameterError(f"length = {length!r}: must be a finite number > 0 for "
                             f"path = {path!r}")
    if path == "straight":
        end = (x0 + length * math.cos(heading0), y0 + length * math.sin(heading0))
        return PolylinePath([(x0, y0), end], heading0)
    if path == "s_curve":
        return SCurvePath(x0, y0, heading0, length, amplitude)
    if not path.lower().endswith(".csv"):
        raise ParameterError(f"path = {path!r}: not one of {list(BUILT_IN_PATHS)} "
                             "nor a CSV file of waypoints (*.csv)")
    return PolylinePath(read_waypoints(path))
