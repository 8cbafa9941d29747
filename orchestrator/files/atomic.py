"""Atomic file writes: a reader sees the old file or the new one, never a half-written one.

Every whole-file write of the orchestrator (a run's ``summary.json`` and plots, the sweep's
table, the reports, a rewritten FMU) goes through :func:`atomic_open`: the content goes to a
temporary file in the target's folder, which is flushed, fsync'ed on request and renamed over
the target with :func:`os.replace` (atomic on POSIX and Windows within one file system). A
write that fails midway (an exception, a full disk, a failed rename) removes the temporary file
and leaves the old target as it was.

Temporary files are hidden, named ``.<name>.<pid>.<random>.partial`` (:data:`TEMPORARY_PREFIX`,
:data:`TEMPORARY_SUFFIX`), so a killed writer's leftovers are recognisable (the run folder
removes them when a new run starts) and two writers never share one. They are created with
mode 0o666 less the umask, as :func:`open` would, so the target gets an ordinary file's mode.
"""

import contextlib
import os
import secrets
from pathlib import Path

from .json_policy import dumps

__all__ = ["TEMPORARY_PREFIX", "TEMPORARY_SUFFIX", "atomic_open", "atomic_write_bytes",
           "atomic_write_json", "atomic_write_text"]

TEMPORARY_PREFIX = "."
TEMPORARY_SUFFIX = ".partial"


def _create_temporary(path):
    """Create and open a new temporary file beside ``path``; return ``(descriptor, Path)``."""
    while True:
        temporary = path.with_name(f"{TEMPORARY_PREFIX}{path.name}.{os.getpid()}."
                                   f"{secrets.token_hex(4)}{TEMPORARY_SUFFIX}")
        try:
            flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
            return os.open(temporary, flags, 0o666), temporary
        except FileExistsError:
            continue


def _fsync_directory(directory):
    """Make a rename in ``directory`` durable (where the platform allows opening a folder)."""
    try:
        descriptor = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(descriptor)
    except OSError:
        pass
    finally:
        os.close(descriptor)


@contextlib.contextmanager
def atomic_open(path, mode="wb", fsync=True, encoding=None, newline=None):
    """Open a temporary file that replaces ``path`` when the ``with`` block ends without error.

    Parameters
    ----------
    path : path-like
        The target file; its folder must exist.
    mode : {"wb", "w"}
        Binary or text.
    fsync : bool
        Also fsync the file and its folder, so the new content survives a power cut, not only
        a killed process.
    encoding, newline : str, optional
        For text mode (default encoding UTF-8).

    Yields
    ------
    file object
        Write the whole new content to it (a :class:`zipfile.ZipFile` may write into it).

    Raises
    ------
    ValueError
        For another mode.
    """
    if mode not in ("wb", "w"):
        raise ValueError(f"atomic_open mode = {mode!r}; valid: 'wb', 'w'")
    path = Path(path)
    descriptor, temporary = _create_temporary(path)
    try:
        if mode == "w":
            stream = os.fdopen(descriptor, "w", encoding=encoding or "utf-8", newline=newline)
        else:
            stream = os.fdopen(descriptor, "wb")
    except BaseException:
        os.close(descriptor)
        temporary.unlink(missing_ok=True)
        raise
    try:
        with stream:
            yield stream
            stream.flush()
            if fsync:
                os.fsync(stream.fileno())
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise
    if fsync:
        _fsync_directory(path.parent)


def atomic_write_bytes(path, data, fsync=True):
    """Write ``data`` to ``path`` atomically; see :func:`atomic_open`.

    Parameters
    ----------
    path : path-like
        The target file; its folder must exist.
    data : bytes
        The whole new content.
    fsync : bool
        Also fsync the file and its folder.
    """
    with atomic_open(path, "wb", fsync=fsync) as stream:
        stream.write(data)


def atomic_write_text(path, text, fsync=True):
    """Write ``text`` (UTF-8, line ends as given) atomically; see :func:`atomic_open`."""
    atomic_write_bytes(path, text.encode("utf-8"), fsync=fsync)


def atomic_write_json(path, data, fsync=True, indent=2):
    """Write ``data`` as JSON (the :mod:`.json_policy`, then a newline) atomically.

    Non-finite floats are written as ``null``; for finite values the text is what
    ``json.dumps(data, indent=indent) + "\\n"`` gives.
    """
    atomic_write_text(path, dumps(data, indent=indent) + "\n", fsync=fsync)
