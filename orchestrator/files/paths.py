"""Paths named inside scenario and system files: relative to that file, and kept in its folder.

A scenario's ``source.path = "waypoints.csv"`` means the CSV beside the scenario, whichever
folder the command runs from; a waypoint CSV bound in an ``.ssd`` or ``.ssv`` is beside that
file; an ``.ssv`` named by a parameter binding is beside the ``.ssd``. A file that names a
path outside its own folder (``../../etc/passwd``, an absolute path elsewhere, or a symbolic
link leading out) is refused unless the user asks for it with ``--allow-outside``
(``allow_outside=True`` in the library calls): a scenario or system file received from
someone else cannot read arbitrary files by itself.

Which parameter values are files: strings ending in one of :data:`FILE_SUFFIXES`, the same
rule the SoundSource FMU uses to tell a waypoint CSV from a built-in path name.
"""

from pathlib import Path

__all__ = ["ALLOW_OUTSIDE_HINT", "FILE_SUFFIXES", "confine", "names_a_file"]

FILE_SUFFIXES = (".csv",)
ALLOW_OUTSIDE_HINT = "pass --allow-outside to read it"


def names_a_file(value):
    """Whether a parameter value is a file path (a string ending in a file suffix)."""
    return isinstance(value, str) and value.strip().lower().endswith(FILE_SUFFIXES)


def confine(text, base_dir, allow_outside=False, must_exist=True):
    """Resolve a path named in a file against that file's folder.

    Parameters
    ----------
    text : str
        The path as written (relative to ``base_dir``, or absolute).
    base_dir : path-like
        The folder of the file that names the path.
    allow_outside : bool
        Accept a path that leads outside ``base_dir``.
    must_exist : bool
        Report a path that names no file.

    Returns
    -------
    (pathlib.Path, str or None)
        The resolved absolute path (symbolic links followed), and why it is refused (a phrase
        to follow the field's name) or None.
    """
    base = Path(base_dir).resolve()
    resolved = (base / Path(text)).resolve()
    if not allow_outside and not resolved.is_relative_to(base):
        return resolved, (f"{text!r} leads outside {base} (the folder of the file that names "
                          f"it); {ALLOW_OUTSIDE_HINT}")
    if must_exist and not resolved.is_file():
        what = "is a folder" if resolved.is_dir() else "does not exist"
        return resolved, f"{text!r} ({resolved}) {what}; expected a file"
    return resolved, None
