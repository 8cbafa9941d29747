"""`sonotrack verify`: the wheel-speed loop's checks with verdicts and their reports.

Modules: :mod:`.loop_model` (the sampled loop), :mod:`.analysis` (poles, margins, edges,
Routh), :mod:`.robustness` (other plants, the largest stable plant-gain factor),
:mod:`.case1` (the paper's Case 1 on the nonlinear plant core), :mod:`.measure` (the figures
of a run), :mod:`.fmu_runs` (the built FMUs against the models), :mod:`.checks`
(requirements and verdicts) and :mod:`.robust_checks` (those on other plants);
the off-nominal requirements: :mod:`.designs` (the three designs judged and their loop
gains), :mod:`.sampled_wheel` (the discrete-time loop with the real controller),
:mod:`.wheel_experiments` (references, wheels, metrics), :mod:`.requirement_runs` (on the
loop), :mod:`.fmu_requirements` (through the FMUs in our master), :mod:`.requirement_checks`
(verdicts, ranges); :mod:`.figures`, :mod:`.document` and :mod:`.requirements_document` (the
report as one document, rendered to Markdown and HTML by :mod:`orchestrator.report`),
:mod:`.report` (:func:`verify`) and :mod:`.cli`.
"""

from .analysis import (
    KP_SEARCH_MAX, GainAnalysis, analyse_gains, continuous_gain_bound, controller_cross_check,
    kp_edge, routh_bounds, stability_boundary,
)
from .checks import Check, exit_status, load_requirements
from .cli import register_cli
from .fmu_runs import (
    closed_loop_fmu_comparison, compliance_bound, controller_fmu_comparison, fmu_step_comparison,
)
from .loop_model import LinearWheelModel, WheelLoopModel, linear_wheel_model
from .designs import DESIGNS, design_settings, loop_gains
from .fmu_requirements import fmu_requirements
from .report import DEFAULT_OUT_DIR, VerificationReport, off_nominal, verify
from .requirement_checks import design_lines, largest_ranges, requirement_checks
from .requirement_runs import measure_requirements
from .sampled_wheel import SampledWheel, run_loop
from .robustness import (
    PlantVariant, largest_stable_gain_factor, plant_gain_edges, robustness_point,
    steady_state_error,
)

__all__ = [
    "KP_SEARCH_MAX", "GainAnalysis", "analyse_gains", "continuous_gain_bound",
    "controller_cross_check", "kp_edge", "routh_bounds", "stability_boundary",
    "Check", "exit_status", "load_requirements", "register_cli",
    "closed_loop_fmu_comparison", "compliance_bound", "controller_fmu_comparison",
    "fmu_step_comparison", "LinearWheelModel", "WheelLoopModel", "linear_wheel_model",
    "DEFAULT_OUT_DIR", "VerificationReport", "verify", "off_nominal",
    "DESIGNS", "design_settings", "loop_gains", "fmu_requirements", "design_lines",
    "largest_ranges", "requirement_checks", "measure_requirements", "SampledWheel", "run_loop",
    "PlantVariant", "robustness_point", "steady_state_error", "largest_stable_gain_factor",
    "plant_gain_edges",
]
