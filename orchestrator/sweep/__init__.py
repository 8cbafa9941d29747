"""Many runs at once: parameter grids, seeds and Monte Carlo draws on Dask, stored by the hash
of everything they read.

- :mod:`~orchestrator.sweep.plan`: ``--set`` / ``--seeds`` parsing, the grid, every run
  checked and keyed before anything runs;
- :mod:`~orchestrator.sweep.inputs`: the files a run reads (scenario, ``.ssd``, ``.ssv``,
  data files such as a waypoint CSV, FMUs), by content;
- :mod:`~orchestrator.sweep.store`: stored runs read defensively, the table written
  atomically;
- :mod:`~orchestrator.sweep.engine`: Dask's local process scheduler over warm workers, or a
  ``dask.distributed`` scheduler;
- :mod:`~orchestrator.sweep.worker`: one run per task on FMU instances kept warm;
- :mod:`~orchestrator.sweep.runs`: :func:`sweep` and :func:`run_many`.
"""

from orchestrator.sweep.engine import ClusterEngine, LocalEngine, open_engine
from orchestrator.sweep.plan import (PlannedRun, expand_grid, parse_assignment, parse_seeds,
                                     plan_runs, plan_scenarios)
from orchestrator.sweep.runs import SweepResult, run_many, sweep

__all__ = ["ClusterEngine", "LocalEngine", "PlannedRun", "SweepResult", "expand_grid",
           "open_engine", "parse_assignment", "parse_seeds", "plan_runs", "plan_scenarios",
           "run_many", "sweep"]
