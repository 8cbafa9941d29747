"""Reading a starting scheduler's address: partial JSON is waited out, an exit is reported."""

import subprocess
import sys

import pytest

from components.common.errors import SimulationError
from orchestrator.sweep.dask_cluster import scheduler_address

# Writes the file in two pieces, as a scheduler's non-atomic write can be seen, then lives on.
_SLOW_WRITER = """
import sys, time
path = sys.argv[1]
with open(path, "w") as stream:
    stream.write('{"address": "tcp://127.0.0.1:')
    stream.flush()
    time.sleep(0.5)
    stream.write('41234", "type": "Scheduler"}')
time.sleep(30)
"""


def test_the_address_is_read_once_the_json_is_whole(tmp_path):
    target = tmp_path / "scheduler.json"
    process = subprocess.Popen([sys.executable, "-c", _SLOW_WRITER, str(target)])
    try:
        assert scheduler_address(target, process, timeout=30) == "tcp://127.0.0.1:41234"
    finally:
        process.kill()
        process.wait()


def test_a_scheduler_that_exits_is_named_with_its_status(tmp_path):
    process = subprocess.Popen([sys.executable, "-c", "raise SystemExit(3)"])
    process.wait()
    with pytest.raises(SimulationError, match="exited with status 3"):
        scheduler_address(tmp_path / "scheduler.json", process, timeout=5)


def test_no_address_in_time_is_an_error(tmp_path):
    process = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        with pytest.raises(SimulationError, match="wrote no address"):
            scheduler_address(tmp_path / "scheduler.json", process, timeout=0.5)
    finally:
        process.kill()
        process.wait()
