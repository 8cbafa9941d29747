"""Where a scenario's files are: its ``.ssd`` and its file-valued parameters.

A relative ``system`` resolves from the scenario file's folder (the current directory for a
scenario given as a dict without ``base_dir``); without ``system``, the ``.ssd`` is
``<scenario folder>/../fmus/SystemStructure.ssd`` or the repository's. File-valued parameters
(``source.path = "waypoints.csv"``) resolve from the scenario's folder and must stay inside it
unless ``allow_outside`` (:mod:`orchestrator.files.paths`).
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["default_system_path", "resolve_system_path", "resolve_file_parameters"]


def default_system_path(base_dir=None):
    """The default ``.ssd``: ``<base_dir>/../fmus/SystemStructure.ssd`` if it exists.

    Without ``base_dir``, or when a scenario lives outside a checkout (no ``../fmus`` beside
    it), the repository's ``fmus/SystemStructure.ssd`` (the ``orchestrator`` package's sibling).
    """
    repository = Path(__file__).resolve().parents[2] / "fmus" / "SystemStructure.ssd"
    if base_dir is None:
        return repository
    beside = (Path(base_dir) / ".." / "fmus" / "SystemStructure.ssd").resolve()
    return beside if beside.is_file() else repository


def resolve_system_path(check, system, given, base_dir):
    """The absolute path of a scenario's ``.ssd``, or None if there is no usable one.

    Parameters
    ----------
    check : orchestrator.scenario.schema.FieldChecker
        Receives the problem when the path is not an existing file.
    system : str or None
        The checked ``system`` field (None when absent or of the wrong type).
    given : bool
        Whether the scenario has a ``system`` field at all (absent means the default).
    base_dir : str or pathlib.Path or None
        Folder a relative path resolves from (None: the current directory).
    """
    if system is None and not given:
        system_path = default_system_path(base_dir)
    elif system is not None:
        system_path = Path(system)
        if not system_path.is_absolute():
            system_path = (Path(base_dir) if base_dir is not None else Path.cwd()) / system_path
        system_path = system_path.resolve()
    else:
        return None   # the field's type problem is already reported
    if not system_path.is_file():
        what = "is a directory" if system_path.is_dir() else "does not exist"
        check.add("system", f"{str(system_path)!r} {what} (a path to an .ssd file)")
        return None
    return system_path


def resolve_file_parameters(check, parameters, base_dir, allow_outside):
    """File-valued parameters as absolute paths, resolved from the scenario's folder."""
    from orchestrator.files.paths import confine, names_a_file

    resolved = dict(parameters)
    for key, value in parameters.items():
        if names_a_file(value):
            path, problem = confine(value, base_dir, allow_outside)
            if problem is not None:
                check.add(f"parameters.{key}", problem)
            else:
                resolved[key] = str(path)
    return resolved

