"""Wheel-speed control numerics: the FGS-PD fuzzy gain scheduler, PID and PD laws.

Pure numerics on the standard library (numpy for the sampled centroid used in tests and
for the Routh-Hurwitz tables of :mod:`.routh`);
the pythonfmu slave lives in :mod:`.fmu` and is not imported here.
"""

from .controller import DEFAULTS, FORM_PARAMETERS, FORMS, MODES, WheelSpeedController
from .default_form import DefaultFormLaw
from .defuzzify import discrete_centroid, exact_centroid, weighted_average
from .derivative import FilteredDerivative
from .fgs_pd import PAPER_TO_OURS, check_gain_range, scheduled_gain
from .inference import CENTROIDS, METHODS, FuzzyGainScheduler
from .membership import INPUT_TERMS, OUTPUT_TERMS, fuzzify, input_membership, output_membership
from .pid import PidLaw
from .routh import (
    bilinear_to_w, is_hurwitz, is_schur, largest_stable_gain, rhp_root_count, routh_table,
    stable_gain_intervals,
)
from .rules import BIG, KD_TABLE, KP_TABLE, SMALL, rule_matrix

__all__ = [
    "DEFAULTS", "FORM_PARAMETERS", "FORMS", "MODES", "WheelSpeedController", "DefaultFormLaw",
    "discrete_centroid", "exact_centroid", "weighted_average",
    "FilteredDerivative",
    "PAPER_TO_OURS", "check_gain_range", "scheduled_gain",
    "CENTROIDS", "METHODS", "FuzzyGainScheduler",
    "INPUT_TERMS", "OUTPUT_TERMS", "fuzzify", "input_membership", "output_membership",
    "PidLaw",
    "bilinear_to_w", "is_hurwitz", "is_schur", "largest_stable_gain", "rhp_root_count",
    "routh_table", "stable_gain_intervals",
    "BIG", "KD_TABLE", "KP_TABLE", "SMALL", "rule_matrix",
]
