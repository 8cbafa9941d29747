"""The localizer's parameters, validated together, with the quantities derived from them."""

import functools
import math

import numpy as np

from ..common.errors import ParameterError
from ..common.ranges import load_ranges
from .burst import ChirpBurst
from .estimators import ESTIMATORS
from .gcc import WEIGHTINGS
from .room import REAL_ABSORPTION, image_absorption, image_count, image_rt60, time_cut
from .synthesis import noise_std, quantisation_step, record_length

__all__ = ["DEFAULTS", "LocalizerSettings"]

# Defaults: the paper's array and ADC (Sec. 2, Sec. 6), its 2.5 ms window and 100 ms data cycle.
DEFAULTS = {
    "mic_spacing": 0.4,          # m
    "sample_rate": 100e3,        # Hz
    "adc_bits": 10,
    "snr_db": 20.0,              # dB at 1 m, see synthesis.noise_std
    "speed_of_sound": 340.0,     # m/s
    "window": 2.5e-3,            # s
    "fix_period": 0.1,           # s
    "band_low": 1000.0,          # Hz, chirp start
    "band_high": 16000.0,        # Hz, chirp end (the ETM-001 microphone reaches 18 kHz)
    "burst_duration": 1.0e-3,    # s, the longest that fits the 2.5 ms window with l/c
    "seed": 0,
    "array_offset": 0.0,         # m
    "method": "exact",
    "weighting": "band",
    "min_range": 0.4,            # m
    "max_range": 5.0,            # m
    "min_peak_quality": 0.35,
    "onset_threshold_db": 13.0,  # dB, matched-filter peak over its median
    # The room (room.py, reverberation.py; docs/acoustics.md): off by default (free field).
    "room": False,
    "room_origin_x": -3.5,       # m, the paper's 7 m x 7 m lab around the robot's start
    "room_origin_y": -0.5,       # m
    "room_length_x": 7.0,        # m
    "room_length_y": 7.0,        # m
    "room_height": 2.7,          # m
    "absorption_walls": 0.22,    # energy absorption; see room.image_rt60
    "absorption_floor": 0.22,
    "absorption_ceiling": 0.22,
    "rt60": 0.0,                 # s; > 0 sets one absorption for every surface (room.py)
    "source_height": 0.3,        # m, the speaker on the master robot
    "mic_height": 0.2,           # m, the microphones on the tracking robot
    "reverb_cut_db": 30.0,       # dB, image sources up to rt60 * reverb_cut_db / 60
    "image_order": -1,           # reflections at most; -1: no limit (the time cut alone)
    "burst_period": 0.01,        # s, the source's emit_period; 0: the latest burst alone
    # The array's imperfections (docs/acoustics.md): heard, never assumed by the estimator.
    "mic_left_along": 0.0,       # m, towards the robot's left
    "mic_left_across": 0.0,      # m, forward
    "mic_centre_along": 0.0,     # m
    "mic_centre_across": 0.0,    # m
    "mic_right_along": 0.0,      # m
    "mic_right_across": 0.0,     # m
    "adc_skew_left": 0.0,        # s, M1's sampling instants after M2's
    "adc_skew_right": 0.0,       # s, M3's sampling instants after M2's
}

# Per microphone (M1, M2, M3): its displacement (along, across) from the nominal array, and
# its channel's sampling skew (M2's is the reference, 0).
MIC_OFFSETS = (("mic_left_along", "mic_left_across"), ("mic_centre_along", "mic_centre_across"),
               ("mic_right_along", "mic_right_across"))
ADC_SKEWS = ("adc_skew_left", None, "adc_skew_right")
IMPERFECTIONS = tuple(name for pair in MIC_OFFSETS for name in pair) + ("adc_skew_left",
                                                                       "adc_skew_right")

# Fixed timing of the record around a burst: noise-only lead-in before the earliest arrival,
# and how far ahead of a detected onset a correlation window starts (covers onset jitter).
PRE_ROLL = 1.0e-3
PRE_TRIGGER = 0.2e-3
# Image sources the localizer computes per burst at most (about 20 ms of numpy per fix): the
# room's size, RT60 and reverb_cut_db set how many there are (room.image_count).
MAX_IMAGES = 200_000
# Each record is gated to its burst +- this margin: the matched-filter onset is within
# +-0.06 ms at 10 dB and 3 m (1st-99th percentile), so 0.15 ms loses no signal.
GATE_MARGIN = 0.15e-3


class LocalizerSettings:
    """Validated localizer parameters plus derived sample counts, burst and noise level.

    Parameters
    ----------
    **parameters
        Any of :data:`DEFAULTS`; missing ones take the default.

    Raises
    ------
    ParameterError
        Listing every invalid parameter with its value and the valid range or choices.
    """

    def __init__(self, **parameters):
        unknown = sorted(set(parameters) - set(DEFAULTS))
        if unknown:
            raise ParameterError(f"AcousticLocalizer: unknown parameters {unknown}; "
                                 f"valid: {', '.join(sorted(DEFAULTS))}")
        values = dict(DEFAULTS, **parameters)
        problems = _problems(values)
        if problems:
            raise ParameterError("AcousticLocalizer: " + "; ".join(problems))
        for name, value in values.items():
            setattr(self, name, value)
        self.seed = int(self.seed)
        self.adc_bits = int(self.adc_bits)
        self.image_order = int(self.image_order)
        self.room = bool(self.room)
        self.burst = ChirpBurst(self.band_low, self.band_high, self.burst_duration)
        self.passband = self.burst.passband()
        self.max_lag = self.mic_spacing / self.speed_of_sound
        self.noise_std = noise_std(self.burst, self.snr_db, self.sample_rate)
        self.noise_variance = self.noise_std**2 + quantisation_step(self.adc_bits) ** 2 / 12.0
        self.pre_roll = PRE_ROLL
        self.record_samples = record_length(PRE_ROLL, self.window, self.mic_spacing,
                                            self.speed_of_sound, self.sample_rate)
        self.window_samples = int(round(self.window * self.sample_rate))
        self.pre_trigger_samples = int(round(PRE_TRIGGER * self.sample_rate))
        self.gate_margin_samples = int(round(GATE_MARGIN * self.sample_rate))
        self.template = self.burst.waveform(
            np.arange(int(np.ceil(self.burst_duration * self.sample_rate))) / self.sample_rate)
        self.room_absorption, self.room_rt60, self.room_time_cut = _room_decay(values)
        # Floats (an FMU's Real may arrive as an int 0): the synthesis adds them to floats.
        self.mic_offsets = tuple((float(values[along]), float(values[across]))
                                 for along, across in MIC_OFFSETS)
        self.adc_skews = tuple(0.0 if name is None else float(values[name])
                               for name in ADC_SKEWS)

    def as_dict(self):
        """Return the parameters (not the derived values) as a plain dict."""
        return {name: getattr(self, name) for name in DEFAULTS}


def _finite_positive(values, name, unit):
    value = values[name]
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        return [f"{name} = {value!r} {unit} must be finite and > 0"]
    return []


def _problems(values):
    problems = []
    for name, unit in (("mic_spacing", "m"), ("sample_rate", "Hz"), ("speed_of_sound", "m/s"),
                       ("window", "s"), ("fix_period", "s"), ("band_low", "Hz"),
                       ("band_high", "Hz"), ("burst_duration", "s"), ("min_range", "m"),
                       ("max_range", "m")):
        problems += _finite_positive(values, name, unit)
    numbers_ok = not problems
    problems += _imperfection_problems(values)
    if not (isinstance(values["adc_bits"], int) and 2 <= values["adc_bits"] <= 24):
        problems.append(f"adc_bits = {values['adc_bits']!r} must be an integer in 2..24")
    for name in ("snr_db", "array_offset", "onset_threshold_db", "min_peak_quality"):
        if not (isinstance(values[name], (int, float)) and math.isfinite(values[name])):
            problems.append(f"{name} = {values[name]!r} must be a finite number")
    if not isinstance(values["seed"], int) or values["seed"] < 0:
        problems.append(f"seed = {values['seed']!r} must be a non-negative integer")
    if values["method"] not in ESTIMATORS:
        problems.append(f"method = {values['method']!r}; valid choices: "
                        f"{', '.join(sorted(ESTIMATORS))}")
    if values["weighting"] not in WEIGHTINGS:
        problems.append(f"weighting = {values['weighting']!r}; valid choices: "
                        f"{', '.join(WEIGHTINGS)}")
    if not numbers_ok:
        return problems
    if values["band_high"] <= values["band_low"]:
        problems.append(f"band_high = {values['band_high']!r} Hz must exceed "
                        f"band_low = {values['band_low']!r} Hz")
    if values["band_high"] + 1.0 / values["burst_duration"] >= 0.5 * values["sample_rate"]:
        problems.append(f"band_high = {values['band_high']!r} Hz plus the burst's 1/duration "
                        f"must stay below sample_rate/2 = {0.5 * values['sample_rate']!r} Hz")
    if values["max_range"] <= values["min_range"]:
        problems.append(f"max_range = {values['max_range']!r} m must exceed "
                        f"min_range = {values['min_range']!r} m")
    # A correlation window starts PRE_TRIGGER before a pair's first onset and must hold the
    # burst at both microphones of the pair, which arrive up to l/c apart.
    needed = PRE_TRIGGER + values["mic_spacing"] / values["speed_of_sound"] + values["burst_duration"]
    if values["window"] < needed:
        problems.append(f"window = {values['window']!r} s must be >= pre-trigger + l/c + "
                        f"burst_duration = {needed!r} s")
    if not 0.0 <= values["min_peak_quality"] < 1.0:
        problems.append(f"min_peak_quality = {values['min_peak_quality']!r} must be in [0, 1)")
    if not isinstance(values["room"], bool):
        problems.append(f"room = {values['room']!r} must be true or false")
    elif values["room"]:
        problems += _room_problems(values)
    return problems


def _imperfection_problems(values):
    """Each imperfection against its valid range in ranges.toml (the FMU's own check)."""
    table = _port_table().parameters
    return [problem for name in IMPERFECTIONS
            if (problem := table[name].problem(values[name])) is not None]


@functools.lru_cache(maxsize=1)
def _port_table():
    return load_ranges("acoustics")


_ROOM_NUMBERS = (("room_origin_x", "m"), ("room_origin_y", "m"), ("room_length_x", "m"),
                 ("room_length_y", "m"), ("room_height", "m"), ("absorption_walls", ""),
                 ("absorption_floor", ""), ("absorption_ceiling", ""), ("rt60", "s"),
                 ("source_height", "m"), ("mic_height", "m"), ("reverb_cut_db", "dB"),
                 ("burst_period", "s"))


def _room_size(values):
    return values["room_length_x"], values["room_length_y"], values["room_height"]


def _room_decay(values):
    """``(absorptions, rt60, time cut)`` of the room (absorptions from rt60 when it is given)."""
    if values["room"] is not True:
        return None, 0.0, 0.0
    size, c = _room_size(values), values["speed_of_sound"]
    if values["rt60"] > 0.0:
        uniform = image_absorption(values["rt60"], size, c)
        absorption = (uniform, uniform, uniform)
    else:
        absorption = (values["absorption_walls"], values["absorption_floor"],
                      values["absorption_ceiling"])
    rt60 = image_rt60(size, *absorption, c)
    return absorption, rt60, time_cut(rt60, values["reverb_cut_db"])


def _room_problems(values):
    """Relations of the room's parameters (each alone is checked against ranges.toml)."""
    problems = []
    for name, unit in _ROOM_NUMBERS:
        value = values[name]
        if not (isinstance(value, (int, float)) and not isinstance(value, bool)
                and math.isfinite(value)):
            problems.append(f"{name} = {value!r}{' ' + unit if unit else ''} must be a finite "
                            f"number")
    order = values["image_order"]
    if not (isinstance(order, int) and not isinstance(order, bool) and order >= -1):
        problems.append(f"image_order = {order!r} must be an integer >= -1 (-1: no limit)")
    if problems:
        return problems
    size = _room_size(values)
    if min(size) <= 0.0:
        return [f"room size {size!r} m: every side must be > 0"]
    for name in ("absorption_walls", "absorption_floor", "absorption_ceiling"):
        if not 0.0 <= values[name] <= 1.0:
            problems.append(f"{name} = {values[name]!r} must be in [0, 1]")
    for name in ("source_height", "mic_height"):
        if not 0.0 < values[name] < values["room_height"]:
            what = "the speaker" if name == "source_height" else "the microphones"
            problems.append(f"{name} = {values[name]!r} m puts {what} outside the room: valid "
                            f"(0, room_height = {values['room_height']!r}) m")
    across = 2.0 * values["mic_spacing"]
    if across >= min(size[:2]):
        problems.append(f"mic_spacing = {values['mic_spacing']!r} m: the array (2 x spacing) "
                        f"does not fit in a {size[0]!r} x {size[1]!r} m room")
    if values["rt60"] < 0.0:
        problems.append(f"rt60 = {values['rt60']!r} s must be >= 0 (0: from the absorptions)")
    if problems:
        return problems
    c = values["speed_of_sound"]
    shape = f"{size[0]:g} x {size[1]:g} x {size[2]:g} m"
    real_low, real_high = (image_rt60(size, a, a, a, c) for a in reversed(REAL_ABSORPTION))
    _, rt60, cut = _room_decay(values)
    if values["rt60"] > 0.0 and not real_low <= values["rt60"] <= real_high:
        uniform = image_absorption(values["rt60"], size, c)
        problems.append(f"rt60 = {values['rt60']!r} s: no {shape} room has it (it needs a "
                        f"uniform absorption of {uniform:.4g}, real surfaces have "
                        f"{REAL_ABSORPTION[0]}..{REAL_ABSORPTION[1]}); valid for this room: "
                        f"[{real_low:.3g}, {real_high:.3g}] s")
        return problems
    record_span = PRE_ROLL * 3.0 + values["window"] + values["mic_spacing"] / c
    count = image_count(c * (cut + record_span), size) if math.isfinite(cut) else math.inf
    if count > MAX_IMAGES:
        given = (f"rt60 = {values['rt60']!r} s" if values["rt60"] > 0.0 else
                 f"absorptions {values['absorption_walls']!r} / {values['absorption_floor']!r}"
                 f" / {values['absorption_ceiling']!r} (RT60 {rt60:.3g} s)")
        longest = _longest_rt60(size, c, values["reverb_cut_db"], record_span)
        problems.append(f"{given} with reverb_cut_db = {values['reverb_cut_db']!r}: about "
                        f"{count:.3g} image sources per burst, more than the {MAX_IMAGES} the "
                        f"localizer computes; valid RT60 for this room at this cut: "
                        f"[{real_low:.3g}, {longest:.3g}] s (or lower reverb_cut_db)")
    return problems


def _longest_rt60(size, speed_of_sound, cut_db, record_span):
    """The RT60 whose time cut reaches MAX_IMAGES image sources."""
    volume = size[0] * size[1] * size[2]
    reach = (MAX_IMAGES * volume * 3.0 / (4.0 * math.pi)) ** (1.0 / 3.0)
    return (reach / speed_of_sound - record_span) * 60.0 / cut_db
