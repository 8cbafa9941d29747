"""One run: a scenario in, a run folder out (``results.csv``, ``summary.json``, plots).

The pipeline, one concept per module, in the order a run passes through it:

- :mod:`~orchestrator.run.runner`: :func:`run_scenario`, which loads the scenario and its
  system, instantiates the FMUs and drives the rest;
- :mod:`~orchestrator.run.plan`: the :class:`RunPlan`, what a run needs, checked and
  resolved once before t0;
- :mod:`~orchestrator.run.parameters`: :func:`instance_parameters`, the parameter values per
  instance (``.ssd`` bindings, scenario overrides, fault schedules, seed);
- :mod:`~orchestrator.run.master`: the co-simulation master (fixed base step, multi-rate,
  Gauss-Seidel or Jacobi), written in :mod:`components.system.master`;
- :mod:`~orchestrator.run.signals`: SIGINT / SIGTERM as a request to stop at the next step;
- :mod:`~orchestrator.run.recorder`: outputs streamed to ``results.csv`` while the run goes;
- :mod:`~orchestrator.run.folder`: the run folder, its status lifecycle and atomic writes;
- :mod:`~orchestrator.run.results`: ``results.csv`` read back in bounded chunks;
- :mod:`~orchestrator.run.summary`: the figures of ``summary.json`` over a stream of row
  chunks, from the rows kept while recording or from ``results.csv`` read back; the figures
  themselves in :mod:`~orchestrator.run.metrics` (tracking, and the one point-to-polyline
  distance) and :mod:`~orchestrator.run.fault_metrics` (robustness);
- :mod:`~orchestrator.run.summary_text`: the summary as the lines ``sonotrack run`` prints;
- :mod:`~orchestrator.run.plots`, :mod:`~orchestrator.run.fault_plots` and
  :mod:`~orchestrator.run.plot_renderer`: the PNG figures, drawn by a renderer process;
- :mod:`~orchestrator.run.compare`: finished runs side by side (``sonotrack compare``);
- :mod:`~orchestrator.run.as_fmu`: a scenario's run plan as the whole-system FMU
  (``sonotrack build --system``).

Imports :mod:`orchestrator.fmu`, :mod:`orchestrator.system`, :mod:`orchestrator.scenario` and
:mod:`orchestrator.report`; never sweep, verify, reproduce or the CLI.
"""

from .folder import (ABANDONED, RESULTS_NAME, STATUSES, SUMMARY_NAME, RunFolder,
                     atomic_write_bytes, atomic_write_json, atomic_write_text, mark_abandoned,
                     read_summary)
from .master import MASTER_ALGORITHMS, InstanceSpec, Link, Master
from .results import count_rows, iter_result_chunks, read_header, read_results
from .parameters import instance_parameters
from .plan import BACKENDS, RunPlan, plan_run
from .runner import RunResult, run_scenario

__all__ = ["ABANDONED", "BACKENDS", "MASTER_ALGORITHMS", "RESULTS_NAME", "STATUSES",
           "SUMMARY_NAME", "InstanceSpec", "Link", "Master", "RunFolder", "RunPlan", "RunResult",
           "atomic_write_bytes", "atomic_write_json", "atomic_write_text", "count_rows",
           "instance_parameters", "iter_result_chunks", "mark_abandoned", "plan_run",
           "read_header", "read_results", "read_summary", "run_scenario"]
