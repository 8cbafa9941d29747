"""A co-simulation system: an ``.ssd`` checked against its FMUs, ready for a master.

:func:`check_system` compares a :class:`~orchestrator.ssp.SystemDescription` with the model
descriptions of its FMUs and returns *every* problem it finds (unknown components and ports,
type and unit mismatches, miswired or unconnected inputs, bad parameter bindings, algebraic
loops). :func:`load_system` reads the files, runs the checks and either raises one
:class:`SystemDescriptionError` listing all problems or returns a :class:`System` whose
connections are resolved to value references, so that the master never looks a name up again.

The stepping order for Gauss-Seidel is documented in ``docs/system.md`` and
:func:`gauss_seidel_order`.
"""

from __future__ import annotations

import difflib
import heapq
from dataclasses import dataclass, field
from pathlib import Path

from components.common.errors import ConfigError

from .ssp import ParameterValue, SystemDescription, read_ssd

__all__ = [
    "SystemDescriptionError",
    "Variable",
    "ResolvedConnection",
    "SystemComponent",
    "System",
    "variable_unit",
    "direct_dependencies",
    "algebraic_loops",
    "gauss_seidel_order",
    "check_system",
    "load_system",
]

# Which FMI 2.0 causality each SSP connector kind must match.
_KIND_TO_CAUSALITY = {
    "input": "input",
    "output": "output",
    "parameter": "parameter",
    "calculatedParameter": "calculatedParameter",
}
# Variables an ssv:Parameter may set: libcosim accepts parameters and inputs (start values).
_SETTABLE_CAUSALITIES = ("parameter", "input")
_MAX_LOOPS = 20


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


@dataclass(frozen=True)
class Variable:
    """One FMU variable of one component instance, resolved once before t0.

    Attributes
    ----------
    component : str
        Instance name.
    name : str
        Variable name in the FMU.
    value_reference : int
        FMI value reference.
    type : str
        ``"Real"``, ``"Integer"``, ``"Boolean"``, ``"String"`` or ``"Enumeration"``.
    causality : str
        FMI causality (``"input"``, ``"output"``, ``"parameter"``, ...).
    unit : str or None
        The variable's unit (its own or its declared type's).
    """

    component: str
    name: str
    value_reference: int
    type: str
    causality: str
    unit: str | None

    def __str__(self):
        return f"{self.component}.{self.name}"


@dataclass(frozen=True)
class ResolvedConnection:
    """A connection whose two ends are resolved to FMU variables."""

    start: Variable
    end: Variable

    def __str__(self):
        return f"{self.start} -> {self.end}"


@dataclass
class SystemComponent:
    """A component instance with its FMU.

    Attributes
    ----------
    name : str
        Instance name.
    fmu_path : pathlib.Path
        The ``.fmu`` file (shared by instances of the same FMU).
    model_description : fmpy.model_description.ModelDescription
        Its model description, read once.
    parameters : dict of str to ParameterValue
        Values bound in the ``.ssd``, by variable name.
    step_size_hint : float or None
        The ``.ssd``'s suggested communication step, in s.
    """

    name: str
    fmu_path: Path
    model_description: object
    parameters: dict[str, ParameterValue] = field(default_factory=dict)
    step_size_hint: float | None = None

    def variable(self, name):
        """Return the :class:`Variable` called ``name``; raise ConfigError naming the choices."""
        for v in self.model_description.modelVariables:
            if v.name == name:
                return _resolve(self.name, v)
        names = [v.name for v in self.model_description.modelVariables]
        raise ConfigError(f"{self.name}.{name}: no such variable in {self.fmu_path.name}"
                          f"{_suggest(name, names)}; variables are: {', '.join(names)}")


@dataclass
class System:
    """A checked system, ready to instantiate.

    Attributes
    ----------
    description : SystemDescription
        What the ``.ssd`` says.
    components : list of SystemComponent
        In ``.ssd`` order.
    connections : list of ResolvedConnection
        In ``.ssd`` order, each from an output to an input.
    """

    description: SystemDescription
    components: list[SystemComponent]
    connections: list[ResolvedConnection]

    def component(self, name):
        """Return the component called ``name``; raise ConfigError naming the choices."""
        for component in self.components:
            if component.name == name:
                return component
        names = [c.name for c in self.components]
        raise ConfigError(f"{self.description.path}: no component '{name}'"
                          f"{_suggest(name, names)}; components are: {', '.join(names)}")

    def variable(self, qualified_name):
        """Return the variable ``"instance.port"``; raise ConfigError naming the choices."""
        instance, dot, port = qualified_name.partition(".")
        if not dot or not port:
            raise ConfigError(f"{qualified_name!r} is not of the form 'instance.port'")
        return self.component(instance).variable(port)

    @property
    def parameter_values(self):
        """All bound parameter values, keyed ``"instance.parameter"``."""
        return {f"{c.name}.{name}": value
                for c in self.components for name, value in c.parameters.items()}

    def stepping_order(self):
        """Component names in Gauss-Seidel stepping order (see :func:`gauss_seidel_order`)."""
        model_descriptions = {c.name: c.model_description for c in self.components}
        return gauss_seidel_order(self.description, model_descriptions)


# ----- model-description helpers ---------------------------------------------------------------

def variable_unit(variable):
    """Return the unit of an fmpy variable: its own, else its declared type's, else None."""
    if variable.unit is not None:
        return variable.unit
    declared = getattr(variable, "declaredType", None)
    return getattr(declared, "unit", None) if declared is not None else None


def _resolve(component, variable):
    return Variable(component, variable.name, variable.valueReference, variable.type,
                    variable.causality, variable_unit(variable))


def direct_dependencies(model_description):
    """Map each output name to the set of input names it depends on directly.

    An output listed in ``ModelStructure/Outputs`` without a ``dependencies`` attribute, or not
    listed at all, depends on every input (FMI 2.0, section 2.2.8): the conservative reading.
    """
    inputs = {v.name for v in model_description.modelVariables if v.causality == "input"}
    listed = {}
    for unknown in model_description.outputs:
        if unknown.variable is None:
            continue
        if unknown.dependencies is None:
            listed[unknown.variable.name] = set(inputs)
        else:
            listed[unknown.variable.name] = {d.name for d in unknown.dependencies
                                             if d.name in inputs}
    return {v.name: listed.get(v.name, set(inputs))
            for v in model_description.modelVariables if v.causality == "output"}


def _unit_text(unit):
    return "no unit" if unit is None else f"unit '{unit}'"


def _suggest(name, choices):
    close = difflib.get_close_matches(name, choices, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def _by_causality(model_description, causality):
    return [v.name for v in model_description.modelVariables if v.causality == causality]


# ----- graphs ------------------------------------------------------------------------------------

def _valid_connections(description, model_descriptions):
    """Connections whose ends exist and run output -> input, as (start, end) fmpy variables."""
    valid = []
    for connection in description.connections:
        start_md = model_descriptions.get(connection.start_element)
        end_md = model_descriptions.get(connection.end_element)
        if start_md is None or end_md is None:
            continue
        start = _find(start_md, connection.start_connector)
        end = _find(end_md, connection.end_connector)
        if start is None or end is None:
            continue
        if start.causality == "output" and end.causality == "input":
            valid.append((connection, start, end))
    return valid


def _find(model_description, name):
    for variable in model_description.modelVariables:
        if variable.name == name:
            return variable
    return None


def _strongly_connected(nodes, edges):
    """Tarjan's algorithm; returns the components as lists (iterative to avoid recursion)."""
    index, low, on_stack, stack, result = {}, {}, set(), [], []
    counter = 0
    for root in nodes:
        if root in index:
            continue
        work = [(root, iter(edges.get(root, ())))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, successors = work[-1]
            advanced = False
            for successor in successors:
                if successor not in index:
                    index[successor] = low[successor] = counter
                    counter += 1
                    stack.append(successor)
                    on_stack.add(successor)
                    work.append((successor, iter(edges.get(successor, ()))))
                    advanced = True
                    break
                if successor in on_stack:
                    low[node] = min(low[node], index[successor])
            if advanced:
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                result.append(component)
    return result


def _elementary_cycles(nodes, edges, limit):
    """Every elementary cycle, each found once from its smallest node, at most ``limit``."""
    cycles = []
    for component in _strongly_connected(nodes, edges):
        if len(component) < 2:
            continue
        members = set(component)
        for start in sorted(component):
            allowed = {n for n in members if n >= start}
            path, on_path = [start], {start}
            work = [iter(sorted(s for s in edges.get(start, ()) if s in allowed))]
            while work and len(cycles) < limit:
                successor = next(work[-1], None)
                if successor is None:
                    work.pop()
                    on_path.discard(path.pop())
                    continue
                if successor == start:
                    cycles.append(list(path))
                elif successor not in on_path:
                    path.append(successor)
                    on_path.add(successor)
                    work.append(iter(sorted(s for s in edges.get(successor, ())
                                            if s in allowed)))
    return cycles


def algebraic_loops(description, model_descriptions, limit=_MAX_LOOPS):
    """Return the algebraic loops of a system as lists of ``"instance.port"`` names.

    The graph has an edge from each connected output to the input it drives, and from each
    input to every output of the same FMU that depends on it directly (ModelStructure
    ``dependencies``). Each elementary cycle of that graph is an algebraic loop; it is returned
    starting at its first output in ``.ssd`` component order and variable order.

    Parameters
    ----------
    description : SystemDescription
        The system.
    model_descriptions : dict of str to ModelDescription
        Model description per component instance; components without one are skipped.
    limit : int
        Stop after this many loops.

    Returns
    -------
    list of list of str
        One list per loop, without repeating the first element at the end.
    """
    order = {c.name: i for i, c in enumerate(description.components)}
    keys, names, causality = {}, {}, {}
    for component in description.components:
        md = model_descriptions.get(component.name)
        if md is None:
            continue
        for position, variable in enumerate(md.modelVariables):
            if variable.causality in ("input", "output"):
                key = (order[component.name], position)
                keys[(component.name, variable.name)] = key
                names[key] = f"{component.name}.{variable.name}"
                causality[key] = variable.causality
    edges = {}
    for connection, start, end in _valid_connections(description, model_descriptions):
        source = keys[(connection.start_element, start.name)]
        target = keys[(connection.end_element, end.name)]
        edges.setdefault(source, set()).add(target)
    for component in description.components:
        md = model_descriptions.get(component.name)
        if md is None:
            continue
        for output, inputs in direct_dependencies(md).items():
            for input_name in inputs:
                edges.setdefault(keys[(component.name, input_name)], set()).add(
                    keys[(component.name, output)])
    loops = []
    for cycle in _elementary_cycles(sorted(keys.values()), edges, limit):
        outputs = [i for i, key in enumerate(cycle) if causality[key] == "output"]
        first = min(outputs, key=lambda i: cycle[i]) if outputs else 0
        loops.append(cycle[first:] + cycle[:first])
    loops.sort()
    return [[names[key] for key in loop] for loop in loops]


def gauss_seidel_order(description, model_descriptions):
    """Return the component names in Gauss-Seidel stepping order.

    Rule: component A must step before component B when a connection runs from an output of A
    to an input of B *and* some output of B depends directly on that input. Connections into an
    input without direct feedthrough impose no order: B's outputs after its step do not depend
    on the value it receives, so such edges break loops. The remaining component graph is
    sorted topologically, ties (and any leftover cycle) broken by ``.ssd`` order.

    Parameters
    ----------
    description : SystemDescription
        The system.
    model_descriptions : dict of str to ModelDescription
        Model description per component instance.

    Returns
    -------
    list of str
        Every component name exactly once.
    """
    names = [c.name for c in description.components]
    order = {name: i for i, name in enumerate(names)}
    feeds = {name: set().union(*direct_dependencies(md).values())
             for name, md in model_descriptions.items()}
    predecessors = {name: set() for name in names}
    for connection, start, end in _valid_connections(description, model_descriptions):
        a, b = connection.start_element, connection.end_element
        if a != b and end.name in feeds.get(b, set()):
            predecessors[b].add(a)
    successors = {name: set() for name in names}
    for b, sources in predecessors.items():
        for a in sources:
            successors[a].add(b)
    waiting = {name: len(predecessors[name]) for name in names}
    ready = [order[name] for name in names if waiting[name] == 0]
    heapq.heapify(ready)
    result, done = [], set()
    while len(result) < len(names):
        if not ready:
            # A cycle among feedthrough components: step the earliest one with old inputs.
            ready = [min(order[n] for n in names if n not in done)]
        position = heapq.heappop(ready)
        name = names[position]
        if name in done:
            continue
        result.append(name)
        done.add(name)
        for successor in successors[name]:
            waiting[successor] -= 1
            if waiting[successor] == 0 and successor not in done:
                heapq.heappush(ready, order[successor])
    return result


# ----- checks ------------------------------------------------------------------------------------

def _check_connectors(component, md, problems, unknown_ports):
    variables = {v.name: v for v in md.modelVariables}
    for connector in component.connectors:
        port = f"{component.name}.{connector.name}"
        variable = variables.get(connector.name)
        if variable is None:
            wanted = _KIND_TO_CAUSALITY.get(connector.kind, connector.kind)
            choices = _by_causality(md, wanted)
            problems.append(f"{port}: unknown port, {md.modelName} has no variable "
                            f"'{connector.name}'{_suggest(connector.name, choices)}; its "
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
                            f"{_unit_text(variable_unit(variable))}")


def _check_parameters(component, md, problems):
    variables = {v.name: v for v in md.modelVariables}
    for name, value in component.parameters.items():
        port = f"{component.name}.{name}"
        variable = variables.get(name)
        if variable is None:
            choices = _by_causality(md, "parameter")
            problems.append(f"{port}: parameter binding names no variable of {md.modelName}"
                            f"{_suggest(name, choices)}; its parameters are: "
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
                        f"{_suggest(element, names)}; components are: {', '.join(names)}")
        return None
    if component.connector(connector) is None:
        problems.append(f"connection {connection}: {element}.{connector} is not declared in "
                        f"the <ssd:Connectors> of '{element}' (libcosim needs every connected "
                        f"port declared)")
    md = model_descriptions.get(element)
    if md is None:
        return None
    variable = _find(md, connector)
    if variable is None:
        if (element, connector) not in unknown_ports:
            ports = _by_causality(md, "input") + _by_causality(md, "output")
            problems.append(f"connection {connection}: unknown port {element}.{connector}"
                            f"{_suggest(connector, ports)}; ports of {md.modelName} are: "
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
                            f"{_unit_text(variable_unit(start))} and {end_name} has "
                            f"{_unit_text(variable_unit(end))}")
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
        for name in _by_causality(md, "input"):
            inputs.add(f"{component.name}.{name}")
            if (component.name, name) not in drivers and \
                    f"{component.name}.{name}" not in allow_unconnected:
                problems.append(f"{component.name}.{name}: input is not connected (connect it "
                                f"or list it in allow_unconnected)")
    for entry in sorted(allow_unconnected):
        instance = entry.partition(".")[0]
        if entry not in inputs and instance in model_descriptions:
            problems.append(f"allow_unconnected: '{entry}' is not an input of the system"
                            f"{_suggest(entry, sorted(inputs))}")


def _check(description, model_descriptions, allow_unconnected, unavailable):
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
    loops = algebraic_loops(description, model_descriptions, limit=_MAX_LOOPS + 1)
    for loop in loops[:_MAX_LOOPS]:
        problems.append("algebraic loop: " + " -> ".join(loop + loop[:1]))
    if len(loops) > _MAX_LOOPS:
        problems.append(f"more than {_MAX_LOOPS} algebraic loops; only the first {_MAX_LOOPS} "
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
    return _check(description, model_descriptions, allow_unconnected, {})


def load_system(ssd_path, fmu_dir=None, allow_unconnected=(), allow_outside=False):
    """Read an ``.ssd`` and its FMUs' model descriptions, check them and resolve the system.

    Parameters
    ----------
    ssd_path : str or pathlib.Path
        The ``SystemStructure.ssd`` file.
    fmu_dir : str or pathlib.Path, optional
        Directory against which component sources resolve; default: the ``.ssd``'s directory
        (as libcosim does).
    allow_unconnected : iterable of str
        ``"instance.port"`` inputs that may stay unconnected.
    allow_outside : bool
        Accept parameter files and waypoint CSVs outside their file's folder (see
        :func:`orchestrator.ssp.read_ssd`).

    Returns
    -------
    System
        Components with their FMU paths and model descriptions, connections resolved to value
        references, and bound parameter values.

    Raises
    ------
    ConfigError
        If the ``.ssd`` cannot be parsed.
    SystemDescriptionError
        Listing every problem :func:`check_system` finds, plus FMUs that are missing or cannot
        be read.
    """
    from fmpy import read_model_description

    description = read_ssd(ssd_path, allow_outside=allow_outside)
    base = Path(fmu_dir) if fmu_dir is not None else description.directory
    model_descriptions, unavailable, fmu_paths, cache = {}, {}, {}, {}
    for component in description.components:
        fmu_path = (base / component.source).resolve()
        fmu_paths[component.name] = fmu_path
        if fmu_path not in cache:
            if not fmu_path.is_file():
                cache[fmu_path] = f"not found at {fmu_path}"
            else:
                try:
                    cache[fmu_path] = read_model_description(str(fmu_path))
                except Exception as error:  # fmpy raises bare Exceptions for invalid XML
                    cache[fmu_path] = f"cannot be read ({fmu_path}: {error})"
        entry = cache[fmu_path]
        if isinstance(entry, str):
            unavailable[component.name] = entry
        else:
            model_descriptions[component.name] = entry
    problems = _check(description, model_descriptions, allow_unconnected, unavailable)
    if problems:
        raise SystemDescriptionError(problems, description.path)
    components = [SystemComponent(c.name, fmu_paths[c.name], model_descriptions[c.name],
                                  dict(c.parameters), c.step_size_hint)
                  for c in description.components]
    connections = [ResolvedConnection(_resolve(connection.start_element, start),
                                      _resolve(connection.end_element, end))
                   for connection, start, end in
                   _valid_connections(description, model_descriptions)]
    return System(description, components, connections)
