"""A run killed while its renderer draws: the renderer and its forked copy end with it, and
the run's summary reads back with its plots abandoned (its results, finished, stand)."""

import json
import os
import signal
import subprocess
import sys

import pytest

from orchestrator.builder.fmus import REPO_ROOT
from orchestrator.run.folder import read_summary
from tests.support.process_group import (end_command, group_members, pause_env, read_to_eof,
                                         wait_for_stopped, wait_until_gone)
from tests.support.sweep_command import short_scenario

pytestmark = [pytest.mark.integration,
              pytest.mark.skipif(not sys.platform.startswith("linux"),
                                 reason="process states from /proc; parent-death signal")]


def _ppid(pid):
    text = open(f"/proc/{pid}/stat").read()
    return int(text[text.rfind(")") + 2:].split()[1])


def test_a_run_killed_mid_figure_leaves_no_renderer_and_reads_plots_abandoned(fmu_dir,
                                                                              tmp_path):
    scenario = short_scenario(tmp_path, 2.0)
    out = tmp_path / "run"
    # the renderer stops itself as it writes its first figure (the run waits for it)
    process = subprocess.Popen(
        [sys.executable, "-m", "orchestrator.cli", "run", str(scenario), "--out", str(out),
         "--fmu-dir", str(fmu_dir), "--quiet"], cwd=REPO_ROOT, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, start_new_session=True,
        env=pause_env("open */.trajectories.png.*.partial 1"))
    try:
        [renderer] = wait_for_stopped(process.pid, process=process)
        assert _ppid(renderer) == process.pid
        drawing = [pid for pid in group_members(process.pid) if pid != process.pid]
        assert len(drawing) >= 1 and renderer in drawing
        written = json.loads((out / "summary.json").read_text())
        assert (written["status"], written["plots"]) == ("ok", "drawing")
        assert read_summary(out)["plots"] == "drawing"   # the run waits: still drawing
        os.kill(process.pid, signal.SIGKILL)
        process.wait(timeout=30)
        # once the run is reaped its end has been signalled; only then may the renderer go on
        try:
            os.killpg(process.pid, signal.SIGCONT)
        except ProcessLookupError:
            pass
        elapsed, left = wait_until_gone(process.pid, 3.0)
        assert left == [], f"renderers still running {elapsed:.1f} s after the kill: {left}"
        assert read_to_eof(process.stdout, 1.0) is not None
        assert read_to_eof(process.stderr, 1.0) is not None
    finally:
        end_command(process)
    summary = read_summary(out)
    assert summary["status"] == "ok"   # results.csv and the figures of the run are complete
    assert summary["plots"] == "abandoned"
    assert f"pid {process.pid} on " in summary["plots_error"]
    assert not (out / "trajectories.png").exists(), "a renderer drew on after its run died"
