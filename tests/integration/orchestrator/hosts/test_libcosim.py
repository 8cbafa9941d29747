"""libcosim's child process ends with the process that asked for the run, however it dies."""

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from orchestrator.builder.fmus import REPO_ROOT
from tests.support.process_group import group_members, kill_group, wait_until_gone

pytestmark = [pytest.mark.integration,
              pytest.mark.skipif(not sys.platform.startswith("linux"),
                                 reason="process groups and memory maps from /proc (Linux)")]

_CALLER = """
import sys
from orchestrator.hosts.libcosim import run_libcosim_ssd
run_libcosim_ssd(sys.argv[1], 0.01, 600.0, ["plant.x"])   # about a minute of stepping
"""


def _has_loaded_libcosim(pid):
    try:
        return "cosim" in Path(f"/proc/{pid}/maps").read_text()
    except OSError:
        return False


def test_a_killed_caller_takes_its_libcosim_child_with_it(fmu_dir):
    pytest.importorskip("libcosimpy")
    ssd = fmu_dir / "LibcosimKill.ssd"   # beside the FMUs it names
    shutil.copy(REPO_ROOT / "fmus" / "SystemStructure.ssd", ssd)
    caller = subprocess.Popen([sys.executable, "-c", _CALLER, str(ssd)], cwd=REPO_ROOT,
                              stderr=subprocess.PIPE, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        children = []
        while not children and time.monotonic() < deadline:
            assert caller.poll() is None, caller.communicate()
            children = [pid for pid in group_members(caller.pid)
                        if pid != caller.pid and _has_loaded_libcosim(pid)]
            time.sleep(0.05)
        assert children, "no libcosim child appeared"
        os.kill(caller.pid, signal.SIGKILL)
        caller.wait(timeout=30)
        elapsed, left = wait_until_gone(caller.pid, 3.0)
        assert left == [], f"libcosim still running {elapsed:.1f} s after its caller died"
    finally:
        kill_group(caller.pid)
        if caller.poll() is None:
            caller.kill()
        caller.wait(timeout=30)
