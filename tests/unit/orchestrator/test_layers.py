"""The architecture as a test: the import graph of ``orchestrator/`` and ``components/``.

Every module is parsed with :mod:`ast` (never imported) and every ``import`` and ``from ...
import`` in it counts, at any depth: inside functions, ``if``, ``try`` and ``TYPE_CHECKING``
blocks, relative or absolute. An import names the deepest module it reaches:
``from orchestrator.run import runner`` is ``orchestrator.run.runner``, ``from orchestrator.run
import RunResult`` is the package ``orchestrator.run`` (its ``__init__``). The parent packages
Python imports on the way are not counted: every module imports its own package first, and a
package's ``__init__`` may import its modules.

Checked, each with every offender listed at once:

- no import cycle between modules;
- the layers, lower never importing upper (same layer: free);
- ``components/`` never imports ``orchestrator/`` (anyone may import ``components/``);
- no module over :data:`MAX_LINES` lines unless :data:`LONG_MODULES` says why.
"""

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
PACKAGES = ("orchestrator", "components")

#: Bottom to top. A layer is ``components``, the package ``orchestrator`` itself (its
#: ``__init__``), or the subpackage or top-level module ``orchestrator.<name>``.
LAYERS = ("components", "orchestrator", "files", "processes", "report", "ssp", "fmu", "system",
          "scenario", "hosts", "builder", "run", "sweep", "verify", "reproduce", "cli")

MAX_LINES = 500

#: ``path -> why`` for each module allowed past :data:`MAX_LINES`.
LONG_MODULES = {}


def find_modules(root, packages=PACKAGES):
    """``dotted name -> (path, is_package)`` for every ``.py`` file under ``packages``."""
    modules = {}
    for package in packages:
        for path in sorted((Path(root) / package).rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            is_package = parts[-1] == "__init__"
            modules[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return modules


def _deepest_module(name, modules):
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def imports_of(name, modules):
    """The modules of ``modules`` that module ``name`` imports (see the module docstring)."""
    path, is_package = modules[name]
    package = name if is_package else name.rpartition(".")[0]
    targets = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            named = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module
            named = [f"{source}.{alias.name}" if f"{source}.{alias.name}" in modules else source
                     for alias in node.names]
        else:
            continue
        for target in named:
            target = _deepest_module(target, modules)
            if target is not None and target != name:
                targets.add(target)
    return targets


def import_graph(root, packages=PACKAGES):
    """``module -> set of modules it imports``, within ``packages``."""
    modules = find_modules(root, packages)
    return {name: imports_of(name, modules) for name in modules}


def find_cycles(graph):
    """Import cycles, each a list of modules with the first repeated last.

    Per strongly connected component, the shortest cycle through each of its modules, each
    cycle once (starting at its first module in sorted order), so that two cycles sharing a
    module are both shown.
    """
    index, low, stack, on_stack, cycles = {}, {}, [], set(), []

    def connect(node):  # Tarjan; the graph has a few hundred nodes, recursion is fine
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in sorted(graph[node]):
            if target not in index:
                connect(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = set()
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.add(member)
                if member == node:
                    break
            if len(component) > 1:
                for member in sorted(component):
                    cycle = _cycle_through(member, component, graph)[:-1]
                    first = cycle.index(min(cycle))
                    cycle = cycle[first:] + cycle[:first]
                    if cycle + cycle[:1] not in cycles:
                        cycles.append(cycle + cycle[:1])

    for node in sorted(graph):
        if node not in index:
            connect(node)
    return sorted(cycles, key=len)


def _cycle_through(start, component, graph):
    """A shortest import path from ``start`` back to itself inside ``component``."""
    paths, seen = [[start]], {start}
    while paths:
        path = paths.pop(0)
        for target in sorted(graph[path[-1]] & component):
            if target == start:
                return path + [start]
            if target not in seen:
                seen.add(target)
                paths.append(path + [target])
    raise AssertionError(f"no cycle through {start}")  # pragma: no cover


def layer_of(module):
    """``components``, ``orchestrator`` (the package's ``__init__``) or ``orchestrator.<name>``'s
    ``<name>``."""
    parts = module.split(".")
    if parts[0] == "components":
        return "components"
    return parts[1] if len(parts) > 1 else "orchestrator"


def layer_violations(graph, layers=LAYERS):
    """Lines ``a (layer) imports b (higher layer)``, and modules whose layer is not listed."""
    rank = {layer: position for position, layer in enumerate(layers)}
    problems = [f"{module}: layer {layer_of(module)!r} is not in LAYERS; place it there"
                for module in sorted(graph) if layer_of(module) not in rank]
    for module, targets in sorted(graph.items()):
        for target in sorted(targets):
            low, high = layer_of(module), layer_of(target)
            if low in rank and high in rank and rank[high] > rank[low]:
                problems.append(f"{module} ({low}) imports {target} ({high}), a higher layer")
    return problems


def long_modules(root, allowed, packages=PACKAGES, max_lines=MAX_LINES):
    """Modules over ``max_lines`` lines not in ``allowed``, and entries of ``allowed`` that are
    not (or no longer) long."""
    problems = []
    lengths = {path.relative_to(root).as_posix(): len(path.read_text(encoding="utf-8")
                                                        .splitlines())
               for path, _ in find_modules(root, packages).values()}
    for name, lines in sorted(lengths.items()):
        if lines > max_lines and name not in allowed:
            problems.append(f"{name}: {lines} lines (> {max_lines}); split it or say why in "
                            "LONG_MODULES")
    for name in sorted(allowed):
        if lengths.get(name, 0) <= max_lines:
            problems.append(f"{name}: in LONG_MODULES but {lengths.get(name, 'not found')} "
                            "lines; remove the entry")
    return problems


@pytest.fixture(scope="module")
def graph():
    return import_graph(REPO)


def test_no_import_cycle(graph):
    cycles = find_cycles(graph)
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c) for c in cycles)


def test_lower_layers_never_import_upper_ones(graph):
    problems = layer_violations(graph)
    assert not problems, ("layers, bottom to top: " + " < ".join(LAYERS) + "\n"
                          + "\n".join(problems))


def test_components_never_import_the_orchestrator(graph):
    problems = [f"{module} imports {target}" for module, targets in sorted(graph.items())
                if module.startswith("components") for target in sorted(targets)
                if target.startswith("orchestrator")]
    assert not problems, "\n".join(problems)


def test_every_layer_holds_modules(graph):
    assert set(LAYERS) <= {layer_of(module) for module in graph}


def test_no_module_past_the_line_limit_without_a_reason():
    assert all(reason.strip() for reason in LONG_MODULES.values())
    problems = long_modules(REPO, LONG_MODULES)
    assert not problems, "\n".join(problems)


# -- the checks themselves, on a small tree written here --------------------------------------

_TREE = {
    "components/__init__.py": "",
    "components/core.py": "def f():\n    from orchestrator.files import paths\n",
    "orchestrator/__init__.py": "",
    "orchestrator/files/__init__.py": "from .paths import confine\n",
    "orchestrator/files/paths.py": "import os\n\ndef confine():\n    pass\n",
    "orchestrator/run/__init__.py": "from . import runner\nfrom .runner import RUN\n",
    "orchestrator/run/runner.py": ("import components.core\n"
                                   "from ..files import paths\n"
                                   "RUN = 1\n"
                                   "def go():\n"
                                   "    if True:\n"
                                   "        try:\n"
                                   "            from orchestrator.sweep.plan import plan\n"
                                   "        except ImportError:\n"
                                   "            pass\n"),
    "orchestrator/sweep/__init__.py": "",
    "orchestrator/sweep/plan.py": "from orchestrator.run import RUN\n\ndef plan():\n    pass\n",
}


@pytest.fixture
def tree(tmp_path):
    for name, text in _TREE.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text, encoding="utf-8")
    return tmp_path


def test_the_scanner_sees_local_nested_and_relative_imports(tree):
    assert import_graph(tree) == {
        "components": set(),
        "components.core": {"orchestrator.files.paths"},
        "orchestrator": set(),
        "orchestrator.files": {"orchestrator.files.paths"},
        "orchestrator.files.paths": set(),
        "orchestrator.run": {"orchestrator.run.runner"},
        "orchestrator.run.runner": {"components.core", "orchestrator.files.paths",
                                    "orchestrator.sweep.plan"},
        "orchestrator.sweep": set(),
        "orchestrator.sweep.plan": {"orchestrator.run"},
    }


def test_the_checks_name_the_cycle_the_upward_import_and_the_long_module(tree):
    graph = import_graph(tree)
    assert find_cycles(graph) == [["orchestrator.run", "orchestrator.run.runner",
                                   "orchestrator.sweep.plan", "orchestrator.run"]]
    assert layer_violations(graph, ("components", "orchestrator", "files", "run", "sweep")) == [
        "components.core (components) imports orchestrator.files.paths (files), a higher layer",
        "orchestrator.run.runner (run) imports orchestrator.sweep.plan (sweep), a higher layer",
    ]
    assert layer_violations(graph, ("components", "orchestrator", "files", "sweep", "run")) == [
        "components.core (components) imports orchestrator.files.paths (files), a higher layer",
        "orchestrator.sweep.plan (sweep) imports orchestrator.run (run), a higher layer",
    ]
    assert layer_violations(graph, ("components", "orchestrator", "files", "run")) == [
        "orchestrator.sweep: layer 'sweep' is not in LAYERS; place it there",
        "orchestrator.sweep.plan: layer 'sweep' is not in LAYERS; place it there",
        "components.core (components) imports orchestrator.files.paths (files), a higher layer",
    ]
    assert long_modules(tree, {}, max_lines=5) == [
        "orchestrator/run/runner.py: 9 lines (> 5); split it or say why in LONG_MODULES"]
    assert long_modules(tree, {"orchestrator/run/runner.py": "one loop",
                               "orchestrator/files/paths.py": "gone"}, max_lines=5) == [
        "orchestrator/files/paths.py: in LONG_MODULES but 4 lines; remove the entry"]
