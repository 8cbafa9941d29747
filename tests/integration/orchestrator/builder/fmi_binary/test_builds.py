"""Build identity: two builds of one model whose code differs, loaded in one process (both
orders), each run their own code, because each build's cores live under a package named after
a hash of its sources (orchestrator.builder.fmi_binary.build_tag). The C library's own identity (which
sources it was compiled from) is checked in tests/unit/orchestrator/builder/test_fmi_binary.py.
"""

import json
import re
import shutil
import subprocess
import sys
import textwrap

import pytest

from orchestrator.builder.fmus import REPO_ROOT, build_fmu

pytestmark = pytest.mark.integration

_TWO_BUILDS = textwrap.dedent('''
    import json, sys
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    instances = []
    for index, path in enumerate(sys.argv[1:]):
        description = fmpy.read_model_description(path)
        slave = FMU2Slave(guid=description.guid, unzipDirectory=fmpy.extract(path),
                          modelIdentifier="WheelController", instanceName=f"build{index}")
        refs = {v.name: v.valueReference for v in description.modelVariables}
        start = next(v.start for v in description.modelVariables if v.name == "v_supply")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        instances.append((path, slave, refs, float(start)))
    result = {}
    for path, slave, refs, start in instances:  # step both only after both are loaded
        slave.setReal([refs["v_ref"], refs["v_meas"]], [1.0, 0.0])
        slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.005)
        voltage, v_supply = slave.getReal([refs["voltage"], refs["v_supply"]])
        result[path] = {"voltage": voltage, "v_supply": v_supply, "declared": start}
    print(json.dumps(result))
''')


def test_two_builds_of_one_model_each_run_their_own_code(fmu_paths, tmp_path):
    components = tmp_path / "components"
    shutil.copytree(REPO_ROOT / "components", components,
                    ignore=shutil.ignore_patterns("__pycache__"))
    # the core's default and the FMU's start value (the port table) of v_supply, as one change
    controller = components / "control" / "controller.py"
    source = controller.read_text()
    assert '"v_supply": 11.1,' in source
    controller.write_text(source.replace('"v_supply": 11.1,', '"v_supply": 7.5,'))
    table = components / "control" / "ranges.toml"
    text, count = re.subn(r"(\[parameters\.v_supply\][^\[]*\nstart = )11\.1\n", r"\g<1>7.5\n",
                          table.read_text())
    assert count == 1
    table.write_text(text)
    changed = build_fmu("WheelController", tmp_path / "b", components_dir=components)
    original = fmu_paths["WheelController"]
    for order in ([original, changed], [changed, original]):
        completed = subprocess.run([sys.executable, "-c", _TWO_BUILDS, *map(str, order)],
                                   capture_output=True, text=True, cwd="/", timeout=300)
        assert completed.returncode == 0, completed.stderr[-2000:]
        result = json.loads(completed.stdout.splitlines()[-1])
        # v_ref = 1 m/s from standstill saturates the output at +v_supply of each build's code
        assert result[str(original)] == {"voltage": 11.1, "v_supply": 11.1, "declared": 11.1}
        assert result[str(changed)] == {"voltage": 7.5, "v_supply": 7.5, "declared": 7.5}
