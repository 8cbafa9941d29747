"""Debian minimal roots with no Python (made once by ``make debian11-root`` / ``make
debian12-root`` with debootstrap, kept in ``~/.cache/sonotrack/roots``), and running the C host
inside one with chroot.

Used by tests/integration/orchestrator/builder/fmi_binary/test_old_glibc.py (Debian 11: the
library's glibc floor) and tests/integration/orchestrator/builder/portable/test_no_python.py
(Debian 12: portable FMUs where no Python is installed).
"""

import os
import shutil
import subprocess
import sys
import uuid
from contextlib import contextmanager
from pathlib import Path

import pytest

from tests.support.fmi_binary import C_HOST_SOURCE, fmi_headers

__all__ = ["ROOTS", "ZIG", "debian_root", "folder_inside", "host_for_glibc_2_17", "run_in_root"]

ROOTS = {
    11: ("SONOTRACK_DEBIAN11_ROOT", "debian11", "libc-2.31.so"),
    12: ("SONOTRACK_DEBIAN12_ROOT", "debian12", "libc.so.6"),
}
ZIG = Path(sys.executable).parent / "python-zig"


def debian_root(version):
    """The Debian ``version`` root, checked to be that release with no Python; skips (saying
    why) where it was not made or chroot cannot be used."""
    variable, name, libc = ROOTS[version]
    root = Path(os.environ.get(variable) or
                Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") /
                "sonotrack" / "roots" / name)
    if not (root / ".complete").exists():
        pytest.skip(f"no Debian {version} root at {root}: `make {name}-root` makes one (as "
                    f"root, with debootstrap from Debian)")
    if os.geteuid() != 0 or shutil.which("chroot") is None:
        pytest.skip("chroot is not installed or we are not root")
    assert (root / "etc" / "debian_version").read_text().startswith(f"{version}.")
    assert (root / "lib" / "x86_64-linux-gnu" / libc).exists()
    pythons = [p for folder in ("usr/bin", "usr/local/bin", "usr/lib/x86_64-linux-gnu", "usr/lib")
               for p in (root / folder).glob("*python3*")]
    assert not pythons, pythons
    return root


@contextmanager
def folder_inside(root):
    """A fresh folder inside the root: (its path on this machine, its path in the root)."""
    name = f"sonotrack-test-{uuid.uuid4().hex[:8]}"
    folder = root / "tmp" / name
    folder.mkdir(parents=True)
    try:
        yield folder, Path("/tmp") / name
    finally:
        shutil.rmtree(folder)


def host_for_glibc_2_17(folder):
    """tests/support/fmi_host.c compiled by zig for glibc 2.17 into ``folder``."""
    if not ZIG.exists():
        pytest.skip(f"{ZIG} is missing: `make` installs ziglang into the venv")
    host = folder / "fmi_host"
    subprocess.run([str(ZIG), "cc", "-target", "x86_64-linux-gnu.2.17", "-std=c11", "-O1",
                    "-Wall", "-Werror", f"-I{fmi_headers()}", "-o", str(host), str(C_HOST_SOURCE),
                    "-ldl", "-pthread"], check=True, capture_output=True, text=True, timeout=600)
    return host


def run_in_root(root, in_root, plan_text, *flags):
    """Run ``<in_root>/fmi_host`` (see :func:`host_for_glibc_2_17`) in the root on a plan."""
    return subprocess.run([shutil.which("chroot"), str(root), str(in_root / "fmi_host"), *flags],
                          input=plan_text, capture_output=True, text=True, timeout=600,
                          env={"PATH": "/usr/local/bin:/usr/bin:/bin", "HOME": "/root"})
