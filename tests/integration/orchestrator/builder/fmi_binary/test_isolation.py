"""The FMUs run in a host whose Python has another pythonfmu, and ship only what runs.

Each FMU carries pythonfmu's run-time modules under a private name (``<package>._pythonfmu``,
orchestrator/builder/fmi_binary/carried_pythonfmu.py), so a host with pythonfmu 0.6.5 imported
(another Fmi2Slave; with the public name every FMU failed at fmi2SetupExperiment with a
TypeError) runs all five FMUs, from five threads, and prints what the C host prints for the same
plan. The archives: every entry deflated, no resources/pythonfmu, no build-time module of
pythonfmu (builder, deploy, csvbuilder, __main__), no code importing pythonfmu by its public name.
"""

import ast
import subprocess
import sys
import zipfile

import pytest

from tests.support.fmi_binary import NAMES, plan, run_host
from tests.support.fmi_threads import FMPY_THREADS, fmpy_spec

pytestmark = pytest.mark.integration

OTHER_PYTHONFMU = "0.6.5"
STEPS = 20
# What pythonfmu 0.7.0's __init__ needs at run time, read off its source by hand: the reference
# the build's import closure is checked against.
RUNTIME_0_7_0 = {"__init__.py", "_version.py", "enums.py", "fmi2slave.py", "variables.py",
                 "default_experiment.py", "logmsg.py"}


@pytest.fixture(scope="module")
def other_pythonfmu(tmp_path_factory):
    """A folder holding pythonfmu 0.6.5 from PyPI (skipped, saying why, if pip cannot get it)."""
    target = tmp_path_factory.mktemp("pythonfmu_065")
    completed = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                                "--disable-pip-version-check", "--target", str(target),
                                f"pythonfmu=={OTHER_PYTHONFMU}"],
                               capture_output=True, text=True, timeout=300)
    if completed.returncode != 0:
        pytest.skip(f"pip cannot install pythonfmu {OTHER_PYTHONFMU} here: "
                    f"{completed.stderr.strip()[-300:]}")
    return target


_HOST_PROLOGUE = f'''
import sys
import pythonfmu  # the host's own pythonfmu, imported before any FMU
assert pythonfmu.__version__ == "{OTHER_PYTHONFMU}", pythonfmu.__file__
host_pythonfmu = pythonfmu
host_folder = pythonfmu.__file__.rsplit("/pythonfmu/", 1)[0]
'''
_HOST_EPILOGUE = '''
assert sys.modules["pythonfmu"] is host_pythonfmu  # the FMUs left the host's copy alone
public = [m for m in sys.modules if m == "pythonfmu" or m.startswith("pythonfmu.")]
assert all(sys.modules[m].__file__.startswith(host_folder) for m in public), public
'''


def test_a_host_with_pythonfmu_0_6_5_runs_every_fmu(c_host, extracted, other_pythonfmu,
                                                    tmp_path):
    entries = [(name, *extracted[name], f"i_{name}") for name in NAMES]
    text, _ = plan(None, entries, STEPS)
    reference = run_host(c_host, text)
    assert reference.returncode == 0, reference.stderr[-2000:]
    spec = tmp_path / "spec.json"
    spec.write_text(fmpy_spec(entries, STEPS))
    env = {"PYTHONPATH": str(other_pythonfmu), "PATH": "/usr/bin:/bin"}
    completed = subprocess.run([sys.executable, "-c",
                                _HOST_PROLOGUE + FMPY_THREADS + _HOST_EPILOGUE, str(spec)],
                               capture_output=True, text=True, env=env, cwd="/", timeout=300)
    assert completed.returncode == 0, completed.stderr[-3000:]
    assert completed.stdout.strip() == reference.stdout.strip()


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_entries_are_deflated_and_only_pythonfmus_runtime_ships(fmu_paths, name):
    with zipfile.ZipFile(fmu_paths[name]) as archive:
        infos = archive.infolist()
        stored = [i.filename for i in infos if i.compress_type != zipfile.ZIP_DEFLATED]
        assert not stored, stored
        names = [i.filename for i in infos]
        assert not [n for n in names if n.startswith("resources/pythonfmu/")]
        carried = {n.rsplit("/", 1)[1] for n in names if "/_pythonfmu/" in n}
        assert carried == RUNTIME_0_7_0
        for entry in [n for n in names if n.endswith(".py")]:
            tree = ast.parse(archive.read(entry), filename=entry)
            for node in ast.walk(tree):
                if isinstance(node, ast.Import):
                    assert not any(a.name.split(".")[0] == "pythonfmu" for a in node.names), entry
                elif isinstance(node, ast.ImportFrom) and node.level == 0:
                    assert node.module.split(".")[0] != "pythonfmu", (entry, node.lineno)
