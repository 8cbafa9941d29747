"""Stand-ins for a loaded system and scenario, for unit tests of the run layer without FMUs.

:func:`fake_system` has the shape of :class:`orchestrator.system.System` that planning a run
reads (components with their model variables, bound parameter values, look-ups that raise
``ConfigError`` naming the choices, a stepping order); :func:`fake_scenario` that of a loaded
:class:`orchestrator.scenario.Scenario`. Shared by tests/unit/orchestrator/run/test_plan.py
and test_parameters.py.
"""

from types import SimpleNamespace

from components.common.errors import ConfigError

__all__ = ["fake_scenario", "fake_system"]


def fake_system(instances, bindings=None, order=None):
    """A system of ``instances``: ``{name: [(port, causality, type, start), ...]}``.

    Parameters
    ----------
    instances : dict of str to list of tuple
        Ports per instance, in declaration order.
    bindings : dict of str to object, optional
        Bound parameter values, keyed ``"instance.parameter"`` (the ``.ssd``'s).
    order : list of str, optional
        The stepping order (default: the instances' order).
    """
    components = [
        SimpleNamespace(name=name, model_description=SimpleNamespace(modelVariables=[
            SimpleNamespace(name=port, causality=causality, type=type_name, start=start)
            for port, causality, type_name, start in ports]))
        for name, ports in instances.items()]
    by_name = {c.name: c for c in components}

    def component(name):
        if name not in by_name:
            raise ConfigError(f"no component {name!r}; components: {', '.join(by_name)}")
        return by_name[name]

    def variable(qualified_name):
        instance, _, port = qualified_name.partition(".")
        for v in component(instance).model_description.modelVariables:
            if v.name == port:
                return v
        raise ConfigError(f"{qualified_name}: no such variable")

    return SimpleNamespace(components=components, parameter_values=dict(bindings or {}),
                           component=component, variable=variable,
                           stepping_order=lambda: list(order or by_name))


def fake_scenario(**fields):
    """A scenario with the defaults of a small run; ``fields`` replace them."""
    values = dict(stop_time=1.0, base_step=0.01, steps={}, parameters={}, outputs=[],
                  master="gauss-seidel", seed=7, faults=(), source="s.toml")
    values.update(fields)
    values["step_count"] = round(values["stop_time"] / values["base_step"])
    return SimpleNamespace(**values)
