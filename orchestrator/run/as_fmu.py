"""A scenario's run as one FMU: its run plan written down as a system description, then built.

:func:`system_description` turns the :class:`~orchestrator.run.plan.RunPlan` that
``sonotrack run`` makes of a scenario (the parameter values per instance after ``.ssd``
bindings, overrides, fault schedules and seed; the rates; the stepping order; the master
algorithm) into the :class:`components.system.SystemDescription` the whole-system FMU carries,
so the FMU runs what the run would. :func:`build_scenario_fmu` makes the plan and builds
``TrackingSystem.fmu`` (:mod:`orchestrator.builder.system_fmu`). This module sits in the run
layer because the plan does: the builder, below it, only packages a description.
"""

from pathlib import Path

from components import FMU_PACKAGES
from components.common.errors import BuildError, ConfigError
from components.system import InstancePlan, SystemDescription

__all__ = ["build_scenario_fmu", "system_description"]


def system_description(plan):
    """The description of a whole-system FMU that runs ``plan``.

    Parameters
    ----------
    plan : orchestrator.run.RunPlan
        A run plan (:func:`~orchestrator.run.plan.plan_run`).

    Returns
    -------
    components.system.SystemDescription
        Instances in the plan's stepping order; an instance that takes the scenario's seed
        (it has a ``seed`` parameter and the scenario does not set it) is ``seeded`` and its
        seed is left to the FMU's ``seed`` parameter.

    Raises
    ------
    ConfigError
        If an instance's model is not one of the sonotrack FMUs (the system FMU carries their
        slaves, not other FMUs).
    """
    from orchestrator.system.sonotrack import SONOTRACK

    scenario, system = plan.scenario, plan.system
    instances, problems = [], []
    for name in plan.order:
        model = system.component(name).model_description.modelName
        if model not in FMU_PACKAGES:
            problems.append(f"instance {name}: model {model!r} is not a sonotrack FMU "
                            f"({', '.join(FMU_PACKAGES)})")
            continue
        parameters = dict(plan.parameters[name])
        declared = {v.name for v in system.component(name).model_description.modelVariables
                    if v.causality == "parameter"}
        # the rule of orchestrator.run.parameters: the scenario's seed, unless it sets this one
        seeded = "seed" in declared and f"{name}.seed" not in scenario.parameters
        if seeded:
            parameters.pop("seed", None)
        instances.append(InstancePlan(name, model, FMU_PACKAGES[model], plan.rates[name],
                                      parameters, seeded))
    if problems:
        raise ConfigError(f"{getattr(scenario, 'source', 'scenario')}: cannot be one FMU: "
                          + "; ".join(problems))
    positions = {}
    outputs = {f"{c.name}.{v.name}" for c in system.components
               for v in c.model_description.modelVariables if v.causality == "output"}
    if set(SONOTRACK.position_columns) <= outputs:
        positions = {"robot_position": SONOTRACK.robot_position,
                     "source_position": SONOTRACK.source_position}
    return SystemDescription(
        name=getattr(scenario, "name", "") or "scenario", base_step=float(scenario.base_step),
        algorithm=plan.algorithm, stop_time=float(scenario.stop_time), seed=int(scenario.seed),
        instances=tuple(instances),
        links=tuple((str(c.start), str(c.end)) for c in system.connections), **positions)


def build_scenario_fmu(scenario, dest_dir, fmu_dir=None, allow_outside=False, portable=False):
    """Build ``TrackingSystem.fmu`` running ``scenario`` (as ``sonotrack run`` would).

    Parameters
    ----------
    scenario : Scenario or path-like
        A loaded scenario or a TOML scenario file.
    dest_dir : path-like
        Folder the FMU is written to.
    fmu_dir : path-like, optional
        Where the system's five FMUs are, if not beside its ``.ssd`` (their model
        descriptions give the ports and the stepping order; the system FMU carries the code).
    allow_outside : bool
        Let the scenario and system files name files outside their folders.
    portable : bool
        Carry a Python runtime in the FMU (``sonotrack build --portable``).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    BuildError
        If an FMU of the system carries other code than ``components/`` holds now: the system
        FMU would not equal ``sonotrack run`` with those FMUs.
    """
    from orchestrator.builder.system_fmu import build_system_fmu, code_mismatches
    from orchestrator.run.plan import plan_run
    from orchestrator.scenario import load_scenario
    from orchestrator.system import load_system

    if not hasattr(scenario, "stop_time"):
        scenario = load_scenario(scenario, allow_outside=allow_outside)
    system = load_system(scenario.system, fmu_dir=fmu_dir, allow_outside=allow_outside)
    description = system_description(plan_run(scenario, system))
    stale = code_mismatches({c.model_description.modelName: (
        FMU_PACKAGES[c.model_description.modelName], c.fmu_path) for c in system.components})
    if stale:
        raise BuildError("the system FMU would run other code than sonotrack run with these "
                         "FMUs; rebuild them (`sonotrack build --system` builds both): "
                         + "; ".join(stale))
    return build_system_fmu(description, Path(dest_dir), portable=portable)
