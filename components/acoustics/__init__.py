"""Acoustic localizer: three-microphone line array, synthesised records, TDOA range and bearing.

Free field by default; with ``room`` a shoebox room heard through image sources for the moving
source and the moving array (``room``, ``motion``, ``reverberation``, ``rendering``).

Pure numerics (numpy only); the pythonfmu slave is :mod:`.fmu`, not imported here.
"""

from .burst import ChirpBurst
from .crlb import (band_derivative_energy, geometry_jacobian, range_bearing_covariance_bound,
                   tdoa_covariance_bound)
from .estimators import (ESTIMATORS, ExactNearField, FarField, Location, PaperEq4,
                         PositionEstimator, far_field_pair_bearings, make_estimator,
                         register_estimator)
from .gcc import WEIGHTINGS, DelayEstimate, estimate_delays, estimate_pair_delays
from .geometry import (exact_tdoas, microphone_positions, microphone_ranges, robot_polar,
                       source_in_array_frame)
from .localizer import BurstFixes, FixStatus, LocalizerCore, judge, locate_bursts, locate_records
from .motion import PoseHistory
from .onset import detect_onsets
from .rendering import ArrivalRenderer
from .reverberation import Arrivals, RoomAcoustics
from .room import (ImageLattice, LeftRoomError, ShoeboxRoom, eyring_rt60, image_absorption,
                   image_rt60, sabine_rt60)
from .settings import DEFAULTS, LocalizerSettings
from .synthesis import (REFERENCE_AMPLITUDE, REFERENCE_DISTANCE, noise_std, quantisation_step,
                        quantise, record_length, synthesise_records)
from .tdoa import TdoaMeasurement, measure_tdoas

__all__ = [
    "ChirpBurst", "band_derivative_energy", "geometry_jacobian", "range_bearing_covariance_bound",
    "tdoa_covariance_bound", "ESTIMATORS", "ExactNearField", "FarField", "Location", "PaperEq4",
    "PositionEstimator", "far_field_pair_bearings", "make_estimator", "register_estimator",
    "WEIGHTINGS", "DelayEstimate", "estimate_delays", "estimate_pair_delays", "exact_tdoas",
    "microphone_positions", "microphone_ranges", "robot_polar", "source_in_array_frame",
    "BurstFixes", "FixStatus", "LocalizerCore", "judge",
    "locate_bursts", "locate_records", "PoseHistory", "detect_onsets", "ArrivalRenderer",
    "Arrivals", "RoomAcoustics", "ImageLattice", "LeftRoomError", "ShoeboxRoom", "eyring_rt60",
    "image_absorption", "image_rt60", "sabine_rt60", "DEFAULTS",
    "LocalizerSettings", "REFERENCE_AMPLITUDE", "REFERENCE_DISTANCE", "noise_std",
    "quantisation_step", "quantise", "record_length", "synthesise_records", "TdoaMeasurement",
    "measure_tdoas",
]
