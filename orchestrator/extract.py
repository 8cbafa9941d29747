"""Unpack FMUs safely, once, into one cache keyed by their content.

An FMU is a zip archive. :func:`extract_fmu` unpacks it into ``<cache>/fmus/<sha256>/``,
where ``<sha256>`` is the digest of the ``.fmu`` file's bytes, and every later call (in any
process) reuses that folder: a rebuilt FMU has another digest, so a run never executes an
older build's binary, and nothing is written to the temporary folder.

Before anything is written the archive's entries are checked (:func:`check_archive`):
absolute names, drive letters, ``..`` components, backslashes, symbolic links and other
non-regular entries are refused, and the unpacked size is capped at
:data:`MAX_UNPACKED_BYTES` (256 MiB; raise it with the environment variable
``SONOTRACK_FMU_MAX_BYTES``) by the sizes the archive declares and again while unpacking, in
case they lie. Refusals are :class:`ConfigError` naming the FMU, the entry and the rule.

Concurrent processes are safe: each unpacks into its own temporary folder beside the cache
entry and renames it into place (atomic); a loser of that race drops its copy and uses the
winner's. A cache entry holds a marker listing its files and sizes, checked on every use, so
an entry damaged by hand is unpacked again rather than used.

The cache is ``$SONOTRACK_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/sonotrack``, else
``~/.cache/sonotrack``.
"""

import contextlib
import hashlib
import json
import os
import shutil
import stat
import tempfile
import zipfile
import zlib
from pathlib import Path, PurePosixPath

from components.common.errors import ConfigError

__all__ = ["MAX_UNPACKED_BYTES", "cache_dir", "check_archive", "extract_fmu",
           "max_unpacked_bytes"]

MAX_UNPACKED_BYTES = 256 * 2**20
MAX_ENTRIES = 10_000
_MARKER = ".sonotrack-extracted.json"
_COPY_BLOCK = 1 << 20


def cache_dir():
    """The folder holding sonotrack's caches (see the module docstring)."""
    explicit = os.environ.get("SONOTRACK_CACHE_DIR")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "sonotrack"


def max_unpacked_bytes():
    """The cap on an FMU's unpacked size: ``SONOTRACK_FMU_MAX_BYTES`` or 256 MiB."""
    text = os.environ.get("SONOTRACK_FMU_MAX_BYTES")
    if not text:
        return MAX_UNPACKED_BYTES
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value <= 0:
        raise ConfigError(f"SONOTRACK_FMU_MAX_BYTES={text!r}: expected a positive number of "
                          f"bytes (default {MAX_UNPACKED_BYTES})")
    return value


def _entry_problem(info):
    """Why an archive entry may not be unpacked, or None."""
    name = info.filename
    if "\\" in name:
        return "contains a backslash"
    if name.startswith("/") or (len(name) > 1 and name[1] == ":"):
        return "is an absolute path"
    if any(part == ".." for part in PurePosixPath(name).parts):
        return "contains a '..' component"
    if "\x00" in name or not name.strip("/"):
        return "has an empty or invalid name"
    mode = info.external_attr >> 16
    if mode and stat.S_IFMT(mode) not in (0, stat.S_IFREG, stat.S_IFDIR):
        return "is a symbolic link" if stat.S_ISLNK(mode) else "is not a regular file"
    return None


def check_archive(path, limit=None):
    """Check an FMU's entries before anything is unpacked; return them.

    Parameters
    ----------
    path : path-like
        The ``.fmu`` file.
    limit : int, optional
        Cap on the unpacked size in bytes (default :func:`max_unpacked_bytes`).

    Returns
    -------
    list of zipfile.ZipInfo

    Raises
    ------
    ConfigError
        If the file is not a zip archive or an entry breaks a rule (all such entries named).
    """
    path = Path(path)
    limit = max_unpacked_bytes() if limit is None else limit
    try:
        with zipfile.ZipFile(path) as archive:
            entries = archive.infolist()
    except (zipfile.BadZipFile, OSError, ValueError) as error:
        raise ConfigError(f"{path}: not an FMU (cannot read it as a zip archive: {error})") \
            from None
    if len(entries) > MAX_ENTRIES:
        raise ConfigError(f"{path}: {len(entries)} entries, more than {MAX_ENTRIES}; refused")
    problems = [f"entry {info.filename!r} {problem}" for info in entries
                if (problem := _entry_problem(info)) is not None]
    if problems:
        raise ConfigError(f"{path}: unsafe FMU archive, refused: " + "; ".join(problems[:5])
                          + (f" (and {len(problems) - 5} more)" if len(problems) > 5 else ""))
    declared = sum(info.file_size for info in entries)
    if declared > limit:
        largest = max(entries, key=lambda info: info.file_size)
        raise ConfigError(f"{path}: unpacks to {declared} bytes (entry {largest.filename!r}: "
                          f"{largest.file_size}), more than the cap of {limit}; refused "
                          f"(raise it with SONOTRACK_FMU_MAX_BYTES)")
    return entries


def _digest(path):
    sha = hashlib.sha256()
    with open(path, "rb") as stream:
        while block := stream.read(_COPY_BLOCK):
            sha.update(block)
    return sha.hexdigest()


def _intact(folder):
    """Whether a cache entry holds every file its marker lists, at the listed size."""
    try:
        listing = json.loads((folder / _MARKER).read_text())["files"]
        return all((folder / name).stat().st_size == size for name, size in listing.items())
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return False


def _unpack(path, entries, target, limit):
    """Unpack the checked entries into ``target``, counting bytes as they are written."""
    written = 0
    files = {}
    with zipfile.ZipFile(path) as archive:
        for info in entries:
            destination = target.joinpath(*PurePosixPath(info.filename).parts)
            if info.is_dir():
                destination.mkdir(parents=True, exist_ok=True)
                continue
            destination.parent.mkdir(parents=True, exist_ok=True)
            size = 0
            with archive.open(info) as source, open(destination, "xb") as sink:
                while block := source.read(_COPY_BLOCK):
                    size += len(block)
                    written += len(block)
                    if size > info.file_size or written > limit:
                        raise ConfigError(f"{path}: entry {info.filename!r} unpacks to more "
                                          f"than it declares or past the cap of {limit} "
                                          f"bytes; refused")
                    sink.write(block)
            files[PurePosixPath(info.filename).as_posix()] = size
    (target / _MARKER).write_text(json.dumps({"source": str(path), "files": files}))


def _remove_abandoned(root, age=3600.0):
    """Remove staging folders a killed process left behind (older than ``age`` seconds)."""
    import time

    for folder in root.glob(".*-*"):
        with contextlib.suppress(OSError):
            if folder.is_dir() and time.time() - folder.stat().st_mtime > age:
                shutil.rmtree(folder, ignore_errors=True)


def extract_fmu(path):
    """Unpack an FMU into the cache (once per content) and return its folder.

    Parameters
    ----------
    path : path-like
        The ``.fmu`` file.

    Returns
    -------
    pathlib.Path
        ``<cache>/fmus/<sha256 of the file>``, holding ``modelDescription.xml``,
        ``binaries/`` and ``resources/``.

    Raises
    ------
    ConfigError
        If the archive is refused (see :func:`check_archive`) or the cache cannot be written.
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{path}: no such FMU file")
    root = cache_dir() / "fmus"
    target = root / _digest(path)
    if _intact(target):
        return target
    limit = max_unpacked_bytes()
    entries = check_archive(path, limit)
    try:
        root.mkdir(parents=True, exist_ok=True)
        _remove_abandoned(root)
        staging = Path(tempfile.mkdtemp(prefix=f".{target.name[:16]}-", dir=root))
    except OSError as error:
        raise ConfigError(f"FMU cache {root}: cannot write there ({error.strerror}); set "
                          f"SONOTRACK_CACHE_DIR to a writable folder") from None
    try:
        _unpack(path, entries, staging, limit)
        if target.exists() and not _intact(target):
            # damaged by hand (or an older layout): move it aside, then put ours in its place
            broken = Path(tempfile.mkdtemp(prefix=".broken-", dir=root))
            with contextlib.suppress(OSError):
                os.rename(target, broken / "entry")
            shutil.rmtree(broken, ignore_errors=True)
        try:
            os.rename(staging, target)
        except OSError:
            if not _intact(target):  # not another process's finished copy
                raise
    except OSError as error:
        raise ConfigError(f"{path}: cannot unpack into the FMU cache {root} "
                          f"({error.strerror or error})") from None
    except (zipfile.BadZipFile, zlib.error, EOFError, NotImplementedError) as error:
        raise ConfigError(f"{path}: damaged FMU archive ({error}); refused") from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return target
