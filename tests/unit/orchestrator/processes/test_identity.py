"""A process record and its judgement: alive, gone (ended, zombie, pid reused, rebooted) or
unknown (another host, no record), against processes started and ended here."""

import json
import os
import socket
import subprocess
import sys
import time

import psutil
import pytest

from orchestrator.processes import (ALIVE, GONE, UNKNOWN, describe, process_record,
                                    process_state)

linux = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc (Linux)")


@linux
def test_a_record_names_this_process_and_its_start_time():
    record = process_record()
    assert (record["pid"], record["host"]) == (os.getpid(), socket.gethostname())
    # psutil reads the start time its own way (boot time + start ticks, cached once)
    assert record["started"] == pytest.approx(psutil.Process().create_time(), abs=1.0)
    assert record["started"] <= time.time()
    assert process_state(record) == ALIVE


@linux
def test_a_process_that_ended_is_gone_reaped_or_not():
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        record = process_record(child.pid)
        assert record["pid"] == child.pid and process_state(record) == ALIVE
        child.kill()
        # a killed child not yet reaped by its parent (us) is a zombie: it runs no more
        deadline = time.monotonic() + 10
        while psutil.Process(child.pid).status() != psutil.STATUS_ZOMBIE:
            assert time.monotonic() < deadline
            time.sleep(0.01)
        assert process_state(record) == GONE
    finally:
        child.kill()
        child.wait()
    assert process_state(record) == GONE   # reaped: no such process


@linux
def test_a_pid_that_names_another_process_now_is_gone():
    """pid reuse: the id exists, but the process under it started at another clock tick than
    the recorded one (the kernel's own start times of two processes, never equal here)."""
    record = process_record()
    older = subprocess.run([sys.executable, "-c", "import json; from orchestrator.processes "
                            "import process_record; print(json.dumps(process_record()))"],
                           capture_output=True, text=True, check=True)
    other = json.loads(older.stdout)
    assert other["start_ticks"] > record["start_ticks"]
    reused = dict(other, pid=os.getpid())   # our id, the other process's start
    assert process_state(reused) == GONE
    assert process_state(dict(record, boot_id="another-boot")) == GONE


@pytest.mark.parametrize("record", [
    None, "4242", {}, {"pid": True, "host": socket.gethostname()},
    {"pid": -1, "host": socket.gethostname()}, {"pid": os.getpid()},
    {"pid": os.getpid(), "host": socket.gethostname() + ".elsewhere"},
], ids=["none", "text", "empty", "bool-pid", "negative-pid", "no-host", "other-host"])
def test_what_cannot_be_judged_here_is_unknown(record):
    assert process_state(record) == UNKNOWN


def test_a_record_without_a_start_time_is_judged_by_its_id():
    """What a record written where /proc is missing holds: pid and host only."""
    here = socket.gethostname()
    assert process_state({"pid": os.getpid(), "host": here}) == ALIVE
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    assert process_state({"pid": child.pid, "host": here}) == GONE


def test_describe_names_the_process_for_messages():
    assert describe({"pid": 4242, "host": "lab-3"}) == "pid 4242 on lab-3"
    assert describe(None) == "an unrecorded process"
