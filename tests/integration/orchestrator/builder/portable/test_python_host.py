"""Portable FMUs on the build machine: what they declare and carry, and which Python they use.

Which libpython a process loads is read from the dynamic loader's own trace (``LD_DEBUG=files``
lists every file it opens): in fmpy (a Python host) the FMU's carried libpython is never
opened, and no module comes from its folder; in the C host on this machine, where the build's
Python is also there to be found, the carried one is opened and the build's is not (the search
order: the runtime carried in the FMU comes before the paths recorded at build).
"""

import json
import os
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

from orchestrator.builder.fmi_binary import BINDING_FILE
from orchestrator.builder.portable import MANIFEST, RUNTIME_FOLDER, SIZE_LIMIT
from tests.support.fmi_binary import check_host_run, host_env, plan, run_host

pytestmark = pytest.mark.integration

NAME = "WheelController"
WITHOUT_NUMPY = {"RobotPlant", "CurvaturePlanner"}  # the models whose code never imports numpy
SITE = "lib/python3.11/site-packages"


def test_portable_fmus_are_at_most_20_mb_need_no_execution_tool_and_carry_numpy_where_used(
        portable_paths, fmu_paths):
    for name, path in portable_paths.items():
        assert path.stat().st_size <= SIZE_LIMIT, (name, path.stat().st_size)
        with zipfile.ZipFile(path) as archive:
            description = archive.read("modelDescription.xml").decode()
            table = archive.read(BINDING_FILE).decode()
            manifest = json.loads(archive.read(MANIFEST))
            names = archive.namelist()
            assert f"{RUNTIME_FOLDER}/lib/libpython3.11.so.1.0" in archive.namelist()
            assert not [n for n in archive.namelist() if n.startswith("binaries/win64/")]
        assert 'needsExecutionTool="false"' in description
        assert f"runtime\t{RUNTIME_FOLDER}\n" in table
        numpy_files = [n for n in names if n.startswith(f"{RUNTIME_FOLDER}/{SITE}/numpy")]
        if name in WITHOUT_NUMPY:  # their cores and the shared slave base never import it
            assert manifest["numpy"] is None and not numpy_files, name
            assert "runtime_numpy\tno\n" in table
            assert path.stat().st_size <= 6_000_000, (name, path.stat().st_size)
        else:
            assert manifest["numpy"] and numpy_files, f"{name} carries no numpy"
            assert "runtime_numpy\t" not in table
            assert path.stat().st_size > 6_000_000, (name, path.stat().st_size)
        assert set(manifest["recorded_stdlib_modules"]) - set(manifest["left_out_by_rule"]) <= \
            set(manifest["carried_stdlib_modules"])
        with zipfile.ZipFile(fmu_paths[name]) as archive:  # the plain build
            assert 'needsExecutionTool="true"' in archive.read("modelDescription.xml").decode()
            assert "runtime\t" not in archive.read(BINDING_FILE).decode()


_FMPY_RUN = """
import sys
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave
folder = sys.argv[1]
description = read_model_description(folder)
slave = FMU2Slave(guid=description.guid, unzipDirectory=folder, modelIdentifier="{name}",
                  instanceName="host")
slave.instantiate()
slave.setupExperiment(startTime=0.0)
slave.enterInitializationMode()
slave.exitInitializationMode()
for k in range(10):
    slave.doStep(currentCommunicationPoint=k * 0.005, communicationStepSize=0.005)
import numpy
print("NUMPY", numpy.__file__)
print("FILES", *[getattr(m, "__file__", None) or "" for m in list(sys.modules.values())])
""".format(name=NAME)


def _opened(stderr):
    """Files the dynamic loader opened (LD_DEBUG=files)."""
    return [line.split("file=", 1)[1].split()[0] for line in stderr.splitlines()
            if "file=" in line]


def test_in_a_python_host_the_fmu_uses_the_host_interpreter(portable_extracted):
    folder = portable_extracted[NAME][0]
    runtime = str(folder / RUNTIME_FOLDER)
    completed = subprocess.run([sys.executable, "-c", _FMPY_RUN, str(folder)],
                               capture_output=True, text=True, timeout=300,
                               env={**host_env(), "LD_DEBUG": "files"})
    assert completed.returncode == 0, completed.stderr[-3000:]
    opened = _opened(completed.stderr)
    assert any(path.endswith(f"{NAME}.so") for path in opened)  # the trace is there
    assert not [path for path in opened if path.startswith(runtime)]
    numpy_file = next(x for x in completed.stdout.splitlines() if x.startswith("NUMPY "))
    assert numpy_file.split(" ", 1)[1].startswith(sys.prefix)
    files = next(x for x in completed.stdout.splitlines() if x.startswith("FILES ")).split()
    assert not [f for f in files if f.startswith(runtime)]


def test_in_a_c_host_the_carried_runtime_comes_before_the_build_python(
        c_host, portable_extracted):
    folder, description = portable_extracted[NAME]
    text, _ = plan(None, [(NAME, folder, description, f"c_{NAME}")])
    carried = str(folder / RUNTIME_FOLDER / "lib" / "libpython3.11.so.1.0")
    build_libpython = os.path.realpath(Path(sysconfig.get_config_var("LIBDIR")) /
                                       sysconfig.get_config_var("INSTSONAME"))
    completed = run_host(c_host, text, env={**host_env(), "LD_DEBUG": "files"})
    opened = _opened(completed.stderr)
    assert carried in opened, opened
    assert build_libpython not in [os.path.realpath(p) for p in opened]
    check_host_run(run_host(c_host, text), [NAME], portable_extracted)
    # the same check the other way round: a Python named in SONOTRACK_PYTHON comes first
    completed = run_host(c_host, text, env={**host_env(), "LD_DEBUG": "files",
                                            "SONOTRACK_PYTHON": sys.executable})
    opened = [os.path.realpath(p) for p in _opened(completed.stderr)]
    assert build_libpython in opened and os.path.realpath(carried) not in opened
