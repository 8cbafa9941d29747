"""Renderer processes: the same PNGs as drawing in-process, failures named, no orphans."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from orchestrator.run import plot_renderer
from orchestrator.run.plot_renderer import PlotError, PlotRenderer
from orchestrator.run.plots import PLOT_FILES, plot_run
from orchestrator.run.recorder import Recorder
from orchestrator.run.results import read_results

COLUMNS = ["source.x", "source.y", "plant.x", "plant.y", "plant.heading",
           "plant.wheel_speed_left", "plant.wheel_speed_right", "planner.v_ref_left",
           "planner.v_ref_right", "controller_left.kp", "controller_left.kd",
           "controller_right.kp", "controller_right.kd", "localizer.distance",
           "localizer.bearing", "localizer.valid"]


@pytest.fixture
def results_csv(tmp_path):
    rng = np.random.default_rng(7)
    path = tmp_path / "results.csv"
    with Recorder(path, COLUMNS) as recorder:
        for k in range(400):
            t = 0.02 * k
            row = [0.3 + 0.1 * t, 2.0 + 0.05 * t, 0.08 * t, 0.1 * t, 1.5 + 0.01 * t]
            row += [float(v) for v in rng.normal(0.3, 0.02, 4)]
            row += [float(v) for v in rng.uniform(-4, -3, 4)]
            row += [2.0 - 0.1 * t, float(rng.normal(0.1, 0.02)), k % 5 == 0]
            recorder.record(t, row)
    return path


def test_renderers_write_the_pngs_drawing_in_process_writes(results_csv, tmp_path):
    renderer = PlotRenderer()
    written = renderer.render(results_csv, tmp_path / "rendered", max_rows=2000)
    assert [p.name for p in written] == list(PLOT_FILES)
    reference = plot_run(read_results(results_csv, max_rows=2000), tmp_path / "in_process")
    for path in reference:
        assert (tmp_path / "rendered" / path.name).read_bytes() == path.read_bytes(), path.name
    times = renderer.timings
    assert times["started"] <= times["ready"] <= times["request"] <= times["done"]


def test_one_process_draws_everything_where_asked(results_csv, tmp_path):
    written = PlotRenderer(processes=1).render(results_csv, tmp_path, max_rows=2000)
    assert [p.name for p in written] == list(PLOT_FILES)


def test_a_renderer_that_dies_is_named_in_one_line(results_csv, tmp_path):
    renderer = PlotRenderer()
    renderer._process.kill()
    renderer._process.wait()
    with pytest.raises(PlotError) as caught:
        renderer.render(results_csv, tmp_path, max_rows=2000)
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith("plots " + ", ".join(PLOT_FILES) + ": ")
    assert "the renderer exited with status -9" in message
    assert not list(tmp_path.glob("*.png"))


@pytest.mark.parametrize("shares, drawn", [
    ((("trajectories.png", "no_such_plot.png"), ("gains.png",)), ["gains.png"]),
    ((("gains.png",), ("trajectories.png", "no_such_plot.png")), ["gains.png"]),
], ids=["failing-share-drawn-by-the-renderer", "failing-share-drawn-by-its-fork"])
def test_a_failing_share_comes_back_with_its_reason_and_the_rest_is_drawn(
        results_csv, tmp_path, monkeypatch, shares, drawn):
    monkeypatch.setattr(plot_renderer, "FIGURE_SHARES", shares)
    with pytest.raises(PlotError, match=r"^plots trajectories.png, no_such_plot.png: "
                                        r"ValueError: unknown plot no_such_plot.png; plots are "
                                        r"trajectories.png, [a-z_, .]*localizer.png$") as caught:
        PlotRenderer().render(results_csv, tmp_path, max_rows=2000)
    assert [p.name for p in caught.value.written] == drawn
    assert sorted(p.name for p in tmp_path.glob("*.png")) == drawn


def test_unreadable_results_are_named(tmp_path):
    (tmp_path / "results.csv").write_text("no header line")
    with pytest.raises(PlotError, match="reading the results: ConfigError: .*no complete "
                                        "header line"):
        PlotRenderer().render(tmp_path / "results.csv", tmp_path, max_rows=2000)


def test_unused_renderers_are_stopped_and_reaped():
    renderer = PlotRenderer()
    renderer.close()
    assert renderer._process.returncode is not None


_PARENT = """
import sys, time
from orchestrator.run.plot_renderer import PlotRenderer
renderer = PlotRenderer()
print(renderer._process.pid, flush=True)
time.sleep(60)
"""


def _alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as stream:
            return stream.read().split(") ")[1][0] != "Z"
    except FileNotFoundError:
        return False


def _ignores_sigint(pid):
    with open(f"/proc/{pid}/status") as stream:
        mask = next(line for line in stream if line.startswith("SigIgn:")).split()[1]
    return bool(int(mask, 16) & (1 << (signal.SIGINT - 1)))


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="parent-death signal: Linux")
def test_renderers_die_with_a_killed_parent():
    parent = subprocess.Popen([sys.executable, "-c", _PARENT], stdout=subprocess.PIPE,
                              text=True)
    try:
        pids = [int(p) for p in parent.stdout.readline().split()]
        assert len(pids) == 1 and all(_alive(pid) for pid in pids)
        # a renderer ignores SIGINT once its parent-death signal is armed: wait for that
        deadline = time.monotonic() + 30
        while not all(_ignores_sigint(pid) for pid in pids) and time.monotonic() < deadline:
            time.sleep(0.02)
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait()
        deadline = time.monotonic() + 10
        while any(_alive(pid) for pid in pids) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not any(_alive(pid) for pid in pids), "a renderer outlived its killed parent"
    finally:
        if parent.poll() is None:
            parent.kill()
            parent.wait()


def test_plot_run_refuses_an_unknown_figure(tmp_path):
    with pytest.raises(ValueError, match="unknown plot x.png"):
        plot_run({"time": np.zeros(2)}, tmp_path, figures=("x.png",))
    assert json.dumps(list(PLOT_FILES))   # the names a renderer request carries
