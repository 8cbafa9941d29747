"""The ecos child ends with its caller, however the caller dies (docs/process_lifetime.md).

A stand-in ``ecos`` (a shell script that records its pid and sleeps) is run through
:func:`orchestrator.hosts.ecos.run_ecos` by a caller process; the caller is killed with
SIGKILL and the stand-in must be gone within a second. Without the tie it sleeps on.
"""

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="the parent-death signal is Linux's")

_CALLER = textwrap.dedent("""
    import sys
    from orchestrator.hosts.ecos import run_ecos
    run_ecos(sys.argv[1], sys.argv[2], 1.0, 0.01, sys.argv[3])
""")


def _alive(pid):
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state not in ("Z", "X")


def test_a_killed_caller_takes_its_ecos_child_with_it(tmp_path):
    pid_file = tmp_path / "ecos.pid"
    fake = tmp_path / "ecos"
    fake.write_text(f"#!/bin/sh\necho $$ > {pid_file}\nexec sleep 30\n")
    fake.chmod(0o755)
    caller = subprocess.Popen([sys.executable, "-c", _CALLER, str(fake), str(tmp_path),
                               str(tmp_path / "out")], start_new_session=True)
    try:
        deadline = time.monotonic() + 30
        while not (pid_file.exists() and pid_file.read_text().strip()):
            assert time.monotonic() < deadline, "the stand-in ecos never started"
            time.sleep(0.05)
        child = int(pid_file.read_text())
        assert _alive(child)
        caller.send_signal(signal.SIGKILL)
        caller.wait()
        deadline = time.monotonic() + 1.0
        while _alive(child) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert not _alive(child), "ecos ran on after its caller was killed"
    finally:
        try:
            os.killpg(caller.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
