"""Every bad input of the corpus (tests/data/bad) ends in one clear line, never a traceback.

The whole corpus runs in one child process through the CLI's entry point (see
:mod:`tests.support.bad_inputs`); a few cases also run through the installed ``sonotrack``
executable, to show the console script behaves the same.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.bad_inputs import CORPUS, case_arguments, load_cases

pytestmark = pytest.mark.integration

CASES = load_cases()
REPO = CORPUS.parent.parent.parent


@pytest.fixture(scope="module")
def corpus_results(fmu_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("bad_inputs")
    done = subprocess.run([sys.executable, "-m", "tests.support.bad_inputs", str(fmu_dir),
                           str(out)], cwd=REPO, capture_output=True, text=True,
                          timeout=60 * len(CASES))
    assert done.returncode == 0, done.stderr[-3000:]
    results = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    assert len(results) == len(CASES), done.stderr[-3000:]
    return results


def _check(case, status, stdout, stderr):
    assert status not in (0, None), (stdout, stderr)
    assert "Traceback" not in stdout + stderr
    lines = stderr.splitlines()
    if case.get("args", ["run"])[0] == "validate":
        # validate reports each problem on stdout and exits with their count
        assert case["expect"] in stdout and Path(case["file"]).name in stdout
        return
    assert len(lines) == 1, lines
    line = lines[0]
    assert case["expect"] in line
    assert line.startswith("sonotrack ")
    if case["kind"] in ("scenario", "fmu", "csv"):
        assert Path(case["file"]).name in line   # the file; the field is in `expect`


@pytest.mark.parametrize("index", range(len(CASES)),
                         ids=[f"{c['kind']}-{c['file']}" + ("-" + c["args"][-1] if "args" in c
                                                             else "") for c in CASES])
def test_bad_input_gives_one_line_naming_file_and_field(corpus_results, index):
    case, result = CASES[index], corpus_results[index]
    assert not result["timed_out"], f"{case['file']}: no answer within the time limit"
    assert result["escaped"] is None, result["escaped"]
    _check(case, result["status"], result["stdout"], result["stderr"])


def test_the_manifest_covers_every_kind_and_point():
    kinds = {c["kind"] for c in CASES}
    assert kinds == {"scenario", "system", "ssv", "csv", "fmu", "cli"}
    points = {p for c in CASES for p in c["point"].split(",")}
    assert {"1", "4", "5", "6", "7", "9"} <= points
    for case in CASES:
        assert (CORPUS / case["file"]).exists(), case["file"]


@pytest.mark.parametrize("name", ["mass_negative.toml", "non_utf8.toml", "band_inverted.toml",
                                  "a_directory.toml"])
def test_the_console_script_gives_the_same_line(fmu_dir, tmp_path, name):
    case = next(c for c in CASES if c["file"] == name)
    executable = Path(sys.executable).parent / "sonotrack"
    done = subprocess.run([str(executable)] + case_arguments(case, fmu_dir, tmp_path / "out"),
                          cwd=CORPUS, capture_output=True, text=True, timeout=120,
                          env={**os.environ, "SONOTRACK_TRACEBACK": ""})
    _check(case, done.returncode, done.stdout, done.stderr)
