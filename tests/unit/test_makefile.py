"""The Makefile's set-up checks: the Python version, a venv made by another Python, the C
compiler. Each target is run for real with ``make`` against stand-ins in a temporary folder."""

import shutil
import subprocess
import sys

import pytest

from orchestrator.builder.fmus import REPO_ROOT

pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="no make on PATH")


def _make(*arguments):
    done = subprocess.run(["make", "-s", "--no-print-directory", *arguments], cwd=REPO_ROOT,
                          capture_output=True, text=True, timeout=60)
    return done.returncode, done.stdout.strip()


def _fake_python(path, version):
    """A script answering the version check as a Python ``version`` would."""
    major, minor = version
    path.write_text(f"#!/bin/sh\nif [ \"$1\" = -c ]; then echo {major}.{minor}; "
                    f"exit {int((major, minor) != (3, 11))}; fi\necho Python {major}.{minor}.0\n")
    path.chmod(0o755)
    return path


@pytest.mark.parametrize("version", [(3, 9), (3, 12)], ids=["older", "newer"])
def test_another_python_is_refused_in_one_line_before_a_venv_exists(tmp_path, version):
    old = _fake_python(tmp_path / "python3", version)
    status, out = _make("python-check", f"PYTHON={old}", f"VENV={tmp_path / 'venv'}")
    assert status != 0
    assert out == (f"sonotrack needs Python 3.11; PYTHON='{old}' is {version[0]}.{version[1]}: "
                   "install python3.11 "
                   "(Debian: apt-get install python3.11-venv) or run make "
                   "PYTHON=/path/to/python3.11")
    assert not (tmp_path / "venv").exists()


def test_a_venv_made_by_another_python_is_made_again(tmp_path):
    venv = tmp_path / "venv"
    (venv / "bin").mkdir(parents=True)
    _fake_python(venv / "bin" / "python", (3, 9))
    status, out = _make("python-check", f"PYTHON={sys.executable}", f"VENV={venv}")
    here = "%d.%d" % sys.version_info[:2]
    assert status == 0 and out == f"{venv} was made by Python 3.9, not {here}: making it again"
    assert not venv.exists()


def test_a_venv_of_the_same_python_is_kept(tmp_path):
    venv = tmp_path / "venv"
    (venv / "bin").mkdir(parents=True)
    _fake_python(venv / "bin" / "python", sys.version_info[:2])
    assert _make("python-check", f"PYTHON={sys.executable}", f"VENV={venv}") == (0, "")
    assert (venv / "bin" / "python").exists()


def test_a_missing_c_compiler_is_named_with_the_fix():
    status, out = _make("cc-check", "FMI_CC=no-such-cc")
    assert status != 0
    assert out == ("no C compiler: 'no-such-cc' not found; install one (Debian: apt-get "
                   "install gcc) or name it: make FMI_CC=/path/to/cc")
    assert _make("cc-check", f"FMI_CC={sys.executable}") == (0, "")
