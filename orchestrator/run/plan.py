"""What a run needs, checked and resolved once before t0: a :class:`RunPlan`.

:func:`plan_run` merges the parameters per instance (:mod:`~orchestrator.run.parameters`),
turns each instance's communication step into a whole number of base steps, chooses the
recorded columns and the stepping order, and asks the system description
(:mod:`orchestrator.system.sonotrack`) for the planner's stop distance. The runner then
passes the one frozen plan around instead of a dozen arguments.
"""

import math
from collections.abc import Callable
from dataclasses import dataclass

from components.common.errors import ConfigError

__all__ = ["BACKENDS", "RunPlan", "plan_run"]

# "fmi": the FMUs through fmpy; "in-process": the same slave classes stepped directly (no FMI)
BACKENDS = ("fmi", "in-process")


@dataclass(frozen=True)
class RunPlan:
    """Everything a run needs, checked before anything runs (built by :func:`plan_run`).

    Attributes
    ----------
    scenario : orchestrator.scenario.Scenario
        The scenario.
    system : orchestrator.system.System
        Its system.
    parameters : dict of str to dict
        Parameter values per instance (:func:`~orchestrator.run.parameters.instance_parameters`).
    rates : dict of str to int
        Base steps per communication step of each instance.
    columns : tuple of str
        The recorded columns, after ``time``, in the order of ``results.csv``.
    order : tuple of str
        Instance names in stepping order.
    algorithm : str
        The master algorithm (the scenario's unless overridden; the master checks it).
    record_every : int
        Base steps between recorded rows.
    stop_distance : float
        The planner's stop distance [m], which the summary's figures are measured against.
    backend : {"fmi", "in-process"}
        How the FMUs are stepped.
    handles : callable or None
        ``handles(instance_name, fmu_path)`` returns an FMU handle (``"fmi"`` backend only).
    fsync : bool
        fsync ``results.csv`` at every flush.
    """

    scenario: object
    system: object
    parameters: dict
    rates: dict
    columns: tuple
    order: tuple
    algorithm: str
    record_every: int
    stop_distance: float
    backend: str = "fmi"
    handles: Callable | None = None
    fsync: bool = False

    @property
    def expected_rows(self):
        """Rows ``results.csv`` holds if the run reaches its stop time (t0's row included)."""
        return self.scenario.step_count // self.record_every + 1


def plan_run(scenario, system, algorithm=None, record_interval=0.02, backend="fmi",
             fsync=False, handles=None):
    """Check a scenario against its system and resolve what its run needs.

    Parameters
    ----------
    scenario : orchestrator.scenario.Scenario
        A loaded scenario.
    system : orchestrator.system.System
        Its system, loaded.
    algorithm : {"gauss-seidel", "jacobi"}, optional
        Overrides the scenario's ``master``.
    record_interval : float
        Simulated time between recorded rows, rounded to a whole number of base steps (at
        least one).
    backend : {"fmi", "in-process"}
        How the FMUs are stepped.
    fsync : bool
        fsync ``results.csv`` at every flush.
    handles : callable, optional
        ``handles(instance_name, fmu_path)`` returns an FMU handle (see
        :func:`~orchestrator.run.runner.run_scenario`).

    Returns
    -------
    RunPlan

    Raises
    ------
    ConfigError
        For an unknown parameter or instance, a step that is not a whole number of base
        steps, an output that is not one, or an unknown backend.
    """
    from orchestrator.run.parameters import instance_parameters
    from orchestrator.system.sonotrack import SONOTRACK

    parameters = instance_parameters(system, scenario)
    rates = _rates(system, scenario)
    columns = _recorded_columns(system, scenario, SONOTRACK.recorded_columns)
    order = tuple(system.stepping_order())
    if backend not in BACKENDS:
        raise ConfigError(f"backend {backend!r} is not one of {', '.join(BACKENDS)}")
    return RunPlan(
        scenario=scenario, system=system, parameters=parameters, rates=rates,
        columns=tuple(columns), order=order, algorithm=algorithm or scenario.master,
        record_every=max(1, int(round(record_interval / scenario.base_step))),
        stop_distance=SONOTRACK.stop_distance(system, parameters), backend=backend,
        handles=handles, fsync=fsync)


def _rates(system, scenario):
    rates = {}
    for component in system.components:
        step = scenario.steps.get(component.name, scenario.base_step)
        ratio = step / scenario.base_step
        rate = int(round(ratio))
        if rate < 1 or not math.isclose(ratio, rate, rel_tol=1e-9):
            raise ConfigError(f"steps.{component.name} = {step} is not a positive integer "
                              f"multiple of base_step = {scenario.base_step}")
        rates[component.name] = rate
    return rates


def _recorded_columns(system, scenario, always):
    """The scenario's ``outputs`` and then those of ``always`` the system has, or every
    output of every instance if the scenario lists none."""
    if scenario.outputs:
        for name in scenario.outputs:
            system.variable(name)  # raises a ConfigError naming the valid variables
        extra = [c for c in always if c not in scenario.outputs]
        for name in list(extra):
            try:
                system.variable(name)
            except ConfigError:
                extra.remove(name)
        return list(scenario.outputs) + extra
    columns = []
    for component in system.components:
        for v in component.model_description.modelVariables:
            if v.causality == "output" and v.type in ("Real", "Integer", "Boolean"):
                columns.append(f"{component.name}.{v.name}")
    return columns
