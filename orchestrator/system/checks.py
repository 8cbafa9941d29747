"""Checks of a system description against its FMUs' model descriptions: every problem at once.

:func:`check_system` returns one message per problem (unknown components and ports, type and
unit mismatches, miswired or unconnected inputs, bad parameter bindings, algebraic loops);
:class:`SystemDescriptionError` carries them all.
"""

from __future__ import annotations

from components.common.errors import ConfigError

from .graph import MAX_LOOPS, algebraic_loops
from .variables import (find_variable, names_by_causality, suggest, unit_text,
                        variable_unit)

__all__ = ["SystemDescriptionError", "check_system", "find_problems"]

# Which FMI 2.0 causality each SSP connector kind must match.
_KIND_TO_CAUSALITY = {
    "input": "input",
    "output": "output",
    "parameter": "parameter",
    "calculatedParameter": "calculatedParameter",
}
# Variables an ssv:Parameter may set: libcosim accepts parameters and inputs (start values).
_SETTABLE_CAUSALITIES = ("parameter", "input")


class SystemDescriptionError(ConfigError):
    """A system description does not fit its FMUs; ``problems`` lists every finding.

    Parameters
    ----------
    problems : list of str
        One message per problem, each naming the component, port or connection.
    path : str or pathlib.Path, optional
        The ``.ssd`` file the problems were found in.
    """

    def __init__(self, problems, path=None):
        self.problems = list(problems)
        self.path = path
        count = len(self.problems)
        where = f"{path}: " if path is not None else ""
        noun = "problem" if count == 1 else "problems"
        lines = "\n".join(f"  {i}. {p}" for i, p in enumerate(self.problems, start=1))
        if count == 1:  # one problem, one line
            super().__init__(f"{where}{self.problems[0]}")
        else:
            super().__init__(f"{where}{count} {noun} in the system:\n{lines}")


def _check_connectors(component, md, problems, unknown_ports):
    variables = {v.name: v for v in md.modelVariables}
    for connector in component.connectors:
        port = f"{component.name}.{connector.name}"
        variable = variables.get(connector.name)
        if variable is None:
            wanted = _KIND_TO_CAUSALITY.get(connector.kind, connector.kind)
            choices = names_by_causality(md, wanted)
            problems.append(f"{port}: unknown port, {md.modelName} has no variable "
                            f"'{connector.name}'{suggest(connector.name, choices)}; its "
                            f"{wanted}s are: {', '.join(choices) or '(none)'}")
            unknown_ports.add((component.name, connector.name))
            continue
        causality = _KIND_TO_CAUSALITY.get(connector.kind)
        if causality != variable.causality:
            problems.append(f"{port}: connector kind '{connector.kind}' but the FMU variable's "
                            f"causality is '{variable.causality}'")
        if connector.type != variable.type:
            problems.append(f"{port}: connector type {connector.type} but the FMU variable is "
                            f"{variable.type}")
        elif connector.unit is not None and connector.unit != variable_unit(variable):
            problems.append(f"{port}: connector unit '{connector.unit}' but the FMU variable has "
                            f"{unit_text(variable_unit(variable))}")


def _check_parameters(component, md, problems):
    variables = {v.name: v for v in md.modelVariables}
    for name, value in component.parameters.items():
        port = f"{component.name}.{name}"
        variable = variables.get(name)
        if variable is None:
            choices = names_by_causality(md, "parameter")
            problems.append(f"{port}: parameter binding names no variable of {md.modelName}"
                            f"{suggest(name, choices)}; its parameters are: "
                            f"{', '.join(choices) or '(none)'}")
            continue
        if variable.causality not in _SETTABLE_CAUSALITIES:
            problems.append(f"{port}: bound as a parameter but its causality is "
                            f"'{variable.causality}'; only {' or '.join(_SETTABLE_CAUSALITIES)} "
                            f"variables can be set")
        if variable.type != value.type:
            problems.append(f"{port}: parameter value is ssv:{value.type} {value.value!r} but the "
                            f"FMU variable is {variable.type}")


def _check_endpoint(connection, element, connector, description, model_descriptions,
                    problems, unknown_ports):
    """Return the fmpy variable of one connection end, or None after recording a problem."""
    component = description.component(element)
    if component is None:
        names = [c.name for c in description.components]
        problems.append(f"connection {connection}: unknown component '{element}'"
                        f"{suggest(element, names)}; components are: {', '.join(names)}")
        return None
    if component.connector(connector) is None:
        problems.append(f"connection {connection}: {element}.{connector} is not declared in "
                        f"the <ssd:Connectors> of '{element}' (libcosim needs every connected "
                        f"port declared)")
    md = model_descriptions.get(element)
    if md is None:
        return None
    variable = find_variable(md, connector)
    if variable is None:
        if (element, connector) not in unknown_ports:
            ports = names_by_causality(md, "input") + names_by_causality(md, "output")
            problems.append(f"connection {connection}: unknown port {element}.{connector}"
                            f"{suggest(connector, ports)}; ports of {md.modelName} are: "
                            f"{', '.join(ports)}")
            unknown_ports.add((element, connector))
    return variable


def _check_connections(description, model_descriptions, problems, unknown_ports):
    drivers = {}
    for connection in description.connections:
        start = _check_endpoint(connection, connection.start_element, connection.start_connector,
                                description, model_descriptions, problems, unknown_ports)
        end = _check_endpoint(connection, connection.end_element, connection.end_connector,
                              description, model_descriptions, problems, unknown_ports)
        if end is not None:
            drivers.setdefault((connection.end_element, connection.end_connector), []).append(
                connection)
        if start is None or end is None:
            continue
        start_name = f"{connection.start_element}.{connection.start_connector}"
        end_name = f"{connection.end_element}.{connection.end_connector}"
        if start.causality != "output":
            problems.append(f"connection {connection}: start {start_name} is an "
                            f"{start.causality}, not an output; a connection runs from an "
                            f"output to an input")
        if end.causality != "input":
            problems.append(f"connection {connection}: end {end_name} is an {end.causality}, "
                            f"not an input; a connection runs from an output to an input")
        if start.type != end.type:
            problems.append(f"connection {connection}: type mismatch, {start_name} is "
                            f"{start.type} and {end_name} is {end.type}")
        elif start.type == "Real" and variable_unit(start) != variable_unit(end):
            problems.append(f"connection {connection}: unit mismatch, {start_name} has "
                            f"{unit_text(variable_unit(start))} and {end_name} has "
                            f"{unit_text(variable_unit(end))}")
    for (element, connector), connections in drivers.items():
        if len(connections) > 1:
            listed = ", ".join(str(c) for c in connections)
            problems.append(f"{element}.{connector}: input driven by {len(connections)} "
                            f"connections: {listed}")
    return drivers


def _check_unconnected(description, model_descriptions, drivers, allow_unconnected, problems):
    inputs = set()
    for component in description.components:
        md = model_descriptions.get(component.name)
        if md is None:
            continue
        for name in names_by_causality(md, "input"):
            inputs.add(f"{component.name}.{name}")
            if (component.name, name) not in drivers and \
                    f"{component.name}.{name}" not in allow_unconnected:
                problems.append(f"{component.name}.{name}: input is not connected (connect it "
                                f"or list it in allow_unconnected)")
    for entry in sorted(allow_unconnected):
        instance = entry.partition(".")[0]
        if entry not in inputs and instance in model_descriptions:
            problems.append(f"allow_unconnected: '{entry}' is not an input of the system"
                            f"{suggest(entry, sorted(inputs))}")


def find_problems(description, model_descriptions, allow_unconnected, unavailable):
    """:func:`check_system` with ``unavailable``: instance name -> why its FMU has no model
    description (not found, unreadable), reported as that component's problem."""
    problems = []
    unknown_ports = set()
    for component in description.components:
        md = model_descriptions.get(component.name)
        if md is None:
            reason = unavailable.get(component.name, "no model description given")
            problems.append(f"component '{component.name}': unknown component, FMU "
                            f"'{component.source}' {reason}")
            continue
        if md.coSimulation is None:
            problems.append(f"component '{component.name}': {component.source} does not "
                            f"support co-simulation")
        _check_connectors(component, md, problems, unknown_ports)
        _check_parameters(component, md, problems)
    drivers = _check_connections(description, model_descriptions, problems, unknown_ports)
    _check_unconnected(description, model_descriptions, drivers, set(allow_unconnected),
                       problems)
    loops = algebraic_loops(description, model_descriptions, limit=MAX_LOOPS + 1)
    for loop in loops[:MAX_LOOPS]:
        problems.append("algebraic loop: " + " -> ".join(loop + loop[:1]))
    if len(loops) > MAX_LOOPS:
        problems.append(f"more than {MAX_LOOPS} algebraic loops; only the first {MAX_LOOPS} "
                        f"are listed (declare outputs' direct dependencies in ModelStructure)")
    return problems


def check_system(description, model_descriptions, allow_unconnected=()):
    """Return every problem of a system description against its FMUs' model descriptions.

    Parameters
    ----------
    description : SystemDescription
        The parsed ``.ssd``.
    model_descriptions : dict of str to fmpy.model_description.ModelDescription
        Model description per component *instance* name; a missing entry is an unknown
        component.
    allow_unconnected : iterable of str
        ``"instance.port"`` inputs that may stay unconnected (they keep their start value).

    Returns
    -------
    list of str
        One message per problem, empty if the system is sound. Detected: unknown components,
        unknown ports, connector kind/type/unit different from the FMU variable, connections
        not from an output to an input, type or unit mismatch between connected ports, inputs
        driven twice, unconnected inputs, parameter bindings to unknown, unsettable or
        differently typed variables, and algebraic loops (each cycle printed).

    Examples
    --------
    >>> problems = check_system(read_ssd("fmus/SystemStructure.ssd"), {})   # doctest: +SKIP
    >>> problems[0]                                                          # doctest: +SKIP
    "component 'source': unknown component, FMU 'SoundSource.fmu' no model description given"
    """
    return find_problems(description, model_descriptions, allow_unconnected, {})
