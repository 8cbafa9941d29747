"""The FMI binary on an older Linux: a Debian 11 minimal root (glibc 2.31, no Python at all).

The root is made once by ``make debian11-root`` (debootstrap) outside the repository; the C host
is compiled for glibc 2.17 like the library, copied into the root with an unzipped FMU and run
there with chroot. The library loads (it needs glibc 2.17 at most), finds no Python and refuses
fmi2Instantiate with the one line that names every place tried and the fix; the host lives on.
The same FMU with the library gcc builds for this machine's glibc does not even load there,
which is what every FMU did before the glibc floor.
"""

import os
import shutil
import subprocess
import sys
import uuid
from pathlib import Path

import pytest

from orchestrator.builder.fmi_binary import HERE, LOCK_LIBRARY, SOURCES
from tests.support.fmi_binary import C_HOST_SOURCE, fmi_headers, plan

pytestmark = pytest.mark.integration

ROOT = Path(os.environ.get("SONOTRACK_DEBIAN11_ROOT") or
            Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") /
            "sonotrack" / "roots" / "debian11")
ZIG = Path(sys.executable).parent / "python-zig"
NAME = "WheelController"


@pytest.fixture(scope="module")
def debian11():
    """The root, checked to be Debian 11 with glibc 2.31 and no Python."""
    if not (ROOT / ".complete").exists():
        pytest.skip(f"no Debian 11 root at {ROOT}: `make debian11-root` makes one (as root, "
                    f"with debootstrap from Debian)")
    if os.geteuid() != 0 or shutil.which("chroot") is None:
        pytest.skip("chroot is not installed or we are not root")
    assert (ROOT / "etc" / "debian_version").read_text().startswith("11.")
    assert (ROOT / "lib" / "x86_64-linux-gnu" / "libc-2.31.so").exists()
    pythons = [p for folder in ("usr/bin", "usr/local/bin", "usr/lib/x86_64-linux-gnu", "usr/lib")
               for p in (ROOT / folder).glob("*python3*")]
    assert not pythons, pythons
    return ROOT


@pytest.fixture
def inside(debian11):
    """A fresh folder inside the root: (its path on this machine, its path in the root)."""
    name = f"sonotrack-test-{uuid.uuid4().hex[:8]}"
    folder = debian11 / "tmp" / name
    folder.mkdir(parents=True)
    yield folder, Path("/tmp") / name
    shutil.rmtree(folder)


def _host_for_glibc_2_17(folder):
    if not ZIG.exists():
        pytest.skip(f"{ZIG} is missing: `make` installs ziglang into the venv")
    host = folder / "fmi_host"
    subprocess.run([str(ZIG), "cc", "-target", "x86_64-linux-gnu.2.17", "-std=c11", "-O1",
                    "-Wall", "-Werror", f"-I{fmi_headers()}", "-o", str(host), str(C_HOST_SOURCE),
                    "-ldl", "-pthread"], check=True, capture_output=True, text=True, timeout=600)
    return host


def _run_in_root(debian11, inside, extracted, library=None):
    """Run the C host on the FMU (its library replaced by ``library``, if given) in the root."""
    folder, in_root = inside
    shutil.copytree(extracted[NAME][0], folder / NAME)
    if library is not None:
        shutil.copy(library, folder / NAME / "binaries" / "linux64" / f"{NAME}.so")
    _host_for_glibc_2_17(folder)
    text, _ = plan(None, [(NAME, in_root / NAME, extracted[NAME][1], "old")], 1)
    return subprocess.run([shutil.which("chroot"), str(debian11), str(in_root / "fmi_host")],
                          input=text,
                          capture_output=True, text=True, timeout=300,
                          env={"PATH": "/usr/local/bin:/usr/bin:/bin", "HOME": "/root"})


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
