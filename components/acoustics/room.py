"""A shoebox room: its walls, their absorption, its reverberation time and its image sources.

The room is the box ``[x0, x0 + length_x] x [y0, y0 + length_y] x [0, height]`` in the world
frame (z up from the floor). Each surface reflects the fraction ``1 - alpha`` of the energy that
reaches it (energy absorption ``alpha``, independent of frequency and angle), so a reflection
scales the amplitude by ``beta = sqrt(1 - alpha)``; the four walls share one ``alpha``, the floor
and the ceiling have their own.

Image sources (Allen and Berkley, 1979): along one axis of length ``L`` a point ``p`` has the
images ``(1 - 2 q) p + 2 j L`` (``q`` in {0, 1}, ``j`` integer), reached after ``|j - q|``
reflections on the wall at 0 and ``|j|`` on the wall at ``L``. An image's amplitude at distance
``r`` is the free-field ``1/r`` times the product of its reflections' ``beta``.

Reverberation time. Sabine's and Eyring's formulas assume a diffuse field; the image sources of a
shoebox with specular walls are not one: an image in direction ``u`` at distance ``r`` has met
``r sum_k |u_k| / L_k`` walls, so paths near an axis (and, in a flat room, the horizontal ones)
meet fewer walls and outlive the rest. The image sources' expected energy decay is therefore
computed as it is: energy arrives at time ``t`` from the sphere ``r = c t`` at the rate
``(c / V) int exp(-c t kappa(u)) dOmega`` with ``kappa(u) = sum_k |u_k| A_k / (2 L_k)`` (``A_k``
minus the log of the energy reflected by both walls of axis ``k``), the Schroeder integral of it
is ``int exp(-c t kappa) / (c kappa) dOmega``, and its RT60 is read as a measurement reads one:
a line fitted to the decay between -5 and -25 dB (T20). :func:`image_rt60` does that by
quadrature over directions. With one absorption everywhere ``kappa`` scales with
``-ln(1 - alpha)``, so a target RT60 inverts in closed form (:func:`image_absorption`). In the
7 x 7 x 2.7 m lab this RT60 is 1.36 times Eyring's for the same absorption; inverting a target
with Eyring's (or Sabine's) formula gives a synthesised decay 27-36 % (or -12..+14 %) off the
target (docs/acoustics.md).
"""

import functools
import math

import numpy as np

from ..common.errors import InputError

__all__ = ["ShoeboxRoom", "ImageLattice", "LeftRoomError", "image_rt60", "image_absorption",
           "eyring_rt60", "sabine_rt60", "eyring_absorption", "sabine_absorption",
           "image_count", "time_cut", "REAL_ABSORPTION", "DECAY_FIT_DB"]

# The absorption coefficients real surfaces have at 1-16 kHz: glazed tile or sealed concrete
# (about 0.01) to anechoic wedges (about 0.99). A target RT60 whose uniform absorption falls
# outside is one no room of that size has.
REAL_ABSORPTION = (0.01, 0.99)
# 60 dB of energy decay is ln(1e6) nepers; with the mean free path 4 V / S the decay rate is
# c S (-ln(1 - alpha)) / (4 V), hence RT60 = 24 ln(10) V / (c S (-ln(1 - alpha))).
_SIXTY_DB_TIMES_FOUR = 4.0 * math.log(1e6)


class LeftRoomError(InputError):
    """The source or a microphone is not inside the room (the run cannot go on)."""


def _surfaces(size):
    length_x, length_y, height = size
    floor = length_x * length_y
    walls = 2.0 * height * (length_x + length_y)
    return floor, walls, length_x * length_y * height


def _mean_absorption(size, absorption_walls, absorption_floor, absorption_ceiling):
    floor, walls, _ = _surfaces(size)
    total = 2.0 * floor + walls
    return (walls * absorption_walls + floor * (absorption_floor + absorption_ceiling)) / total


def _decay_constant(size, speed_of_sound):
    """``24 ln(10) V / (c S)`` [s]: RT60 = this / -ln(1 - alpha) (Eyring) or / alpha (Sabine)."""
    floor, walls, volume = _surfaces(size)
    return _SIXTY_DB_TIMES_FOUR * volume / (speed_of_sound * (2.0 * floor + walls))


def eyring_rt60(size, absorption_walls, absorption_floor, absorption_ceiling, speed_of_sound):
    """Eyring's RT60 [s] of a shoebox, with the area-weighted mean absorption.

    Parameters
    ----------
    size : sequence of float
        ``(length_x, length_y, height)`` [m].
    absorption_walls, absorption_floor, absorption_ceiling : float
        Energy absorption coefficients in [0, 1].
    speed_of_sound : float
        c [m/s].

    Returns
    -------
    float
        RT60 [s]; 0 for a mean absorption of 1, inf for 0.

    Examples
    --------
    >>> round(eyring_rt60((7.0, 7.0, 2.7), 0.2, 0.2, 0.2, 340.0), 4)
    0.5551
    """
    mean = _mean_absorption(size, absorption_walls, absorption_floor, absorption_ceiling)
    if mean >= 1.0:
        return 0.0
    if mean <= 0.0:
        return math.inf
    return _decay_constant(size, speed_of_sound) / -math.log1p(-mean)


def sabine_rt60(size, absorption_walls, absorption_floor, absorption_ceiling, speed_of_sound):
    """Sabine's RT60 [s] of a shoebox (for comparison: it ignores that alpha saturates at 1)."""
    mean = _mean_absorption(size, absorption_walls, absorption_floor, absorption_ceiling)
    return math.inf if mean <= 0.0 else _decay_constant(size, speed_of_sound) / mean


def eyring_absorption(rt60, size, speed_of_sound):
    """The uniform absorption whose Eyring RT60 is ``rt60`` [s] (in (0, 1) for any rt60 > 0)."""
    return -math.expm1(-_decay_constant(size, speed_of_sound) / rt60)


def sabine_absorption(rt60, size, speed_of_sound):
    """The uniform absorption Sabine's formula gives for ``rt60`` (may exceed 1: no such room)."""
    return _decay_constant(size, speed_of_sound) / rt60


# The decay range an RT60 is fitted over (T20), in the model and in the measurement alike.
DECAY_FIT_DB = (-5.0, -25.0)
_DIRECTIONS = 24   # Gauss-Legendre nodes in cos(theta) and midpoints in phi over one octant


def image_rt60(size, absorption_walls, absorption_floor, absorption_ceiling, speed_of_sound):
    """RT60 [s] of the image sources' expected energy decay (T20 of its Schroeder curve).

    Parameters
    ----------
    size : sequence of float
        ``(length_x, length_y, height)`` [m].
    absorption_walls, absorption_floor, absorption_ceiling : float
        Energy absorption coefficients in [0, 1].
    speed_of_sound : float

    Returns
    -------
    float
        0 when every path is absorbed at once, inf when some direction never decays.

    Examples
    --------
    >>> ratio = (image_rt60((7.0, 7.0, 2.7), 0.2, 0.2, 0.2, 340.0)
    ...          / eyring_rt60((7.0, 7.0, 2.7), 0.2, 0.2, 0.2, 340.0))
    >>> round(float(ratio), 2)
    1.36
    """
    logs = []
    for low, high in ((absorption_walls, absorption_walls),
                      (absorption_walls, absorption_walls),
                      (absorption_floor, absorption_ceiling)):
        if low >= 1.0 or high >= 1.0:
            logs.append(math.inf)
        else:
            logs.append(-math.log1p(-low) - math.log1p(-high))
    return _image_rt60(tuple(float(v) for v in size), tuple(logs), float(speed_of_sound))


def image_absorption(rt60, size, speed_of_sound):
    """The uniform absorption whose image-source decay has RT60 ``rt60`` [s].

    The decay rate of every direction is proportional to ``-ln(1 - alpha)``, so the RT60 is
    ``image_rt60(alpha = 1 - 1/e) / -ln(1 - alpha)``.
    """
    unit = image_rt60(size, *(-math.expm1(-1.0),) * 3, speed_of_sound)
    return -math.expm1(-unit / rt60)


@functools.lru_cache(maxsize=64)
def _image_rt60(size, logs, speed_of_sound):
    if all(math.isinf(v) for v in logs):
        return 0.0
    cosines, weights = np.polynomial.legendre.leggauss(_DIRECTIONS)
    cosines, weights = 0.5 * (cosines + 1.0), 0.5 * weights
    azimuths = (np.arange(_DIRECTIONS) + 0.5) * (0.5 * math.pi / _DIRECTIONS)
    sines = np.sqrt(1.0 - cosines**2)
    direction = np.stack([np.outer(sines, np.cos(azimuths)), np.outer(sines, np.sin(azimuths)),
                          np.outer(cosines, np.ones(_DIRECTIONS))]).reshape(3, -1)
    weight = np.repeat(weights, _DIRECTIONS)   # dOmega = d(cos) d(phi); phi's step is constant
    with np.errstate(invalid="ignore"):
        per_metre = sum(np.where(direction[k] > 0.0, direction[k] * logs[k] / (2.0 * size[k]),
                                 0.0) for k in range(3))
    rate = speed_of_sound * per_metre
    if np.any(rate <= 0.0):
        return math.inf
    finite = np.isfinite(rate)
    rate, weight = rate[finite], weight[finite]

    def level(t):
        return 10.0 * np.log10(np.exp(-np.outer(np.atleast_1d(t), rate)) / rate @ weight
                               / (weight / rate).sum())

    # Where the decay crosses the fit's ends: a coarse grid, then linear interpolation on a
    # fine one around each crossing (the curve is smooth and falls monotonically).
    end = 1.0 / rate.min()
    while level(end)[0] > DECAY_FIT_DB[1]:
        end *= 2.0
    grid = np.linspace(0.0, end, 257)
    coarse = level(grid)
    ends = []
    for db in DECAY_FIT_DB:
        after = int(np.argmax(coarse <= db))
        fine = np.linspace(grid[after - 1], grid[after], 257)
        levels = level(fine)
        ends.append(float(np.interp(-db, -levels, fine)))
    times = np.linspace(ends[0], ends[1], 200)
    slope = np.polyfit(times, level(times), 1)[0]
    return -60.0 / slope


def time_cut(rt60, tail_db):
    """The time after emission at which the energy decay has fallen by ``tail_db`` [s].

    Energy arriving later holds the fraction ``10**(-tail_db / 10)`` of the reverberant energy.
    """
    return rt60 * tail_db / 60.0


def image_count(path_length, size):
    """Expected number of image sources within ``path_length`` [m] of a point: one per volume."""
    return 4.0 / 3.0 * math.pi * path_length**3 / _surfaces(size)[2]


class ShoeboxRoom:
    """A shoebox room in the world frame with its surfaces' absorption.

    Parameters
    ----------
    origin : sequence of float
        World ``(x, y)`` of the room's corner with the smallest coordinates [m].
    size : sequence of float
        ``(length_x, length_y, height)`` [m].
    absorption_walls, absorption_floor, absorption_ceiling : float
        Energy absorption coefficients in [0, 1].
    """

    def __init__(self, origin, size, absorption_walls, absorption_floor, absorption_ceiling):
        self.origin = np.array([origin[0], origin[1], 0.0], dtype=float)
        self.size = np.array(size, dtype=float)
        self.absorption = (float(absorption_walls), float(absorption_floor),
                           float(absorption_ceiling))
        # Amplitude reflection factors: (wall at 0, wall at L) per axis.
        wall, floor, ceiling = (math.sqrt(1.0 - a) for a in self.absorption)
        self.reflection = ((wall, wall), (wall, wall), (floor, ceiling))

    def to_room(self, points):
        """World points (..., 3) -> room coordinates (origin at the corner, floor at z = 0)."""
        return np.asarray(points, dtype=float) - self.origin

    def outside(self, point):
        """Which coordinate of a room-frame point (3 floats) is not strictly inside, or None."""
        for axis, (value, length) in enumerate(zip(point, self.size.tolist())):
            if not 0.0 < value < length:
                return "xyz"[axis]
        return None

    def describe(self):
        """The room's extent in the world frame, for messages."""
        (x0, y0, _), (lx, ly, lz) = self.origin.tolist(), self.size.tolist()
        return (f"x in [{x0:g}, {x0 + lx:g}], y in [{y0:g}, {y0 + ly:g}], "
                f"z in [0, {lz:g}] m")

    def check_inside(self, body, world_point, time):
        """Raise :class:`LeftRoomError` naming the body and where it is, unless it is inside.

        Examples
        --------
        >>> room = ShoeboxRoom((0.0, 0.0), (7.0, 7.0, 2.7), 0.2, 0.2, 0.2)
        >>> room.check_inside("the source", (1.0, 7.5, 0.3), 4.2)
        Traceback (most recent call last):
        ...
        components.acoustics.room.LeftRoomError: at t = 4.2 s the source is at (1, 7.5, 0.3) m, \
outside the room (x in [0, 7], y in [0, 7], z in [0, 2.7] m)
        """
        local = (world_point[0] - self.origin[0], world_point[1] - self.origin[1],
                 world_point[2])
        if self.outside(local) is not None:
            where = ", ".join(f"{v:.6g}" for v in world_point)
            raise LeftRoomError(f"at t = {time:.6g} s {body} is at ({where}) m, outside the room "
                                f"({self.describe()})")


class ImageLattice:
    """The image sources of a shoebox within a path length and an order, as affine maps.

    The image of a point ``p`` (room coordinates) is ``signs * p + shifts`` for every row, so
    one lattice serves every source position; it is built once from the parameters.

    Parameters
    ----------
    room : ShoeboxRoom
    max_path : float
        Images farther than this from every point of the room are left out [m].
    max_order : int, optional
        Largest number of reflections (None: no limit).

    Attributes
    ----------
    signs, shifts : numpy.ndarray
        Shape (3, N): one row per axis (whole rows are what the per-fix arithmetic reads).
    attenuation : numpy.ndarray
        Shape (N,): the product of the reflection factors met by each image.
    order : numpy.ndarray of int
        Shape (N,): reflections per image.
    reach : numpy.ndarray
        Shape (N,), ascending: distance of the image of the room's centre from the centre.
        An image of ``p`` is within ``reach + |p - centre| + |q - centre|`` of any ``q``.
    """

    def __init__(self, room, max_path, max_order=None):
        self.max_path = float(max_path)
        self.max_order = max_order
        axes = []
        for length, (beta_low, beta_high) in zip(room.size.tolist(), room.reflection):
            reach = int(math.ceil(self.max_path / (2.0 * length))) + 1
            j = np.repeat(np.arange(-reach, reach + 1), 2)
            q = np.tile([0, 1], 2 * reach + 1)
            low, high = np.abs(j - q), np.abs(j)
            axes.append((1.0 - 2.0 * q, 2.0 * j * length, low + high,
                         beta_low ** low * beta_high ** high))
        grids = [np.meshgrid(*(axis[k] for axis in axes), indexing="ij") for k in range(4)]
        signs, shifts, orders, gains = (np.stack([g.ravel() for g in grid], axis=-1)
                                        for grid in grids)
        order = orders.sum(axis=1)
        # The image of the room's centre is within max_path + the half diagonal of any image
        # of a point in the room that is within max_path of a point in the room.
        centre = 0.5 * room.size
        half_diagonal = float(np.linalg.norm(centre))
        reach = np.linalg.norm(signs * centre + shifts - centre, axis=1)
        keep = reach <= self.max_path + 2.0 * half_diagonal
        if max_order is not None:
            keep &= order <= max_order
        rank = np.argsort(reach[keep], kind="stable")
        self.reach = reach[keep][rank]
        self.centre = centre
        self.signs = np.ascontiguousarray(signs[keep][rank].T)
        self.shifts = np.ascontiguousarray(shifts[keep][rank].T)
        self.attenuation = np.prod(gains[keep][rank], axis=1)
        self.order = order[keep][rank]

    def __len__(self):
        return len(self.order)

    def images(self, point, count=None):
        """Image positions (3, N) of a room-frame point (3,); the nearest ``count`` by reach."""
        rows = slice(None) if count is None else slice(0, count)
        return self.signs[:, rows] * np.asarray(point, dtype=float)[:, None] + self.shifts[:, rows]

    def within(self, distance, point, others):
        """How many rows (by reach) can hold an image of ``point`` within ``distance`` of a
        point in ``others`` (N, 3): the rest are farther."""
        # The norms as np.linalg.norm computes them, without its checks (called every fix).
        from_centre = np.asarray(others, dtype=float) - self.centre
        farthest = math.sqrt(float(np.add.reduce(from_centre * from_centre, axis=-1).max()))
        from_centre = np.asarray(point, dtype=float) - self.centre
        bound = distance + math.sqrt(from_centre.dot(from_centre)) + farthest
        return int(self.reach.searchsorted(bound, side="right"))
