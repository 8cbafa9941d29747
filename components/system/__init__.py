"""The whole system in one slave: the co-simulation master and the TrackingSystem FMU.

- :mod:`~components.system.master`: the master of ``sonotrack run`` (fixed base step,
  multi-rate, Gauss-Seidel or Jacobi); ``orchestrator.run.master`` re-exports it;
- :mod:`~components.system.description`: what the system FMU runs (instances, connections,
  schedule, parameter values), as data it carries in its resources;
- :mod:`~components.system.instances`: a slave object behind the master's instance
  interface, stepped in-process;
- :mod:`~components.system.fmu`: the ``TrackingSystem`` slave (pythonfmu).

Re-exports the master and the description; the slave is imported from :mod:`.fmu` only (it
needs pythonfmu, which the host side of a run does not).
"""

from .description import DESCRIPTION_FILE, InstancePlan, SystemDescription
from .master import MASTER_ALGORITHMS, InstanceSpec, Link, Master

__all__ = ["DESCRIPTION_FILE", "MASTER_ALGORITHMS", "InstancePlan", "InstanceSpec", "Link",
           "Master", "SYSTEM_MODEL", "SystemDescription"]

SYSTEM_MODEL = "TrackingSystem"
"""Model name (and slave class) of the whole-system FMU."""
