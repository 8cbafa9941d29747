"""The FMI binary's identity: which C sources a library was compiled from.

The library is compiled by ``make`` from every ``*.c`` and ``*.h`` in ``orchestrator/builder/fmi_binary``
and carries the sha256 of those sources; ``sonotrack build`` refuses a library whose hash is not
that of the sources in the checkout. These tests check that the hash covers every source file,
that ``make`` rebuilds on a change to any of them, and that a stale library is refused.
"""

import shutil
import subprocess

import pytest

from components.common.errors import BuildError
from orchestrator.builder.fmus import REPO_ROOT
from tests.support.elf_versions import glibc_floor, required_versions
from orchestrator.builder.fmi_binary import (HERE, LIBRARY, LOCK_LIBRARY, SOURCES, install_binary,
                                             library_source_hash, source_hash)

SOURCE_NAMES = [path.name for path in SOURCES]


def _copy_sources(folder):
    folder.mkdir()
    for path in SOURCES:
        shutil.copy2(path, folder / path.name)
    return folder


def test_sources_are_every_c_file_and_header_of_the_folder():
    on_disk = sorted(p.name for p in HERE.iterdir() if p.suffix in (".c", ".h"))
    assert sorted(SOURCE_NAMES) == on_disk
    assert "sonotrack_fmi2.h" in SOURCE_NAMES and len(SOURCES) >= 8


@pytest.mark.parametrize("name", SOURCE_NAMES, ids=SOURCE_NAMES)
def test_editing_any_one_source_changes_the_hash(tmp_path, name):
    folder = _copy_sources(tmp_path / "src")
    original = source_hash(folder)
    assert original == source_hash(HERE)  # the copy is the checkout's sources
    path = folder / name
    path.write_bytes(path.read_bytes() + b" ")  # one byte more, e.g. a trailing space
    assert source_hash(folder) != original


def test_adding_removing_or_renaming_a_source_changes_the_hash(tmp_path):
    folder = _copy_sources(tmp_path / "src")
    original = source_hash(folder)
    (folder / "extra.c").write_text("/* a new translation unit */\n")
    added = source_hash(folder)
    (folder / "extra.c").unlink()
    assert source_hash(folder) == original
    (folder / "step.c").rename(folder / "stepping.c")
    renamed = source_hash(folder)
    (folder / "stepping.c").unlink()
    assert len({original, added, renamed, source_hash(folder)}) == 4


def test_the_built_library_records_the_hash_of_the_sources_in_the_checkout():
    assert LIBRARY.is_file(), "make builds the library before the tests"
    assert library_source_hash(LIBRARY) == source_hash()
    assert library_source_hash(LOCK_LIBRARY) == source_hash()


@pytest.mark.parametrize("library", [LIBRARY, LOCK_LIBRARY], ids=["library", "lock_library"])
def test_the_libraries_load_on_glibc_2_17(library):
    """The newest symbol version the libraries need is at most GLIBC_2.17 (RHEL 7, Debian 8,
    Ubuntu 14.04 and every later release), whatever glibc built them; what they need besides
    libc is only its old companions and the lock library."""
    print(f"{library.name}: {sorted(required_versions(library).items())}")
    assert glibc_floor(library) <= (2, 17)
    assert set(required_versions(library)) <= {"libc.so.6", "libdl.so.2", "libpthread.so.0"}


def test_a_stale_lock_library_is_refused(tmp_path):
    """The lock library beside the main one is checked too: both come from one checkout."""
    shutil.copy(LIBRARY, tmp_path / LIBRARY.name)
    data = LOCK_LIBRARY.read_bytes()
    (tmp_path / LOCK_LIBRARY.name).write_bytes(
        data.replace(library_source_hash(LOCK_LIBRARY).encode(), b"1" * 64))
    with pytest.raises(BuildError, match=rf"{LOCK_LIBRARY.name} was compiled from other C sources"):
        install_binary(tmp_path / "never_read.fmu", "pkg", "Model", "Model",
                       library=tmp_path / LIBRARY.name)


def test_a_library_compiled_from_other_sources_is_refused(tmp_path):
    stale = tmp_path / "stale.so"
    data = LIBRARY.read_bytes()
    recorded = library_source_hash(LIBRARY).encode()
    assert data.count(recorded) == 1
    stale.write_bytes(data.replace(recorded, b"0" * 64))
    with pytest.raises(BuildError, match=r"compiled from other C sources \(sha256 000000000000\)"
                                         r".*run `make`"):
        install_binary(tmp_path / "never_read.fmu", "pkg", "Model", "Model", library=stale)
    unmarked = tmp_path / "unmarked.so"
    unmarked.write_bytes(data.replace(b"sonotrack-fmi2-sources", b"something-else-sources"))
    with pytest.raises(BuildError, match="none recorded"):
        install_binary(tmp_path / "never_read.fmu", "pkg", "Model", "Model", library=unmarked)


@pytest.mark.parametrize("name", SOURCE_NAMES, ids=SOURCE_NAMES)
def test_make_rebuilds_the_library_when_any_source_changes(name):
    make = shutil.which("make")
    if make is None:
        pytest.skip("make is not installed")
    target = LIBRARY.relative_to(REPO_ROOT)
    source = (HERE / name).relative_to(REPO_ROOT)
    # -n: print what would run; -W: as if this one source had just been edited
    completed = subprocess.run([make, "-n", "-W", str(source), str(target)], cwd=REPO_ROOT,
                               capture_output=True, text=True, timeout=120)
    assert completed.returncode == 0, completed.stderr
    compile_lines = [line for line in completed.stdout.splitlines() if f"-o {target}" in line]
    assert compile_lines, completed.stdout
    lock_source = HERE / "process_lock.c"  # its own library, which the main one links to
    assert all(str(path.relative_to(REPO_ROOT)) in compile_lines[0]
               for path in SOURCES if path.suffix == ".c" and path != lock_source)
    assert str(lock_source.relative_to(REPO_ROOT)) not in compile_lines[0]
    if name == lock_source.name:
        lock = LOCK_LIBRARY.relative_to(REPO_ROOT)
        assert any(f"-o {lock}" in line and str(lock_source.relative_to(REPO_ROOT)) in line
                   for line in completed.stdout.splitlines()), completed.stdout
