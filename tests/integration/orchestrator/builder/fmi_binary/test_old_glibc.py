"""The FMI binary on an older Linux: a Debian 11 minimal root (glibc 2.31, no Python at all).

The root is made once by ``make debian11-root`` (debootstrap) outside the repository; the C host
is compiled for glibc 2.17 like the library, copied into the root with an unzipped FMU and run
there with chroot. The library loads (it needs glibc 2.17 at most), finds no Python and refuses
fmi2Instantiate with the one line that names every place tried and the fix; the host lives on.
The same FMU with the library gcc builds for this machine's glibc does not even load there,
which is what every FMU did before the glibc floor.
"""

import shutil
import subprocess
import sys

import pytest

from orchestrator.builder.fmi_binary import HERE, LOCK_LIBRARY, SOURCES
from tests.support.debian_roots import debian_root, folder_inside, host_for_glibc_2_17, run_in_root
from tests.support.fmi_binary import fmi_headers, plan

pytestmark = pytest.mark.integration

NAME = "WheelController"


@pytest.fixture(scope="module")
def debian11():
    """The root, checked to be Debian 11 with glibc 2.31 and no Python."""
    return debian_root(11)


@pytest.fixture
def inside(debian11):
    """A fresh folder inside the root: (its path on this machine, its path in the root)."""
    with folder_inside(debian11) as folders:
        yield folders


def _run_in_root(debian11, inside, extracted, library=None):
    """Run the C host on the FMU (its library replaced by ``library``, if given) in the root."""
    folder, in_root = inside
    shutil.copytree(extracted[NAME][0], folder / NAME)
    if library is not None:
        shutil.copy(library, folder / NAME / "binaries" / "linux64" / f"{NAME}.so")
    host_for_glibc_2_17(folder)
    text, _ = plan(None, [(NAME, in_root / NAME, extracted[NAME][1], "old")], 1)
    return run_in_root(debian11, in_root, text)


def test_in_debian_11_without_python_the_library_loads_and_refuses_with_one_line(
        debian11, inside, extracted):
    completed = _run_in_root(debian11, inside, extracted)
    print(completed.stderr)
    assert completed.returncode == 4, completed.stderr  # instance NULL; the host returned
    assert "GLIBC" not in completed.stderr and "dlopen failed" not in completed.stderr
    lines = [line for line in completed.stderr.splitlines()
             if line.startswith("sonotrack FMU old: ")]
    assert len(lines) == 1, completed.stderr
    for words in ("fmi2Instantiate: no Python 3.11 or newer with numpy",
                  "SONOTRACK_PYTHON, SONOTRACK_LIBPYTHON: not set",
                  f"recorded at build {sys.executable}: does not exist",
                  "python3.11 on PATH: not found", "python3 on PATH: not found",
                  "standard locations (/usr/lib/x86_64-linux-gnu, /usr/lib64, /usr/local/lib, "
                  "/usr/lib): no libpython3.11 to 3.14",
                  "Fix: install Python 3.11 with numpy"):
        assert words in lines[0], (words, lines[0])
    assert "fmi2Instantiate of old returned NULL" in completed.stderr


def test_the_library_gcc_builds_here_does_not_load_there(debian11, inside, extracted, tmp_path):
    """The control: the same sources built for this machine's glibc (as every FMU was before)."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed")
    library = tmp_path / "gcc_built.so"
    subprocess.run(["gcc", "-std=c11", "-fPIC", "-shared", "-O2", "-fvisibility=hidden",
                    '-DSONOTRACK_SOURCE_SHA256="0"', f"-I{fmi_headers()}", "-o", str(library),
                    *[str(p) for p in SOURCES if p.suffix == ".c" and p.name != "process_lock.c"],
                    f"-L{LOCK_LIBRARY.parent}", f"-l:{LOCK_LIBRARY.name}", "-Wl,-rpath,$ORIGIN",
                    "-ldl", "-lpthread"], check=True, cwd=HERE)
    completed = _run_in_root(debian11, inside, extracted, library)
    assert completed.returncode == 3, completed.stderr  # the host's dlopen failed
    assert "version `GLIBC_2.34' not found" in completed.stderr, completed.stderr
