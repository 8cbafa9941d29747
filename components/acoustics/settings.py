"""The localizer's parameters, validated together, with the quantities derived from them."""

import math

import numpy as np

from ..common.errors import ParameterError
from .burst import ChirpBurst
from .estimators import ESTIMATORS
from .gcc import WEIGHTINGS
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
}

# Fixed timing of the record around a burst: noise-only lead-in before the earliest arrival,
# and how far ahead of a detected onset a correlation window starts (covers onset jitter).
PRE_ROLL = 1.0e-3
PRE_TRIGGER = 0.2e-3
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
    return problems
