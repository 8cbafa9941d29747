"""The copy of pythonfmu an FMU carries: only its run-time modules, under a name private to the build.

pythonfmu's builder copies its whole package into ``resources/pythonfmu``: the build-time modules
too (``builder``, ``deploy``, ``csvbuilder``, ``__main__``), and under the public name, so that
in a host whose Python already has a pythonfmu (0.6.5: another ``Fmi2Slave``) the slaves would
run on the host's copy and fail. :func:`carry` moves the run-time modules into the build's private
package as ``<package>._pythonfmu`` (its ``__init__`` without the build-time imports), removes
``resources/pythonfmu`` and points the bundled code's ``from pythonfmu ...`` imports at the private
copy. Which modules are run-time is read from the code: the closure of the relative imports of
pythonfmu's ``__init__`` once the build-time ones are dropped.
"""

import ast
import re
from pathlib import Path

from components.common.errors import BuildError

__all__ = ["BUILD_TIME_MODULES", "PRIVATE_NAME", "runtime_modules", "installed_runtime", "carry"]

BUILD_TIME_MODULES = frozenset({"builder", "csvbuilder", "deploy", "__main__"})
PRIVATE_NAME = "_pythonfmu"
_BUNDLED = "resources/pythonfmu/"
_FROM = re.compile(r"^(\s*)from pythonfmu(?=[\s.])", re.M)
_ANY_IMPORT = re.compile(r"^\s*(from pythonfmu[\s.]|import pythonfmu\b)", re.M)


def _relative_imports(source, name):
    """Module names a module imports relatively (``from .x import y``, ``from . import x``)."""
    try:
        tree = ast.parse(source, filename=name)
    except SyntaxError as exc:
        raise BuildError(f"pythonfmu/{name}: cannot be parsed: {exc}") from None
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            found.update([node.module] if node.module else [a.name for a in node.names])
        elif isinstance(node, ast.Import) or (isinstance(node, ast.ImportFrom) and node.level == 0):
            modules = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module]
            if any(m == "pythonfmu" or m.startswith("pythonfmu.") for m in modules):
                raise BuildError(f"pythonfmu/{name} imports pythonfmu by its public name (line "
                                 f"{node.lineno}); it cannot be carried under a private one")
    return found


def _runtime_init(source):
    """pythonfmu's ``__init__`` without the statements that import build-time modules."""
    lines = source.splitlines(keepends=True)
    for node in reversed(ast.parse(source).body):
        if isinstance(node, ast.ImportFrom) and node.level == 1 and \
                (node.module or "").split(".")[0] in BUILD_TIME_MODULES:
            del lines[node.lineno - 1:node.end_lineno]
    return "".join(lines)


def runtime_modules(files):
    """The run-time part of a pythonfmu package.

    Parameters
    ----------
    files : dict of str to bytes
        pythonfmu's modules by file name (``"__init__.py"``, ``"fmi2slave.py"``, ...).

    Returns
    -------
    dict of str to bytes
        The modules ``__init__`` needs at run time, by file name, ``__init__`` rewritten
        without the build-time imports.

    Raises
    ------
    BuildError
        If a run-time module needs a build-time one or a module that is missing, or imports
        pythonfmu by its public name.
    """
    if "__init__.py" not in files:
        raise BuildError("the carried pythonfmu has no __init__.py")
    out = {"__init__.py": _runtime_init(files["__init__.py"].decode()).encode()}
    pending = ["__init__.py"]
    while pending:
        name = pending.pop()
        for module in sorted(_relative_imports(out[name].decode(), name)):
            file = f"{module.split('.')[0]}.py"
            if module.split(".")[0] in BUILD_TIME_MODULES:
                raise BuildError(f"pythonfmu/{name} needs the build-time module {module} at run "
                                 f"time")
            if file not in files:
                raise BuildError(f"pythonfmu/{name} imports .{module}, which the package lacks")
            if file not in out:
                out[file] = files[file]
                pending.append(file)
    return out


def installed_runtime():
    """The run-time modules of the pythonfmu installed here (what a build will carry)."""
    import pythonfmu

    folder = Path(pythonfmu.__file__).parent
    return runtime_modules({p.name: p.read_bytes() for p in folder.glob("*.py")})


def carry(entries, package, entry):
    """Rewrite an FMU's entries so that its code runs on a private pythonfmu.

    Parameters
    ----------
    entries : dict of str to bytes
        The FMU's files by archive name; changed in place.
    package, entry : str
        The build's private package and the entry module's file stem in ``resources/``.
    """
    bundled = {name[len(_BUNDLED):]: data for name, data in entries.items()
               if name.startswith(_BUNDLED)}
    for name in bundled:
        del entries[_BUNDLED + name]
    flat = {name: data for name, data in bundled.items() if "/" not in name}
    for name, data in runtime_modules(flat).items():
        entries[f"resources/{package}/{PRIVATE_NAME}/{name}"] = data
    private = f"{package}.{PRIVATE_NAME}"
    for name in [n for n in entries if n.endswith(".py") and
                 (n.startswith(f"resources/{package}/") or n == f"resources/{entry}.py")]:
        if f"/{PRIVATE_NAME}/" in name:
            continue
        source = _FROM.sub(rf"\1from {private}", entries[name].decode())
        if _ANY_IMPORT.search(source):
            raise BuildError(f"{name}: imports pythonfmu in a form the build cannot make private "
                             f"(write `from pythonfmu import ...`)")
        entries[name] = source.encode()
    return entries
