"""Lifetime of sonotrack's FMI binary in a Python host: 500 instantiate/free cycles leave
sys.path and sys.modules alone (and RSS nearly flat), and unloading (dlclose) and reloading
every FMU twice in one process exits cleanly (the interpreter is never finalized).
"""

import subprocess
import sys
import textwrap

import pytest

from tests.support.fmi_binary import ABORT_SIGNS, NAMES
from tests.support.fmu_checks import instantiate_free_cycles

pytestmark = pytest.mark.integration


def test_500_instantiations_leave_sys_path_and_sys_modules_unchanged(fmu_paths):
    facts = instantiate_free_cycles(fmu_paths["WheelController"], 500)
    print(f"RSS growth over 500 instantiate/free cycles: {facts['rss_growth_kib']} KiB")
    assert facts["path_unchanged"]
    assert facts["modules_added"] == [] and facts["modules_removed"] == []
    # a leak of one slave per cycle (its core, fuzzy tables, ports) is far above this
    assert facts["rss_growth_kib"] < 4096, facts


_UNLOAD_RELOAD = textwrap.dedent('''
    import sys
    import fmpy
    for round_ in range(2):  # fmpy unloads (dlclose) each binary when simulate_fmu returns
        for path in sys.argv[1:]:
            result = fmpy.simulate_fmu(path, stop_time=0.1)
            assert len(result) > 1
    print("done", flush=True)
''')


def test_python_host_unloading_and_reloading_every_fmu_exits_cleanly(fmu_paths):
    completed = subprocess.run([sys.executable, "-c", _UNLOAD_RELOAD,
                                *[str(fmu_paths[name]) for name in NAMES]],
                               capture_output=True, text=True, cwd="/", timeout=600)
    assert completed.returncode == 0, completed.stderr[-3000:]
    assert completed.stdout.strip() == "done"
    assert not any(sign in completed.stderr for sign in ABORT_SIGNS), completed.stderr[-3000:]
