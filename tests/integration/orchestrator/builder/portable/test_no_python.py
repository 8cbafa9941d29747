"""Portable FMUs where no Python is installed: a Debian 12 minimal root (debootstrap, no Python).

The C host is compiled for glibc 2.17 like the library and run in the root with chroot, on
copies of the portable FMUs unzipped there: each FMU alone and all five in one process (one
without numpy first, and one with numpy first), outputs equal to fmpy's on this machine to
1e-12 (the same inputs, steps and outputs as every C-host test: tests/support/fmi_binary.py).
An FMU whose carried libpython or numpy is gone refuses fmi2Instantiate with the one line
naming what is missing and the fix, and the host lives on.
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


# RobotPlant and CurvaturePlanner carry no numpy (and fewer standard modules); the first FMU
# instantiated starts the interpreter from its runtime, and a later FMU's runtime is added to
# that interpreter's path: both orders
WITHOUT_NUMPY = ["RobotPlant", "CurvaturePlanner"]
WITH_NUMPY = ["SoundSource", "AcousticLocalizer", "WheelController"]


@pytest.mark.parametrize("order", [WITHOUT_NUMPY + WITH_NUMPY, WITH_NUMPY[::-1] + WITHOUT_NUMPY],
                         ids=["one without numpy first", "one with numpy first"])
def test_all_five_portable_fmus_run_in_one_process_in_debian_12(
        debian12, inside, portable_extracted, order):
    carries_numpy = [(portable_extracted[name][0] / RUNTIME_FOLDER / "lib" / "python3.11" /
                      "site-packages" / "numpy").is_dir() for name in order]
    assert carries_numpy == [name in WITH_NUMPY for name in order]
    text, _ = plan(None, _copy_in(inside, portable_extracted, order))
    completed = run_in_root(debian12, inside[1], text)
    check_host_run(completed, order, portable_extracted)


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


@pytest.fixture(scope="module")
def portable_system(portable_paths, tmp_path_factory):
    """TrackingSystem.fmu of the default scenario (first 2 s) built with --portable."""
    from orchestrator.builder.fmus import REPO_ROOT
    from orchestrator.run.as_fmu import build_scenario_fmu
    from orchestrator.scenario import load_scenario

    scenario = load_scenario(REPO_ROOT / "scenarios" / "s_curve.toml").with_overrides(
        stop_time=SYSTEM_STOP)
    return build_scenario_fmu(scenario, tmp_path_factory.mktemp("portable_system"),
                              fmu_dir=next(iter(portable_paths.values())).parent, portable=True)


SYSTEM_STOP = 2.0


def test_the_portable_system_fmu_runs_in_debian_12_like_fmpy_here(debian12, inside,
                                                                   portable_system):
    import fmpy

    from orchestrator.builder.portable import SIZE_LIMIT
    from tests.support.system_fmu import c_host_plan, c_host_rows, fmpy_run, largest_difference

    assert portable_system.stat().st_size <= SIZE_LIMIT
    folder, in_root = inside
    fmpy.extract(str(portable_system), str(folder / "system"))
    description = fmpy.read_model_description(str(folder / "system"))
    ports = [v.name for v in description.modelVariables
             if v.causality == "output" and v.type == "Real"][:64]
    completed = run_in_root(debian12, in_root,
                            c_host_plan(in_root / "system", description, SYSTEM_STOP, ports))
    assert completed.returncode == 0, completed.stderr[-3000:]
    ours = c_host_rows(completed.stdout, ports)
    assert len(ours[ports[0]]) == round(SYSTEM_STOP / 0.02)
    worst, where = largest_difference(ours, fmpy_run(portable_system, SYSTEM_STOP), ports,
                                      first_row=1)
    assert worst <= 1e-12, f"{where}: {worst}"


def test_on_a_glibc_older_than_the_runtime_s_the_fmu_refuses_with_one_line(portable_extracted):
    """Debian 11 has glibc 2.31; the carried libpython needs 2.35 (built here): refused, named."""
    root = debian_root(11)
    with folder_inside(root) as (folder, in_root):
        host_for_glibc_2_17(folder)
        entries = _copy_in((folder, in_root), portable_extracted, ["WheelController"])
        text, _ = plan(None, entries, 1)
        line = _one_line(run_in_root(root, in_root, text), "c_WheelController")
    for word in ("libpython", "(carried in the FMU) could not be loaded",
                 "version `GLIBC_2.3"):
        assert word in line, (word, line)
