"""Portable FMUs where no Python is installed: a Debian 12 minimal root (debootstrap, no Python).

The C host is compiled for glibc 2.17 like the library and run in the root with chroot, on
copies of the portable FMUs unzipped there: each FMU alone and all five in one process, outputs
equal to fmpy's on this machine to 1e-12 (the same inputs, steps and outputs as every C-host
test: tests/support/fmi_binary.py). An FMU whose carried libpython or numpy is gone refuses
fmi2Instantiate with the one line naming what is missing and the fix, and the host lives on.
"""

import shutil

import pytest

from orchestrator.builder.fmus import FMU_PACKAGES
from orchestrator.builder.portable import RUNTIME_FOLDER
from tests.support.debian_roots import debian_root, folder_inside, host_for_glibc_2_17, run_in_root
from tests.support.fmi_binary import check_host_run, plan

pytestmark = pytest.mark.integration

NAMES = list(FMU_PACKAGES)


@pytest.fixture(scope="module")
def debian12():
    """The root, checked to be Debian 12 with no Python."""
    return debian_root(12)


@pytest.fixture
def inside(debian12):
    """A fresh folder inside the root with the glibc 2.17 C host in it."""
    with folder_inside(debian12) as (folder, in_root):
        host_for_glibc_2_17(folder)
        yield folder, in_root


def _copy_in(inside, portable_extracted, names):
    folder, in_root = inside
    for name in names:
        shutil.copytree(portable_extracted[name][0], folder / name)
    return [(name, in_root / name, portable_extracted[name][1], f"c_{name}") for name in names]


@pytest.mark.parametrize("name", NAMES)
def test_each_portable_fmu_runs_alone_in_debian_12_without_python(
        debian12, inside, portable_extracted, name):
    text, _ = plan(None, _copy_in(inside, portable_extracted, [name]))
    completed = run_in_root(debian12, inside[1], text)
    check_host_run(completed, [name], portable_extracted)


def test_all_five_portable_fmus_run_in_one_process_in_debian_12(
        debian12, inside, portable_extracted):
    text, _ = plan(None, _copy_in(inside, portable_extracted, NAMES))
    completed = run_in_root(debian12, inside[1], text)
    check_host_run(completed, NAMES, portable_extracted)


def _one_line(completed, instance):
    assert completed.returncode == 4, completed.stderr[-3000:]  # instance NULL; host returned
    lines = [line for line in completed.stderr.splitlines()
             if line.startswith(f"sonotrack FMU {instance}: ")]
    assert len(lines) == 1, completed.stderr
    assert f"fmi2Instantiate of {instance} returned NULL" in completed.stderr
    return lines[0]


@pytest.mark.parametrize("broken, words", [
    ("lib/libpython3.11.so.1.0", ("carried in the FMU ", "libpython3.11.so.1.0: does not exist")),
    ("lib/python3.11/site-packages/numpy",
     ("carried in the FMU ", "(Python 3.11): no numpy in ", "/site-packages")),
], ids=["libpython removed", "numpy removed"])
def test_a_portable_fmu_missing_part_of_its_runtime_refuses_with_one_line(
        debian12, inside, portable_extracted, broken, words):
    entries = _copy_in(inside, portable_extracted, ["WheelController"])
    target = inside[0] / "WheelController" / RUNTIME_FOLDER / broken
    shutil.rmtree(target) if target.is_dir() else target.unlink()
    text, _ = plan(None, entries, 1)
    line = _one_line(run_in_root(debian12, inside[1], text), "c_WheelController")
    for word in words + ("fmi2Instantiate: no Python 3.11 or newer with numpy",
                         "SONOTRACK_PYTHON, SONOTRACK_LIBPYTHON: not set",
                         "python3 on PATH: not found",
                         "Fix: this FMU carries its own Python in ",
                         "unzip the whole FMU again"):
        assert word in line, (word, line)
