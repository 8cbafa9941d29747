"""A run's parameter values per instance: ``.ssd`` bindings, scenario overrides, faults, seed.

:func:`instance_parameters` is where they are merged, for a run (:mod:`~orchestrator.run.plan`)
and for a sweep that checks its runs before any starts (:mod:`orchestrator.sweep.plan`). Later
sources win: the ``.ssd`` bindings (an ``.ssv`` file's values included), then the scenario's
``parameters``, then each fault target's schedule; every instance with a ``seed`` parameter
gets the scenario's seed unless the scenario sets that instance's seed itself.
"""

from components.common.errors import ConfigError

__all__ = ["instance_parameters"]


def instance_parameters(system, scenario):
    """Merge ``.ssd`` bindings, scenario overrides, fault schedules and the seed per instance.

    Parameters
    ----------
    system : orchestrator.system.System
        The scenario's system.
    scenario : orchestrator.scenario.Scenario
        The scenario (its ``parameters``, ``faults`` and ``seed``).

    Returns
    -------
    dict of str to dict
        ``{instance: {parameter: value}}``, with an entry for every instance.

    Raises
    ------
    ConfigError
        Listing every override that names an unknown instance or parameter.
    """
    per_instance = {c.name: {} for c in system.components}
    for key, value in system.parameter_values.items():
        instance, name = key.split(".", 1)
        # a waypoint CSV bound in the .ssd or an .ssv resolves from that file's folder
        per_instance[instance][name] = value.run_value() if hasattr(value, "run_value") else value
    problems = []
    for key, value in scenario.parameters.items():
        instance, dot, name = key.partition(".")
        if instance not in per_instance:
            problems.append(f"parameters.{key}: no instance {instance!r}; instances are "
                            f"{', '.join(per_instance)}")
            continue
        component = system.component(instance)
        parameters = [v.name for v in component.model_description.modelVariables
                      if v.causality == "parameter"]
        if name not in parameters:
            problems.append(f"parameters.{key}: {instance} has no parameter {name!r}; "
                            f"valid: {', '.join(parameters)}")
            continue
        per_instance[instance][name] = value
    where = getattr(scenario, "source", None) or getattr(scenario, "path", "scenario")
    if problems:
        raise ConfigError(f"{where}: " + "; ".join(problems))
    faults = getattr(scenario, "faults", ())
    if faults:
        from orchestrator.scenario.faults import SCHEDULE_PARAMETER, fault_parameters

        for instance, text in fault_parameters(system, faults, where).items():
            if f"{instance}.{SCHEDULE_PARAMETER}" in scenario.parameters:
                raise ConfigError(f"{where}: parameters.{instance}.{SCHEDULE_PARAMETER} and "
                                  f"[[faults]] both set {instance}'s schedule; keep one")
            per_instance[instance][SCHEDULE_PARAMETER] = text
    for component in system.components:
        names = {v.name for v in component.model_description.modelVariables
                 if v.causality == "parameter"}
        if "seed" in names and f"{component.name}.seed" not in scenario.parameters:
            per_instance[component.name]["seed"] = int(scenario.seed)
    return per_instance
