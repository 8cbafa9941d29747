"""A co-simulation system: an ``.ssd`` checked against its FMUs, ready for a master.

:func:`check_system` compares a :class:`~orchestrator.ssp.SystemDescription` with the model
descriptions of its FMUs and returns *every* problem it finds (unknown components and ports,
type and unit mismatches, miswired or unconnected inputs, bad parameter bindings, algebraic
loops). :func:`load_system` reads the files, runs the checks and either raises one
:class:`SystemDescriptionError` listing all problems or returns a :class:`System` whose
connections are resolved to value references, so that the master never looks a name up again.

One concept per module:

- :mod:`.variables`: a resolved :class:`Variable` and the look-up helpers;
- :mod:`.graph`: direct feedthrough, algebraic loops and the Gauss-Seidel stepping order
  (documented in ``docs/system.md`` and :func:`gauss_seidel_order`);
- :mod:`.checks`: every problem of a description against its FMUs;
- :mod:`.loading`: reading the files into a :class:`System`;
- :mod:`.sonotrack`: what is particular to the sonotrack system (which instance plays which
  role, where the stop distance comes from, the columns a run's summary reads).
"""

from .checks import SystemDescriptionError, check_system
from .graph import algebraic_loops, direct_dependencies, gauss_seidel_order
from .loading import System, SystemComponent, load_system
from .sonotrack import SONOTRACK, SonotrackSystem
from .variables import ResolvedConnection, Variable, variable_unit

__all__ = [
    "SystemDescriptionError",
    "Variable",
    "ResolvedConnection",
    "SystemComponent",
    "System",
    "variable_unit",
    "direct_dependencies",
    "algebraic_loops",
    "gauss_seidel_order",
    "check_system",
    "load_system",
    "SonotrackSystem",
    "SONOTRACK",
]
