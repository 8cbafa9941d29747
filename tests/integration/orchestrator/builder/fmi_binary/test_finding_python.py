"""How the FMI binary finds Python in a host that runs none (docs/fmi_binary.md, "Finding Python").

Through the C host (no Python in it) and the probe FMU, whose action 6 logs ``sys.prefix``:
- found: the recorded Python; SONOTRACK_PYTHON alone (libpython derived from it);
  ``python3.11`` on PATH when the recorded paths are gone; PYTHONHOME and PYTHONPATH pointing
  nowhere change nothing (the interpreter starts isolated; they used to end the host);
- mis-set-up: every case is one line naming the places tried, why each failed and the fix,
  given to the host's logger (fmi2Error) and written to stderr, and fmi2Instantiate returns NULL
  while the host process goes on and exits by itself (the C host's status 4).
"""

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from tests.support.fmi_binary import host_env, run_host

pytestmark = pytest.mark.integration

VERSION = f"3.{sys.version_info.minor}"
LIBPYTHON = Path(sysconfig.get_config_var("LIBDIR"), sysconfig.get_config_var("INSTSONAME"))
BASE = Path(sys.base_prefix)


def _plan(folder, description):
    refs = {v.name: v.valueReference for v in description.modelVariables}
    binary = folder / "binaries" / "linux64" / "Probe.so"
    return (f"1 1\n{binary} {description.guid} {(folder / 'resources').as_uri()} c_probe "
            f"0.01 0 1 {refs['action']} 0 1 {refs['elapsed']} 1 {refs['count']} 0\n6\n")


@pytest.fixture(scope="module")
def moved(probe, tmp_path_factory):
    """The probe as on another machine: the Python recorded at build is not there."""
    folder, description = probe
    copy = tmp_path_factory.mktemp("moved") / "Probe"
    shutil.copytree(folder, copy)
    table = copy / "resources" / "sonotrack_binding.txt"
    lines = [("python\t/nonexistent/bin/python" if line.startswith("python\t") else
              "libpython\t/nonexistent/lib/libpython3.11.so.1.0"
              if line.startswith("libpython\t") else line)
             for line in table.read_text().splitlines()]
    table.write_text("\n".join(lines) + "\n")
    return copy, description


@pytest.fixture(scope="module")
def bare_venv(tmp_path_factory):
    """A venv of this Python without numpy."""
    folder = tmp_path_factory.mktemp("bare") / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(folder)], check=True)
    return folder


def _runs(completed, prefix):
    assert completed.returncode == 0, completed.stderr[-3000:]
    assert completed.stdout.split() == ["0", "0", "0", "1"]  # step 0, FMU 0, elapsed, count
    assert f"sys.prefix={prefix}" in completed.stderr, completed.stderr[-3000:]


def _refused(completed, *words):
    """One line, to the logger and to stderr, with ``words``; NULL instance; the host lives."""
    assert completed.returncode == 4, completed.stderr[-3000:]  # main returned: no exit, no crash
    logged = [line for line in completed.stderr.splitlines() if line.startswith("log c_probe")]
    printed = [line for line in completed.stderr.splitlines()
               if line.startswith("sonotrack FMU c_probe: ")]
    assert len(logged) == len(printed) == 1, completed.stderr
    assert logged[0].startswith("log c_probe status=3 logStatusError: fmi2Instantiate: ")
    line = printed[0].removeprefix("sonotrack FMU c_probe: ")
    assert logged[0].endswith(line)
    assert "fmi2Instantiate of c_probe returned NULL" in completed.stderr
    for word in words + ("tried: ", "Fix: "):
        assert word in line, (word, line)
    return line


def test_the_recorded_python_runs(c_host, probe):
    _runs(run_host(c_host, _plan(*probe)), sys.prefix)


def test_pythonhome_and_pythonpath_pointing_nowhere_change_nothing(c_host, probe):
    env = dict(host_env(), PYTHONHOME="/nonexistent", PYTHONPATH="/nonexistent")
    _runs(run_host(c_host, _plan(*probe), env=env), sys.prefix)


def test_sonotrack_python_alone_gives_its_libpython(c_host, moved):
    env = dict(host_env(), SONOTRACK_PYTHON=sys.executable)
    _runs(run_host(c_host, _plan(*moved), env=env), sys.prefix)


def test_python3_x_on_path_is_found_when_the_recorded_one_is_gone(c_host, moved):
    bin_folder = Path(sys.executable).parent  # this venv's bin: python3.11 is there
    assert (bin_folder / f"python{VERSION}").exists()
    env = dict(host_env(), PATH=f"/nonexistent:{bin_folder}")
    _runs(run_host(c_host, _plan(*moved), env=env), sys.prefix)


def _prefix_with_libpython(root, stdlib):
    """A copy of this Python's libpython in a prefix of its own, with or without a stdlib."""
    (root / "lib").mkdir(parents=True)
    library = root / "lib" / LIBPYTHON.name
    shutil.copy(LIBPYTHON, library)
    if stdlib:
        lib = root / "lib" / f"python{VERSION}"
        (lib / "encodings").mkdir(parents=True)
        (lib / "lib-dynload").mkdir()
        (lib / "os.py").write_text("")
        (lib / "encodings" / "__init__.py").write_text("")
    return library


def _numpy_for_another_python(root):
    site = root / "lib" / f"python{VERSION}" / "site-packages" / "numpy"
    (site / "_core").mkdir(parents=True)
    (site / "__init__.py").write_text("")
    (site / "_core" / "_multiarray_umath.cpython-39-x86_64-linux-gnu.so").write_text("")
    return root


def _link(path):
    path.symlink_to(LIBPYTHON)
    return path


def _script(folder):
    folder.mkdir()
    (folder / f"python{VERSION}").write_text("#!/bin/sh\nexec false\n")
    (folder / f"python{VERSION}").chmod(0o755)
    return folder


def _venv_with(venv, copy):
    shutil.copytree(venv, copy, symlinks=True)
    _numpy_for_another_python(copy)
    return copy / "bin" / "python"


CASES = {
    "python_nowhere": (lambda tmp, venv: {"SONOTRACK_PYTHON": "/nonexistent/python"},
                       ("SONOTRACK_PYTHON /nonexistent/python: does not exist",)),
    "libpython_nowhere": (lambda tmp, venv: {"SONOTRACK_LIBPYTHON": "/nonexistent/libpython3.11.so"},
                          ("SONOTRACK_LIBPYTHON /nonexistent/libpython3.11.so: does not exist",)),
    "versions_differ": (
        lambda tmp, venv: {"SONOTRACK_PYTHON": sys.executable,
                           "SONOTRACK_LIBPYTHON": str(_link(tmp / "libpython3.12.so.1.0"))},
        ("is Python 3.12 but", f"is Python {VERSION}")),
    "prefixes_differ": (
        lambda tmp, venv: {"SONOTRACK_PYTHON": sys.executable,
                           "SONOTRACK_LIBPYTHON": str(_prefix_with_libpython(tmp / "other", True))},
        ("belongs to the Python in", str(BASE))),
    "no_standard_library": (
        lambda tmp, venv: {"SONOTRACK_LIBPYTHON": str(_prefix_with_libpython(tmp / "bare", False))},
        (f"no standard library of Python {VERSION}",)),
    "no_numpy": (lambda tmp, venv: {"SONOTRACK_PYTHON": str(venv / "bin" / "python")},
                 (f"no numpy in VENV/lib/python{VERSION}/site-packages",)),
    "numpy_for_another_python": (
        lambda tmp, venv: {"SONOTRACK_PYTHON": str(_venv_with(venv, tmp / "v2"))},
        ("is built for another Python", f"CPython {VERSION}")),
    "script_on_path": (lambda tmp, venv: {"PATH": str(_script(tmp / "bin"))},
                       ("a script (a pyenv shim?)",)),
}


@pytest.mark.parametrize("case", list(CASES), ids=list(CASES))
def test_a_mis_set_up_host_gets_one_line_and_lives_on(c_host, moved, bare_venv, tmp_path, case):
    settings, words = CASES[case]
    env = dict(host_env(), **settings(tmp_path, bare_venv))
    words = tuple(w.replace("VENV", str(bare_venv)) for w in words)
    line = _refused(run_host(c_host, _plan(*moved), env=env), *words)
    print(line)


def test_nothing_found_names_every_place_tried(c_host, moved):
    env = dict(host_env(), PATH="/nonexistent")
    line = _refused(run_host(c_host, _plan(*moved), env=env),
                    "SONOTRACK_PYTHON, SONOTRACK_LIBPYTHON: not set",
                    "recorded at build /nonexistent/bin/python: does not exist",
                    f"python{VERSION} on PATH: not found", "python3 on PATH: not found",
                    "standard location")
    print(line)


def test_ecos_shows_the_reason_on_stderr(fmu_paths, tmp_path):
    """ecos logs an fmi2Instantiate refusal at debug level only and then fails on the NULL
    instance (a segfault, status 139, measured with ecospy 0.7.2); the reason must still reach
    the user: it is on ecos's stderr."""
    from orchestrator.hosts.ecos import ecos_binary

    binary, reason = ecos_binary(tmp_path)
    if binary is None:
        pytest.skip(f"ecos cannot run here: {reason}")
    env = dict(host_env(), SONOTRACK_PYTHON="/nonexistent/python")
    completed = subprocess.run([str(binary), "simulate", "--path",
                                str(fmu_paths["WheelController"]), "--stopTime", "0.1",
                                "--stepSize", "0.01", "--noParallel"], capture_output=True,
                               text=True, env=env, cwd=tmp_path, timeout=300)
    print(f"ecos exit status {completed.returncode}")
    lines = [line for line in completed.stderr.splitlines() if line.startswith("sonotrack FMU ")]
    assert len(lines) == 1, completed.stderr[-3000:]
    assert f"fmi2Instantiate: no Python {VERSION} or newer with numpy" in lines[0]
    assert "SONOTRACK_PYTHON /nonexistent/python: does not exist" in lines[0]
    assert "Fix: " in lines[0]
