"""What every sonotrack FMU shares, on the host side and inside each built FMU.

- :mod:`~components.common.errors`: the one exception hierarchy (``SonotrackError`` and its
  subclasses of builtins).
- :mod:`~components.common.faults`: the fault vocabulary and schedules, checked the same way by
  the host and inside the FMU.
- :mod:`~components.common.ranges`: the port table of an FMU (``ranges.toml``): description,
  type, unit, start value and valid range of every parameter and input, and the step range.
- :mod:`~components.common.units`: the units a port may carry, as SI base-unit exponents.
- :mod:`~components.common.slave`: ``SonotrackSlave``, the pythonfmu base class of every slave.
- :mod:`~components.common.state`: JSON-safe snapshots of a core's complete state.
- :mod:`~components.common.trapezoid`: trapezoidal speed profiles (source and planner).

Nothing is re-exported: import from the module. Importing this package then costs nothing, the
host side (scenario checks, fault schedules) never pulls in pythonfmu or numpy through it, and
inside an FMU (where ``sonotrack build`` copies this folder under a private package name) the
modules load in the order the slave imports them.
"""

__all__ = []
