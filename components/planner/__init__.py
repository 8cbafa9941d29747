"""Planner core: wheel-speed references that drive the robot to a heard target.

Pure numerics (numpy only); the FMU slave is :mod:`.fmu`.
"""

from .curvature_mode import CurvatureMode
from .geometry import (RADIUS_STRAIGHT, arc_curvature, arc_length, radius_of, stop_arc_length,
                       wheel_arc_lengths, wheel_factors)
from .limiter import limit_wheel_change
from .odometry import Odometry
from .odometry_check import OdometryCheck
from .planner import (FIX_ACCEPTED, FIX_INVALID, FIX_NEGATIVE, FIX_NONE, IDLE, MODES, MOVING,
                      STOPPING, TURNING, TargetPlanner)
from .pure_pursuit import PurePursuitMode
from .rotate_then_go import RotateThenGoMode

__all__ = [
    "TargetPlanner", "MODES", "CurvatureMode", "RotateThenGoMode", "PurePursuitMode",
    "Odometry", "OdometryCheck", "limit_wheel_change",
    "RADIUS_STRAIGHT", "arc_curvature", "arc_length", "stop_arc_length", "wheel_factors",
    "wheel_arc_lengths", "radius_of",
    "IDLE", "MOVING", "STOPPING", "TURNING",
    "FIX_NONE", "FIX_ACCEPTED", "FIX_INVALID", "FIX_NEGATIVE",
]
