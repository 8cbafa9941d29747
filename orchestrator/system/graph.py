"""The dependency graph of a system: direct feedthrough, algebraic loops, stepping order.

Built from the ``.ssd``'s connections and each FMU's ``ModelStructure`` (which outputs depend
directly on which inputs). :func:`algebraic_loops` lists the cycles a master cannot step
through; :func:`gauss_seidel_order` is the order producers-first stepping uses (documented in
``docs/system.md``).
"""

from __future__ import annotations

import heapq

from .variables import find_variable

__all__ = ["MAX_LOOPS", "direct_dependencies", "valid_connections", "algebraic_loops",
           "gauss_seidel_order"]

MAX_LOOPS = 20


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


def valid_connections(description, model_descriptions):
    """Connections whose ends exist and run output -> input, as (start, end) fmpy variables."""
    valid = []
    for connection in description.connections:
        start_md = model_descriptions.get(connection.start_element)
        end_md = model_descriptions.get(connection.end_element)
        if start_md is None or end_md is None:
            continue
        start = find_variable(start_md, connection.start_connector)
        end = find_variable(end_md, connection.end_connector)
        if start is None or end is None:
            continue
        if start.causality == "output" and end.causality == "input":
            valid.append((connection, start, end))
    return valid


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


def algebraic_loops(description, model_descriptions, limit=MAX_LOOPS):
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
    for connection, start, end in valid_connections(description, model_descriptions):
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
    for connection, start, end in valid_connections(description, model_descriptions):
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
