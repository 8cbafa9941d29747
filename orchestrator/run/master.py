"""The co-simulation master, as the run layer uses it (fixed base step, multi-rate, Gauss-Seidel
or Jacobi).

The algorithm is written once, in :mod:`components.system.master` (its docstring states it
exactly): the whole-system FMU (``sonotrack build --system``) carries that module inside, and a
component may not import the orchestrator, so the module sits below both. This name stays the
stable path for the run layer, the sweeps, the studies and the benchmarks.
"""

from components.system.master import MASTER_ALGORITHMS, InstanceSpec, Link, Master

__all__ = ["InstanceSpec", "Link", "Master", "MASTER_ALGORITHMS"]
