"""The rules that decide what a portable FMU carries (orchestrator/builder/portable/): the
standard-library closure of the recorded modules and of the model's code, what is left out by
rule, and which modules are carried compiled. The runs in a root with no Python are
tests/integration/orchestrator/builder/portable/."""

import sys

import pytest

from orchestrator.builder.portable.recording import needed_stdlib
from orchestrator.builder.portable.runtime import EXCLUDED, runtime_files

VERSION = f"python{sys.version_info.major}.{sys.version_info.minor}"


def test_the_closure_adds_what_recorded_modules_import_and_drops_what_is_not_stdlib():
    needed = needed_stdlib({"json", "numpy", "_sonotrack_x_123"})
    assert needed["recorded"] == ["json"]
    assert {"json", "json.decoder", "json.encoder", "json.scanner", "re"} <= \
        set(needed["carried"])
    assert not [n for n in needed["carried"] if n.startswith(("numpy", "_sonotrack"))]


def test_an_import_inside_a_function_of_the_model_code_is_carried(tmp_path):
    (tmp_path / "model.py").write_text("def later():\n    import csv\n    return csv\n")
    assert "csv" not in needed_stdlib({"bisect"})["carried"]
    assert "csv" in needed_stdlib({"bisect"}, [tmp_path])["carried"]


@pytest.fixture(scope="module")
def files():
    return runtime_files(["json", "json.decoder", "csv", "tkinter", "test.support"],
                         recorded={"json", "json.decoder"}, with_numpy=False)


def test_recorded_modules_are_carried_compiled_and_the_margin_as_source(files):
    assert f"lib/{VERSION}/json/__init__.pyc" in files
    assert f"lib/{VERSION}/json/decoder.pyc" in files
    assert f"lib/{VERSION}/csv.py" in files and f"lib/{VERSION}/csv.pyc" not in files
    # flags: hash based, source never checked (PEP 552)
    assert files[f"lib/{VERSION}/json/__init__.pyc"][4:8] == b"\x01\0\0\0"


def test_the_landmarks_every_codec_and_libpython_are_always_carried(files):
    assert f"lib/{VERSION}/os.pyc" in files or f"lib/{VERSION}/os.py" in files
    assert f"lib/{VERSION}/encodings/latin_1.py" in files
    assert f"lib/lib{VERSION}.so.1.0" in files
    assert f"lib/{VERSION}/lib-dynload/.keep" in files


def test_tools_and_tests_are_left_out_by_rule(files):
    assert "tkinter" in EXCLUDED and "test" in EXCLUDED
    assert not [p for p in files if "/tkinter/" in p or "/test/" in p]
    assert not [p for p in files if "site-packages" in p]  # with_numpy=False
