"""The acoustic localizer: sensor (synthesised microphone records) and estimator in one core.

:func:`locate_bursts` runs one burst per geometry, vectorised over any batch of geometries
(the benchmark's Monte Carlo); :class:`LocalizerCore` is the stateful sample-and-hold the FMU
wraps: one fix per ``fix_period`` while the source emits, the last valid fix held otherwise.
"""

import math

import numpy as np
# numpy.random with the module (the core makes a generator): a first import inside an FMU call
# can crash pythonfmu's binary
import numpy.random  # noqa: F401

from ..common.errors import InputError
from ..common.faults import parse_schedule
from .estimators import make_estimator
from .faults import channel_fault, drops_fix, faulted_records, mirror_in_wall
from .geometry import _robot_polar_one, _source_in_array_frame_one, microphone_ranges
from .motion import PoseHistory
from .reverberation import RoomAcoustics
from .settings import LocalizerSettings
from .synthesis import _quantise, _synthesise_one, synthesise_records
from .tdoa import _measure_tdoas_one, measure_tdoas

__all__ = ["FixStatus", "BurstFixes", "judge", "locate_bursts", "locate_records", "LocalizerCore"]


class FixStatus:
    """Outcome codes of a fix attempt (the ``fix_status`` output); 0 is a valid fix."""

    OK = 0
    NOT_EMITTING = 1
    BEHIND = 2
    TOO_CLOSE = 3
    OUT_OF_RANGE = 4
    NO_ONSET = 5
    WEAK_PEAK = 6
    LAG_AT_BOUND = 7
    INCONSISTENT = 8
    ESTIMATE_OUT_OF_RANGE = 9
    DEAD_MICROPHONE = 10
    CLIPPED_MICROPHONE = 11
    FIX_LOST = 12
    NAMES = ("ok", "not emitting", "source behind the array", "source closer than min_range",
             "source beyond max_range", "no burst onset detected", "weak correlation peak",
             "correlation peak on the +-l/c bound", "delays geometrically inconsistent",
             "estimated range beyond max_range", "a microphone record is dead",
             "a microphone record is clipped", "fix lost (dropped before it was taken)")


class BurstFixes:
    """Result of :func:`locate_bursts` (arrays over the batch shape).

    Attributes
    ----------
    tdoa_12, tdoa_23 : numpy.ndarray
        Measured delays [s].
    distance, bearing : numpy.ndarray
        Range [m] and bearing [rad] from the array centre M2 (NaN where inconsistent).
    quality : numpy.ndarray
        The weaker pair's peak quality.
    status : numpy.ndarray of int
        :class:`FixStatus` code per burst.
    """

    def __init__(self, tdoa_12, tdoa_23, distance, bearing, quality, status):
        self.tdoa_12 = tdoa_12
        self.tdoa_23 = tdoa_23
        self.distance = distance
        self.bearing = bearing
        self.quality = quality
        self.status = status

    @property
    def valid(self):
        """Boolean array: the burst gave a valid fix."""
        return self.status == FixStatus.OK


def judge(measurement, location, settings):
    """Return the :class:`FixStatus` of each measured burst (the first failed check wins)."""
    quality = measurement.quality.min(axis=-1)
    status = np.full(quality.shape, FixStatus.OK)
    checks = (
        (location.distance > settings.max_range, FixStatus.ESTIMATE_OUT_OF_RANGE),
        (~location.consistent, FixStatus.INCONSISTENT),
        (measurement.at_bound, FixStatus.LAG_AT_BOUND),
        (quality < settings.min_peak_quality, FixStatus.WEAK_PEAK),
        (~measurement.detected, FixStatus.NO_ONSET),
    )
    # Applied from the least to the most fundamental failure, so the most fundamental one wins.
    for failed, code in checks:
        status = np.where(failed, code, status)
    return status


def locate_bursts(settings, estimator, ranges, rng):
    """Synthesise and localise one burst for each row of ``ranges``.

    Parameters
    ----------
    settings : LocalizerSettings
    estimator : PositionEstimator
    ranges : array_like
        Shape (..., 3): true ranges R1, R2, R3 [m] (to the microphones where they are: with
        the settings' ``mic_offsets``); the channels are sampled with its ``adc_skews``.
    rng : numpy.random.Generator

    Returns
    -------
    BurstFixes
    """
    records = synthesise_records(
        settings.burst, ranges, sample_rate=settings.sample_rate,
        speed_of_sound=settings.speed_of_sound, snr_db=settings.snr_db,
        adc_bits=settings.adc_bits, pre_roll=settings.pre_roll,
        n_samples=settings.record_samples, rng=rng, adc_skews=settings.adc_skews)
    return locate_records(settings, estimator, records)


def locate_records(settings, estimator, records):
    """Localise given microphone records of shape (..., 3, n) (e.g. from a room simulator)."""
    measurement = measure_tdoas(records, settings)
    location = estimator.locate(measurement.tdoa_12, measurement.tdoa_23)
    status = judge(measurement, location, settings)
    return BurstFixes(measurement.tdoa_12, measurement.tdoa_23, location.distance,
                      location.bearing, measurement.quality.min(axis=-1), status)


def _locate_one(settings, estimator, ranges, rng):
    """:func:`locate_bursts` for one geometry (three float ranges), as Python scalars.

    The same draws and numbers as :func:`locate_bursts` on shape (3,); a fix's arrays are
    so small that numpy's per-call overhead, not the work, sets the cost, so the scalar
    steps run in Python.
    """
    records = _synthesise_one(
        settings.burst, ranges, sample_rate=settings.sample_rate,
        speed_of_sound=settings.speed_of_sound, noise_std=settings.noise_std,
        adc_bits=settings.adc_bits, pre_roll=settings.pre_roll,
        n_samples=settings.record_samples, rng=rng, adc_skews=settings.adc_skews)
    return _locate_records_one(settings, estimator, records)


def _locate_records_one(settings, estimator, records):
    """:func:`locate_records` for the records (3, n) of one burst, as Python scalars.

    A dead or clipped record (:func:`.faults.channel_fault`) gives no delay worth trusting:
    the burst is refused with :attr:`FixStatus.DEAD_MICROPHONE` or
    :attr:`FixStatus.CLIPPED_MICROPHONE` before any correlation.
    """
    dead, clipped = channel_fault(records, settings.adc_bits)
    if dead is not None or clipped is not None:
        status = FixStatus.DEAD_MICROPHONE if dead is not None else FixStatus.CLIPPED_MICROPHONE
        return BurstFixes(0.0, 0.0, math.nan, math.nan, 0.0, status)
    measurement = _measure_tdoas_one(records, settings)
    distance, bearing, consistent = estimator.locate_one(measurement.tdoa_12,
                                                         measurement.tdoa_23)
    quality = min(measurement.quality)
    # judge(), the most fundamental failure first.
    if not measurement.detected:
        status = FixStatus.NO_ONSET
    elif quality < settings.min_peak_quality:
        status = FixStatus.WEAK_PEAK
    elif measurement.at_bound:
        status = FixStatus.LAG_AT_BOUND
    elif not consistent:
        status = FixStatus.INCONSISTENT
    elif distance > settings.max_range:
        status = FixStatus.ESTIMATE_OUT_OF_RANGE
    else:
        status = FixStatus.OK
    return BurstFixes(measurement.tdoa_12, measurement.tdoa_23, distance, bearing, quality,
                      status)


class LocalizerCore:
    """Sample-and-hold localizer: one fix per ``fix_period`` while the source emits.

    Fix instants are ``k * fix_period``; the step whose interval ``[t, t + h)`` contains one
    takes a fix from the inputs at ``t``, so outputs never feed through directly. A failed
    attempt sets ``valid = False`` and keeps the last valid fix's values; ``measurement_id``
    counts valid fixes.

    With ``room`` true the records are those of the shoebox room (:mod:`.reverberation`): the
    core keeps the inputs of recent steps (:class:`~.motion.PoseHistory`, part of the state)
    for the source's positions at earlier emissions, and refuses a step whose source or
    microphones are outside the room (:class:`~.room.LeftRoomError`).

    Parameters
    ----------
    **parameters
        See :data:`~.settings.DEFAULTS`.
    """

    # The fault schedule and the room are set from parameters and never change: not part of
    # the state (the room's image lattice is rebuilt from them).
    STATE_CONSTANTS = ("faults", "acoustics")

    def __init__(self, fault_schedule="", **parameters):
        self.settings = LocalizerSettings(**parameters)
        self.faults = parse_schedule(fault_schedule, "AcousticLocalizer")
        self.faults_active = 0
        self.fix_attempts = 0
        self.estimator = make_estimator(self.settings.method, self.settings.mic_spacing,
                                        self.settings.speed_of_sound)
        self.rng = np.random.default_rng(self.settings.seed)
        self.last_fix_index = -1
        self.distance = 0.0
        self.bearing = 0.0
        self.valid = False
        self.tdoa_12 = 0.0
        self.tdoa_23 = 0.0
        self.measurement_id = 0
        self.peak_quality = 0.0
        self.fix_status = FixStatus.NOT_EMITTING
        self.true_distance = 0.0
        self.true_bearing = 0.0
        self.missed_instants = 0
        self.acoustics = RoomAcoustics(self.settings) if self.settings.room else None
        self.history = (PoseHistory(self.acoustics.history_horizon)
                        if self.acoustics is not None else None)

    def fix_due(self, time, step_size):
        """Return the index of the latest fix instant before ``time + step_size`` not yet served, or None."""
        # The tolerance keeps an instant that t0 + k*h reaches only up to rounding in the next step.
        latest = math.ceil((time + step_size) / self.settings.fix_period - 1e-9) - 1
        return latest if latest > self.last_fix_index else None

    def step(self, time, step_size, source_x, source_y, emitting, robot_x, robot_y, robot_heading):
        """Advance over ``[time, time + step_size)``; take a fix if an instant falls in it.

        Returns
        -------
        bool
            Whether a fix was attempted in this step.

        Raises
        ------
        InputError
            A position or heading is NaN or infinite (naming the port and value).
        LeftRoomError
            In a room, the source or a microphone is outside it (naming the time, the body
            and where it is).
        """
        for port, value in (("source_x", source_x), ("source_y", source_y),
                            ("robot_x", robot_x), ("robot_y", robot_y),
                            ("robot_heading", robot_heading)):
            if not math.isfinite(value):
                raise InputError(f"AcousticLocalizer: input {port} = {value!r} is not finite")
        if self.acoustics is not None:
            self.acoustics.check_inside(time, source_x, source_y, robot_x, robot_y,
                                        robot_heading)
            self.history.record(time, source_x, source_y, emitting, robot_x, robot_y,
                                robot_heading)
        index = self.fix_due(time, step_size)
        if index is None:
            return False
        if self.last_fix_index >= 0:
            self.missed_instants += index - self.last_fix_index - 1
        self.last_fix_index = index
        active = self.faults.active(index * self.settings.fix_period) if self.faults else ()
        self.faults_active = len(active)
        self.fix_attempts += 1
        self._attempt(source_x, source_y, bool(emitting), robot_x, robot_y, robot_heading,
                      index, active, time)
        return True

    def _attempt(self, source_x, source_y, emitting, robot_x, robot_y, robot_heading,
                 index=0, active=(), time=0.0):
        s = self.settings
        forward, left = _source_in_array_frame_one(source_x, source_y, robot_x, robot_y,
                                                   robot_heading, s.array_offset)
        self.true_distance, self.true_bearing = _robot_polar_one(
            math.hypot(forward, left), math.atan2(left, forward), s.array_offset)
        range_2 = math.hypot(forward, left)
        # The array cannot tell front from back (a line array's delays are mirror-symmetric),
        # and the robot's body shadows sound from behind: only the front half-plane is heard.
        lost = any(f.kind == "lost_fixes" and drops_fix(index, f.magnitude) for f in active)
        if lost:
            status = FixStatus.FIX_LOST
        elif not emitting:
            status = FixStatus.NOT_EMITTING
        elif range_2 < s.min_range:
            status = FixStatus.TOO_CLOSE
        elif forward <= 0.0:
            status = FixStatus.BEHIND
        elif range_2 > s.max_range:
            status = FixStatus.OUT_OF_RANGE
        else:
            # The sound reaches the microphones where they are; the estimator assumes the
            # nominal array (settings.mic_offsets, docs/acoustics.md).
            ranges = microphone_ranges(source_x, source_y, robot_x, robot_y, robot_heading,
                                       s.mic_spacing, s.array_offset, s.mic_offsets)
            record_faults = [f for f in active if f.kind != "lost_fixes"]
            if self.acoustics is not None:
                fixes = _locate_records_one(s, self.estimator, self._room_records(
                    time, record_faults, source_x, source_y, robot_x, robot_y, robot_heading))
            elif record_faults:
                fixes = _locate_records_one(s, self.estimator, self._faulted_records(
                    ranges, record_faults, source_x, source_y, robot_x, robot_y,
                    robot_heading))
            else:
                fixes = _locate_one(s, self.estimator, ranges, self.rng)
            status = fixes.status
            self.peak_quality = fixes.quality
            if status == FixStatus.OK:
                self.distance, self.bearing = _robot_polar_one(fixes.distance, fixes.bearing,
                                                               s.array_offset)
                self.tdoa_12 = fixes.tdoa_12
                self.tdoa_23 = fixes.tdoa_23
                self.measurement_id += 1
        self.fix_status = int(status)
        self.valid = status == FixStatus.OK

    def _room_records(self, time, faults, source_x, source_y, robot_x, robot_y,
                      robot_heading):
        """The room's records of the burst heard at ``time``, with noise, faults and the ADC."""
        s = self.settings
        clean, ranges = self.acoustics.records(self.history.table(), time)
        if not faults:
            noise = self.rng.standard_normal(clean.shape)
            noise *= s.noise_std
            noise += clean
            return _quantise(noise, s.adc_bits)
        walls = [f for f in faults if f.kind == "reflecting_wall"]
        image_ranges = None
        # The fault's wall stands apart from the room's: its image (of the direct sound only,
        # reflection 0.9 as in free field) adds to the room's response.
        if walls and (source_x - walls[0].magnitude) * (robot_x - walls[0].magnitude) > 0.0:
            image_x, image_y = mirror_in_wall(source_x, source_y, walls[0].magnitude)
            rise = s.source_height - s.mic_height
            image_ranges = [math.hypot(r, rise) for r in microphone_ranges(
                image_x, image_y, robot_x, robot_y, robot_heading, s.mic_spacing,
                s.array_offset, s.mic_offsets)]
        return faulted_records(s, ranges, image_ranges, faults, self.rng, clean=clean)

    def _faulted_records(self, ranges, faults, source_x, source_y, robot_x, robot_y,
                         robot_heading):
        s = self.settings
        walls = [f for f in faults if f.kind == "reflecting_wall"]
        image_ranges = None
        # The image exists only while source and robot are on the same side of the wall.
        if walls and (source_x - walls[0].magnitude) * (robot_x - walls[0].magnitude) > 0.0:
            image_x, image_y = mirror_in_wall(source_x, source_y, walls[0].magnitude)
            image_ranges = microphone_ranges(image_x, image_y, robot_x, robot_y, robot_heading,
                                             s.mic_spacing, s.array_offset, s.mic_offsets)
        return faulted_records(s, ranges, image_ranges, faults, self.rng)
