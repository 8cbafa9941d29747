"""Sound-source core: the moving master robot with its speaker.

Pure numerics (numpy only); the FMU slave is :mod:`.fmu`.
"""

from .emission import BurstSchedule
from .paths import BUILT_IN_PATHS, PolylinePath, SCurvePath, make_path
from .source import MovingSource
from .waypoints import read_waypoints

__all__ = ["MovingSource", "BurstSchedule", "PolylinePath", "SCurvePath", "make_path",
           "BUILT_IN_PATHS", "read_waypoints"]
