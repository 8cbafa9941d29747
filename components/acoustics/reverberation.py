"""What the three microphones record in a room while the source and the robot move.

One fix records ``n`` samples around the latest burst (the burst whose direct sound reaches M2
at the fix instant ``t``). Into that record fall the latest burst's direct sound and early
reflections and, when the source sounds every ``burst_period``, the late reflections of the
bursts before it (with a 10 ms period and RT60 = 0.4 s, twenty of them within a 30 dB cut).

Every arrival is one image source of one burst ``b``, emitted at ``e_b = e_0 - b T``:

* the source is where it was at ``e_b`` (:class:`~.motion.PoseHistory`, linear between steps);
  ``e_0`` solves ``e_0 = t - |M2(t) - S(e_0)| / c`` (three fixed-point steps);
* each microphone is where it is when that image's wavefront reaches it: at ``a`` with
  ``c (a - e_b) = |M_i(a) - I_b|``, the robot moving at the velocity of its last step. One
  fixed-point step from ``a = t`` leaves an error of ``(v / c)^2 |a - t|``: under 1e-8 s;
* only arrivals inside the record count, and only images reached within the time cut
  (``rt60 * reverb_cut_db / 60`` after emission; the direct sound always counts).

Neglected, with their bounds at the shipped speeds (source 0.2 m/s, robot 0.4 m/s): motion
during one 1 ms burst (source 0.2 mm, robot 0.4 mm: a Doppler stretch below 1.2e-3 of the
burst, common to the three microphones to within 1e-4 of itself, i.e. under 0.1 us across the
burst); the robot's acceleration during one record (the extrapolated pose is off by under
20 um); air absorption and the surfaces' frequency dependence (one absorption per surface over
the 1-16 kHz burst); scattering (specular walls only).

Cost: the image lattice is built once from the parameters; each fix computes the distance of
every image of the latest source position to the three microphones (whole arrays, one
coordinate at a time), picks the burst whose record each can reach, gathers the (microphone,
image) pairs that have one (about half in a reverberant room), computes those arrivals exactly
and renders them (:mod:`.rendering`).
"""

import math

import numpy as np

from .motion import PoseHistory
from .rendering import ArrivalRenderer
from .room import ImageLattice, ShoeboxRoom
from .synthesis import REFERENCE_AMPLITUDE, REFERENCE_DISTANCE

__all__ = ["RoomAcoustics", "Arrivals"]

_SPAN = REFERENCE_AMPLITUDE * REFERENCE_DISTANCE


def _distance(dx, dy, dz):
    """``sqrt(dx^2 + dy^2 + dz^2)`` into a new array."""
    total = np.square(dx)
    square = np.square(dy)
    total += square
    total += np.square(dz, out=square)
    return np.sqrt(total, out=total)


def _largest_norm(rows):
    """``max(np.linalg.norm(rows, axis=1))`` (the same sums) for a few rows."""
    return math.sqrt(float(np.maximum.reduce(np.add.reduce(rows * rows, axis=1))))


class Arrivals:
    """Arrivals of image sources at the microphones (arrays of one length).

    Attributes
    ----------
    microphone : numpy.ndarray of int
        0, 1, 2 for M1, M2, M3.
    delay : numpy.ndarray
        Arrival instant [s] after the latest burst's emission.
    gain : numpy.ndarray
        Amplitude (the free field's ``A_ref r_ref / r`` times the reflections' factors).
    burst, order, image : numpy.ndarray of int or None
        With ``detail``: which burst (0 the latest), reflections on the way, lattice row.
    path : numpy.ndarray or None
        With ``detail``: path length [m].
    """

    def __init__(self, microphone, delay, gain, burst=None, order=None, image=None, path=None):
        self.microphone = microphone
        self.delay = delay
        self.gain = gain
        self.burst = burst
        self.order = order
        self.image = image
        self.path = path


class RoomAcoustics:
    """The room a localizer hears: geometry, image lattice, and the records of one burst.

    Parameters
    ----------
    settings : LocalizerSettings
        With ``room`` true; its room fields are already checked.

    Attributes
    ----------
    room : ShoeboxRoom
    rt60 : float
        The image sources' RT60 (:func:`~.room.image_rt60`) [s].
    cut : float
        Time cut after emission [s].
    lattice : ImageLattice
    """

    # Built from parameters at construction and never changed: not part of the FMU state.
    STATE_CONSTANTS = ("room", "lattice", "renderer", "_bounds", "_amplitude")

    def __init__(self, settings):
        s = settings
        self.room = ShoeboxRoom((s.room_origin_x, s.room_origin_y),
                                (s.room_length_x, s.room_length_y, s.room_height),
                                *s.room_absorption)
        self.rt60 = s.room_rt60
        self.cut = s.room_time_cut
        self.speed_of_sound = s.speed_of_sound
        self.source_height = s.source_height
        self.mic_height = s.mic_height
        self.mic_spacing = s.mic_spacing
        self.array_offset = s.array_offset
        # The array as built (offsets) and its channels' sampling skews: what the room is heard
        # with; the estimator keeps the nominal array.
        self.mic_offsets = s.mic_offsets
        self.adc_skews = np.array(s.adc_skews) if any(s.adc_skews) else None
        self.burst_period = s.burst_period
        self.burst_duration = s.burst_duration
        self.sample_rate = s.sample_rate
        self.pre_roll = s.pre_roll
        self.n_samples = s.record_samples
        # Earlier bursts whose reflections can still arrive within the cut.
        self.earlier_bursts = (int(math.floor(self.cut / self.burst_period))
                               if self.burst_period > 0.0 else 0)
        record_span = (self.n_samples + 1) / self.sample_rate + self.pre_roll
        self.lattice = ImageLattice(self.room, self.speed_of_sound * (self.cut + record_span),
                                    None if s.image_order < 0 else s.image_order)
        self.renderer = ArrivalRenderer(s.burst, s.sample_rate)
        # Each image's amplitude at unit distance.
        self._amplitude = _SPAN * self.lattice.attenuation
        self._bounds = (self.room.origin.tolist(), self.room.size.tolist())

    @property
    def history_horizon(self):
        """How far back the inputs are needed [s]: the earliest emission plus slack."""
        return self.earlier_bursts * self.burst_period + 0.1 + 2.0 * self.cut

    # ----- bodies ------------------------------------------------------------------------------
    def microphones(self, robot_x, robot_y, robot_heading):
        """Room-frame positions (3, 3) of M1, M2, M3 (rows) for a robot pose, where they are."""
        cos_h, sin_h = math.cos(robot_heading), math.sin(robot_heading)
        centre = (robot_x + self.array_offset * cos_h - self.room.origin[0],
                  robot_y + self.array_offset * sin_h - self.room.origin[1])
        left = (-self.mic_spacing * sin_h, self.mic_spacing * cos_h)
        # A zero offset adds zero: the nominal positions' bits.
        return np.array([[centre[0] + side * left[0] + (across * cos_h - along * sin_h),
                          centre[1] + side * left[1] + (along * cos_h + across * sin_h),
                          self.mic_height]
                         for side, (along, across) in zip((1.0, 0.0, -1.0), self.mic_offsets)])

    def _world_microphones(self, robot_x, robot_y, robot_heading):
        """World ``(x, y)`` of M1, M2, M3 with their offsets (along the line, across it)."""
        cos_h, sin_h = math.cos(robot_heading), math.sin(robot_heading)
        centre_x = robot_x + self.array_offset * cos_h
        centre_y = robot_y + self.array_offset * sin_h
        return [(centre_x - side * self.mic_spacing * sin_h + (across * cos_h - along * sin_h),
                 centre_y + side * self.mic_spacing * cos_h + (along * cos_h + across * sin_h))
                for side, (along, across) in zip((1.0, 0.0, -1.0), self.mic_offsets)]

    def check_inside(self, time, source_x, source_y, robot_x, robot_y, robot_heading):
        """Raise :class:`~.room.LeftRoomError` if the source or a microphone is outside.

        Called every step, so in Python floats; the message comes from the room.
        """
        (x0, y0, _), (lx, ly, _) = self._bounds
        if not (x0 < source_x < x0 + lx and y0 < source_y < y0 + ly):
            self.room.check_inside("the source", (source_x, source_y, self.source_height), time)
        for name, (x, y) in zip(("M1", "M2", "M3"),
                                self._world_microphones(robot_x, robot_y, robot_heading)):
            if not (x0 < x < x0 + lx and y0 < y < y0 + ly):
                self.room.check_inside(f"the robot's microphone {name}", (x, y, self.mic_height),
                                       time)

    # ----- one fix from the inputs of the latest steps -------------------------------------
    def records(self, table, time):
        """Clean records (3, n) of the burst heard at ``time`` and the direct slant ranges.

        Parameters
        ----------
        table : numpy.ndarray
            :meth:`PoseHistory.table`, its last sample at ``time``.
        time : float
            The fix instant [s].

        Returns
        -------
        records : numpy.ndarray
            Shape (3, n): noise-free samples (before the ADC).
        ranges : list of float
            Direct paths from the source at emission to M1, M2, M3 [m].
        """
        (t_prev, *pose_prev), (t_now, *pose_now) = PoseHistory.latest_two(table)
        mics = self.microphones(*pose_now)
        velocity = ((mics - self.microphones(*pose_prev)) / (t_now - t_prev)
                    if t_now > t_prev else np.zeros((3, 3)))
        # Emission of the latest burst: its direct sound reaches M2 at `time` (one instant at
        # a time in floats: numpy's array set-up would cost more than the arithmetic).
        (origin_x, origin_y, _), _ = self._bounds
        emission = time
        for _ in range(3):
            x, y = PoseHistory.source_point(table, emission)
            to_m2 = mics[1] - (x - origin_x, y - origin_y, self.source_height)
            emission = time - math.sqrt(to_m2.dot(to_m2)) / self.speed_of_sound
        emitted_at = emission - np.arange(self.earlier_bursts + 1) * self.burst_period
        sounded = PoseHistory.emitting_at(table, emitted_at)
        sounded[0] = True
        return self.render(self._sources(table, emitted_at), sounded, mics, velocity,
                           time - emission)

    def _sources(self, table, times):
        sources = np.empty((len(times), 3))
        sources[:, :2] = PoseHistory.source_at(table, times)
        sources[:, :2] -= self.room.origin[:2]
        sources[:, 2] = self.source_height
        return sources

    def render(self, sources, sounded, mics, velocity, reference):
        """Clean records (3, n) of the latest burst's record and the direct ranges.

        The arguments are those of :meth:`arrivals`.
        """
        ranges = self.direct_ranges(sources[0], mics, velocity, reference)
        start = (math.floor((min(ranges) / self.speed_of_sound - self.pre_roll)
                            * self.sample_rate) / self.sample_rate)
        window = (start - self.burst_duration, start + self.n_samples / self.sample_rate)
        arrivals = self.arrivals(sources, sounded, mics, velocity, reference, window)
        delay = arrivals.delay
        if self.adc_skews is not None:
            # Channel i samples at t_n + skew_i: its arrivals are sampled skew_i earlier
            # (synthesis.py: exact for any waveform).
            delay = delay - self.adc_skews[arrivals.microphone]
        return self.renderer.render(arrivals.microphone, delay, arrivals.gain, start,
                                    self.n_samples), ranges

    def direct_ranges(self, source, mics, velocity, reference):
        """Direct paths [m] of the latest burst to M1, M2, M3 (moving microphones, see above)."""
        ranges = []
        for mic, speed in zip(mics, velocity):
            # |x| as np.linalg.norm computes it for a vector, without its checks.
            to_mic = mic - source
            guess = math.sqrt(to_mic.dot(to_mic))
            to_mic = mic + speed * (guess / self.speed_of_sound - reference) - source
            ranges.append(math.sqrt(to_mic.dot(to_mic)))
        return ranges

    # ----- the arrivals of given emissions -----------------------------------------------------
    def arrivals(self, sources, sounded, mics, velocity, reference, window, detail=False):
        """Arrivals of every image of every burst that start within ``window``.

        Burst ``b`` is emitted ``b * burst_period`` before the latest (``b = 0``).

        Parameters
        ----------
        sources : numpy.ndarray
            Shape (B, 3): room-frame source position at each burst's emission.
        sounded : numpy.ndarray of bool
            Shape (B,): whether the source sounded burst ``b``.
        mics : numpy.ndarray
            Shape (3, 3): room-frame microphones (rows) at ``reference``.
        velocity : numpy.ndarray
            Shape (3, 3): their velocities [m/s].
        reference : float
            Instant of ``mics`` after the latest emission [s].
        window : tuple of float
            ``(first, last)`` [s] after the latest emission: arrivals starting in it.
        detail : bool, optional
            Only the arrivals in the window, with each one's burst, order, lattice row and
            path; otherwise the candidate pairs, those that turn out outside the window or
            unsounded at zero gain (cheaper to render than to select once more).

        Returns
        -------
        Arrivals
        """
        c = self.speed_of_sound
        lattice = self.lattice
        first, last = window
        # Candidates from the latest burst's images at the microphones as they are at
        # `reference`, widened by how far the source and the microphones move meanwhile.
        shift = sources - sources[0]
        moved = _largest_norm(shift[sounded])
        speed = _largest_norm(velocity)
        spread = (moved + speed * (last - first + abs(reference - first)) + 1e-4) / c
        # (3 microphones, N images) arrays, one coordinate at a time: numpy reduces a length-3
        # axis slowly, and most images have a candidate burst in every fix.
        # Only the images that can be reached within the cut (the lattice is sorted by reach).
        count = lattice.within(c * (max(self.cut, last) + spread), sources[0], mics)
        images = lattice.images(sources[0], count)
        to_image = [images[k][None, :] - mics[:, k, None] for k in range(3)]
        travel = _distance(*to_image)
        travel /= c
        reachable = travel <= self.cut + spread
        reachable |= lattice.order[:count] == 0
        # Burst b reaches the window when travel - b T lies in it (+- spread); none after the
        # last that sounded. The exact test is on each arrival's own delay (_exact), so these
        # bounds need only hold to within the spread.
        last_burst = int(np.flatnonzero(sounded)[-1])
        if self.burst_period > 0.0:
            periods = travel / self.burst_period
            lowest = np.ceil(periods - (last + spread) / self.burst_period)
            np.maximum(lowest, 0.0, out=lowest)
            highest = np.floor(periods - (first - spread) / self.burst_period, out=periods)
            np.minimum(highest, float(last_burst), out=highest)
        else:
            lowest = np.zeros_like(travel)
            highest = ((travel >= first - spread) & (travel <= last + spread)) - 1.0
        # A second burst reaches the window only where it is longer than T (a few pairs).
        if last - first + 2.0 * spread < 0.999 * self.burst_period:
            extras = 0
        else:
            extras = max(int(np.max(highest - lowest)), 0)
        parts = []
        for extra in range(extras + 1):
            burst = lowest + extra if extra else lowest
            candidate = burst <= highest
            candidate &= reachable
            parts.append(self._exact(to_image, travel, shift, burst, np.flatnonzero(candidate),
                                     sounded, velocity, reference, window, (moved, speed),
                                     detail))
        if len(parts) == 1:
            return parts[0]
        return Arrivals(*(None if column[0] is None else np.concatenate(column)
                          for column in zip(*(vars(part).values() for part in parts))))

    def _exact(self, to_image, travel, shift, burst, pair, sounded, velocity, reference,
               window, motion, detail):
        """The arrivals of (microphone, image) pairs for their burst.

        ``to_image``, ``travel`` and ``burst`` are (3, N) arrays over the microphones and the
        images; ``pair`` the ascending flat indices of the pairs to compute. ``to_image`` and
        ``travel`` are the latest burst's images seen from the microphones at ``reference``;
        an earlier burst's image is displaced by its source's ``shift`` (mirrored), then each
        microphone moves on to the arrival. The arrival instant that sets where the microphone
        is comes from ``travel`` (exact for the latest burst; for earlier ones off by the
        source's displacement, under 0.2 ms: 0.1 mm of array motion, a phase of the diffuse
        tail).
        """
        c = self.speed_of_sound
        lattice = self.lattice
        count = travel.shape[-1]
        # Ascending pairs: each microphone's are one run.
        ends = pair.searchsorted((0, count, 2 * count, 3 * count))
        runs = ends[1:] - ends[:-1]
        microphone = np.repeat(np.arange(3), runs)
        image = pair - np.repeat((0, count, 2 * count), runs)
        to_image = [d.ravel().take(pair) for d in to_image]
        travel = travel.ravel().take(pair)
        burst = burst.ravel().take(pair)
        offset = burst * -self.burst_period
        moved, speed = motion
        all_sounded = bool(sounded.all())
        if moved > 0.0 or not all_sounded:
            burst = burst.astype(np.int64)
        # A coordinate no body moves along keeps its values (adding zeros).
        if moved > 0.0:
            shift_by_axis = shift.T.copy()
            for axis in np.flatnonzero(shift_by_axis.any(axis=1)):
                to_image[axis] += lattice.signs[axis].take(image) * shift_by_axis[axis].take(burst)
        if speed > 0.0:
            lag = travel + offset
            lag -= reference
            velocity_by_axis = velocity.T
            for axis in np.flatnonzero(velocity_by_axis.any(axis=1)):
                to_image[axis] -= np.repeat(velocity_by_axis[axis], runs) * lag
        if moved > 0.0 or speed > 0.0:
            path = _distance(*to_image)
        else:
            path = travel * c
        delay = path / c
        delay += offset
        keep = delay > window[0]
        keep &= delay < window[1]
        if not all_sounded:
            keep &= sounded.take(burst)
        gain = self._amplitude.take(image)
        gain /= path
        if not detail:
            gain *= keep
            return Arrivals(microphone, delay, gain)
        return Arrivals(microphone[keep], delay[keep], gain[keep], burst[keep].astype(np.int64),
                        lattice.order.take(image[keep]), image[keep], path[keep])

    # ----- static geometry (validation, benchmarks) ------------------------------------------
    def static_records(self, source, mics, earlier=True):
        """Clean records (3, n) and direct ranges for bodies at rest (room-frame positions).

        ``earlier``: the source has sounded every ``burst_period`` long enough for every
        earlier burst within the cut to be heard (the steady state); otherwise one burst.
        """
        source = np.asarray(source, dtype=float)
        mics = np.asarray(mics, dtype=float)
        count = self.earlier_bursts + 1
        sounded = np.zeros(count, dtype=bool)
        sounded[:count if earlier else 1] = True
        reference = float(np.linalg.norm(mics[1] - source)) / self.speed_of_sound
        return self.render(np.tile(source, (count, 1)), sounded, mics, np.zeros((3, 3)),
                           reference)

    def response(self, source, mics, duration):
        """Noise-free records (3, m) of one burst from its emission to ``duration`` [s].

        Bodies at rest (room-frame positions); every image within the time cut. The energy
        decay of this response is what the room's RT60 is checked against.
        """
        source = np.asarray(source, dtype=float)
        arrivals = self.arrivals(source[None, :], np.ones(1, dtype=bool),
                                 np.asarray(mics, dtype=float), np.zeros((3, 3)), 0.0,
                                 (-self.burst_duration, duration))
        return self.renderer.render(arrivals.microphone, arrivals.delay, arrivals.gain, 0.0,
                                    int(math.ceil(duration * self.sample_rate)))
