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

The cache is bounded (:func:`prune_cache`). A process that uses an entry holds a shared
``flock`` on ``<cache>/fmu-locks/<sha256>.lock`` from before it checks the entry until it exits
(the kernel drops the lock when the process ends, also on SIGKILL), and touches that file's
mtime on every use. A process forked from a holder (a local sweep's worker) shares its lock (one
open file description) and keeps it while it lives; such workers end with the sweep's process
(:mod:`orchestrator.sweep.engine`), so a killed sweep leaves no lock held. Each time an entry
is added, the least recently used entries beyond ``$SONOTRACK_CACHE_MAX_FMUS`` (default
:data:`MAX_CACHED_FMUS`) or beyond ``$SONOTRACK_CACHE_MAX_BYTES`` unpacked bytes (default
:data:`MAX_CACHED_BYTES`) are removed, but
only those whose lock the pruner can take exclusively, without waiting: an entry another process
(or this one) uses is never removed, however old. A removed entry is renamed aside before it is
deleted, so no process ever sees half of it; one unpacked again later is simply a new entry.
"""

import contextlib
import fcntl
import hashlib
import json
import os
import shutil
import stat
import tempfile
import threading
import time
import zipfile
import zlib
from pathlib import Path, PurePosixPath

from components.common.errors import ConfigError

__all__ = ["MAX_UNPACKED_BYTES", "MAX_CACHED_FMUS", "MAX_CACHED_BYTES", "cache_dir",
           "check_archive", "extract_fmu", "max_unpacked_bytes", "cache_limits", "prune_cache"]

MAX_UNPACKED_BYTES = 256 * 2**20
MAX_ENTRIES = 10_000
# Cache bounds: a run uses five FMU files, so 32 entries keep about six builds; 2 GiB holds eight
# FMUs at the 256 MiB unpacking cap (ours unpack to about 0.5 MB each).
MAX_CACHED_FMUS = 32
MAX_CACHED_BYTES = 2 * 2**30
_MARKER = ".sonotrack-extracted.json"
_COPY_BLOCK = 1 << 20
_LOCKS = "fmu-locks"
# Shared locks this process holds, by lock file: kept open until the process exits.
_HELD = {}
_HELD_GUARD = threading.Lock()


def cache_dir():
    """The folder holding sonotrack's caches (see the module docstring)."""
    explicit = os.environ.get("SONOTRACK_CACHE_DIR")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "sonotrack"


def _positive_setting(name, default, what):
    text = os.environ.get(name)
    if not text:
        return default
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value <= 0:
        raise ConfigError(f"{name}={text!r}: expected a positive number of {what} "
                          f"(default {default})")
    return value


def max_unpacked_bytes():
    """The cap on an FMU's unpacked size: ``SONOTRACK_FMU_MAX_BYTES`` or 256 MiB."""
    return _positive_setting("SONOTRACK_FMU_MAX_BYTES", MAX_UNPACKED_BYTES, "bytes")


def cache_limits():
    """The cache bounds: (``SONOTRACK_CACHE_MAX_FMUS`` entries, ``SONOTRACK_CACHE_MAX_BYTES``)."""
    return (_positive_setting("SONOTRACK_CACHE_MAX_FMUS", MAX_CACHED_FMUS, "FMUs"),
            _positive_setting("SONOTRACK_CACHE_MAX_BYTES", MAX_CACHED_BYTES, "bytes"))


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
    for folder in root.glob(".*-*"):
        with contextlib.suppress(OSError):
            if folder.is_dir() and time.time() - folder.stat().st_mtime > age:
                shutil.rmtree(folder, ignore_errors=True)


def _open_current_lock(path, operation):
    """Open ``path`` and flock it with ``operation``; return the descriptor, or None.

    None when a non-blocking lock is refused. A lock file can be unlinked by a pruner between
    our open and our lock; then the lock guards nothing, so we retry on the file now at
    ``path`` (inode check).
    """
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, operation)
        except BlockingIOError:
            os.close(fd)
            return None
        except BaseException:
            os.close(fd)
            raise
        try:
            current = os.stat(path)
            held = os.fstat(fd)
            if (current.st_ino, current.st_dev) == (held.st_ino, held.st_dev):
                return fd
        except FileNotFoundError:
            pass
        os.close(fd)


def _hold(cache, name):
    """Take (once per process) a shared lock on entry ``name`` and mark it used now.

    The lock is held until the process exits, so no pruner removes the entry under a run,
    whether it loads the FMU now or again later. Raises OSError if the lock cannot be taken.
    """
    path = cache / _LOCKS / f"{name}.lock"
    with _HELD_GUARD:
        if path not in _HELD:
            path.parent.mkdir(parents=True, exist_ok=True)
            _HELD[path] = _open_current_lock(path, fcntl.LOCK_SH)
        os.utime(path)   # the last use, which the pruner orders by


def _last_use(cache, folder):
    with contextlib.suppress(OSError):
        return (cache / _LOCKS / f"{folder.name}.lock").stat().st_mtime
    with contextlib.suppress(OSError):
        return folder.stat().st_mtime
    return 0.0


def _entry_bytes(folder):
    try:
        return sum(json.loads((folder / _MARKER).read_text())["files"].values())
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return 0


def _remove_unused(cache, name):
    """Remove entry ``name`` and its lock file unless some process holds its lock."""
    root = cache / "fmus"
    lock_path = cache / _LOCKS / f"{name}.lock"
    try:
        fd = _open_current_lock(lock_path, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return False
    if fd is None:
        return False   # in use by a process (possibly this one)
    aside = None
    try:
        if (root / name).exists():
            aside = Path(tempfile.mkdtemp(prefix=".pruned-", dir=root))
            os.rename(root / name, aside / "entry")   # atomic: never half an entry
        os.unlink(lock_path)   # while still locked, so a waiting user retries on a new file
    except OSError:
        return False
    finally:
        os.close(fd)
        if aside is not None:
            shutil.rmtree(aside, ignore_errors=True)
    return True


def prune_cache(max_fmus=None, max_bytes=None):
    """Remove the least recently used unpacked FMUs that no process is using.

    Entries are ranked by last use, newest first; the newest is always kept, and after it each
    entry is kept while at most ``max_fmus`` entries and ``max_bytes`` unpacked bytes are kept.
    An entry past the bounds is removed only if its lock can be taken exclusively at once:
    one in use by any process stays (and counts as kept). Lock files whose entry is gone are
    removed the same way.

    Parameters
    ----------
    max_fmus, max_bytes : int, optional
        Bounds (default :func:`cache_limits`).

    Returns
    -------
    list of str
        Names (SHA-256 digests) of the removed entries.
    """
    default_fmus, default_bytes = cache_limits()
    max_fmus = default_fmus if max_fmus is None else max_fmus
    max_bytes = default_bytes if max_bytes is None else max_bytes
    cache = cache_dir()
    root = cache / "fmus"
    try:
        entries = [folder for folder in root.iterdir()
                   if folder.is_dir() and not folder.name.startswith(".")]
    except OSError:
        return []
    ranked = sorted(entries, key=lambda folder: _last_use(cache, folder), reverse=True)
    removed = []
    kept_fmus = kept_bytes = 0
    for folder in ranked:
        size = _entry_bytes(folder)
        within = kept_fmus < max_fmus and kept_bytes + size <= max_bytes
        if kept_fmus == 0 or within or not _remove_unused(cache, folder.name):
            kept_fmus += 1
            kept_bytes += size
        else:
            removed.append(folder.name)
    names = {folder.name for folder in entries}
    with contextlib.suppress(OSError):
        for lock in (cache / _LOCKS).glob("*.lock"):
            if lock.stem not in names and not (root / lock.stem).exists():
                _remove_unused(cache, lock.stem)
    return removed


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
    cache = cache_dir()
    root = cache / "fmus"
    target = root / _digest(path)
    # The lock comes before the check that the entry is whole, so no pruner removes it after;
    # a refused archive writes nothing, not even a lock file.
    if target.exists():
        with contextlib.suppress(OSError):   # a cache we may not write to: nobody with our
            _hold(cache, target.name)         # rights can prune it either
        if _intact(target):
            return target
    limit = max_unpacked_bytes()
    entries = check_archive(path, limit)
    try:
        _hold(cache, target.name)
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
    prune_cache()   # only when an entry was added: reusing one costs nothing extra
    return target
