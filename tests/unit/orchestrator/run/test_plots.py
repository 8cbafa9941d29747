"""The run plots' drawn elements, read from the matplotlib artists before anything is saved."""

import numpy as np
import pytest
from matplotlib.patches import Circle, Rectangle

from orchestrator.run.plots import PLOT_FILES, PlotContext, break_jumps, draw_figures, fault_spans

CONTEXT = PlotContext("dynamic_case2", "pid", 0.5)


def _run(jump_at=None, fault=None):
    """A 4 s run at 20 ms: the robot drives +y at 0.2 m/s, the source sits at (1, 2) and, if
    ``jump_at``, jumps to (-1, 3); ``fault`` = (start, end) of an active localizer fault."""
    t = np.round(np.arange(0, 4.0001, 0.02), 10)
    source_x = np.where(t >= jump_at, -1.0, 1.0) if jump_at else np.ones_like(t)
    source_y = np.where(t >= jump_at, 3.0, 2.0) if jump_at else 2 * np.ones_like(t)
    data = {"time": t, "plant.x": np.zeros_like(t), "plant.y": 0.2 * t,
            "plant.heading": np.full_like(t, np.pi / 2), "source.x": source_x,
            "source.y": source_y, "plant.odom_x": 0.01 * t, "plant.odom_y": 0.19 * t,
            "localizer.distance": np.hypot(source_x, source_y - 0.2 * t),
            "localizer.bearing": np.zeros_like(t), "localizer.valid": np.ones_like(t)}
    for side in ("left", "right"):
        data[f"plant.wheel_speed_{side}"] = np.round(0.2 * np.ones_like(t) / 0.026) * 0.026
        data[f"plant.rim_speed_{side}"] = 0.2 * np.ones_like(t)
        data[f"planner.v_ref_{side}"] = 0.2 * np.ones_like(t)
        data[f"controller_{side}.kp"] = 3 + t / 4
        data[f"controller_{side}.kd"] = 1 - t / 8
    if fault:
        data["localizer.faults_active"] = ((t >= fault[0]) & (t < fault[1])).astype(float)
    return data


def _spans(ax):
    """``(x0, x1)`` of the shaded vertical spans of an axes."""
    return [(round(p.get_x(), 6), round(p.get_x() + p.get_width(), 6)) for p in ax.patches
            if isinstance(p, Rectangle) and p.get_label() in ("fault active", "")
            and p.get_height() == 1.0]


def test_every_figure_is_titled_with_the_scenario_and_the_controller():
    figures = draw_figures(_run(), context=CONTEXT)
    assert list(figures) == list(PLOT_FILES)
    for name, fig in figures.items():
        title = fig._suptitle.get_text()
        assert "scenario dynamic_case2" in title and "controller pid" in title, name


def test_the_stop_circle_is_drawn_around_the_source_at_the_end():
    ax = draw_figures(_run(jump_at=2.0), ["trajectories.png"], CONTEXT)[
        "trajectories.png"].axes[0]
    circles = [p for p in ax.patches if isinstance(p, Circle)]
    assert len(circles) == 1
    assert circles[0].center == (-1.0, 3.0) and circles[0].radius == 0.5
    assert not draw_figures(_run(), ["trajectories.png"], PlotContext("x", "pid", None))[
        "trajectories.png"].axes[0].patches


def test_a_jump_of_the_source_is_not_drawn_as_motion():
    ax = draw_figures(_run(jump_at=2.0), ["trajectories.png"], CONTEXT)[
        "trajectories.png"].axes[0]
    source = next(line for line in ax.lines if line.get_label() == "source (true)")
    x = source.get_xdata()
    gap = np.flatnonzero(np.isnan(x))
    assert len(gap) == 1 and x[gap[0] - 1] == 1.0 and x[gap[0] + 1] == -1.0
    before = next(line for line in ax.lines if line.get_label() == "source before it jumped")
    assert list(before.get_xydata()[0]) == [1.0, 2.0]


def test_break_jumps_against_hand_made_tracks():
    t = np.array([0.0, 0.02, 0.04, 0.06])
    x, y = break_jumps(np.array([0.0, 0.002, 0.5, 0.502]), np.zeros(4), t)
    assert np.array_equal(np.isnan(x), [False, False, True, False, False])
    x, _ = break_jumps(np.array([0.0, 0.006, 0.012]), np.zeros(3), t[:3])   # 0.3 m/s: driven
    assert not np.isnan(x).any()


def test_fault_windows_are_shaded_on_every_time_axis():
    data = _run(fault=(1.0, 2.5))
    assert fault_spans(data) == [(1.0, 2.5)]
    figures = draw_figures(data, context=CONTEXT)
    for name in ("wheel_speeds.png", "gains.png", "localizer.png"):
        for ax in figures[name].axes:
            assert _spans(ax) == [(1.0, 2.5)], name
    assert all(not _spans(ax) for ax in draw_figures(_run(), context=CONTEXT)[
        "wheel_speeds.png"].axes)


def test_reference_and_true_speed_are_drawn_above_the_encoder_steps():
    ax = draw_figures(_run(), ["wheel_speeds.png"], CONTEXT)["wheel_speeds.png"].axes[0]
    lines = {line.get_label(): line for line in ax.lines}
    encoder = lines["measured (encoder)"]
    assert encoder.get_drawstyle() == "steps-post"
    assert lines["true rim speed"].get_zorder() > encoder.get_zorder()
    assert lines["reference"].get_zorder() > encoder.get_zorder()
    assert lines["reference"].get_linewidth() > encoder.get_linewidth()


def test_gains_are_drawn_for_any_controller_and_legends_sit_off_the_data():
    figures = draw_figures(_run(), context=CONTEXT)
    assert "gains.png" in figures
    for name, fig in figures.items():
        fig.canvas.draw()
        for ax in fig.axes:
            legend = ax.get_legend()
            assert legend is not None, name
            box, frame = legend.get_window_extent(), ax.get_window_extent()
            assert box.x0 >= frame.x1, f"{name}: legend over the axes"


def test_the_odometry_stays_visible_above_the_true_path():
    ax = draw_figures(_run(), ["trajectories.png"], CONTEXT)["trajectories.png"].axes[0]
    lines = {line.get_label(): line for line in ax.lines}
    odometry, true = lines["robot (odometry)"], lines["robot (true)"]
    assert odometry.get_zorder() > true.get_zorder()
    assert odometry.get_color() != true.get_color()


def test_an_unknown_figure_is_refused():
    with pytest.raises(ValueError, match="unknown plot x.png; plots are trajectories.png"):
        draw_figures(_run(), ["x.png"])
