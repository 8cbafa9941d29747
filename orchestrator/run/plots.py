"""PNG plots of a run: trajectories, wheel speeds, scheduled gains, localizer fixes.

Drawing stays cheap because each figure is laid out once: figures are made with
:class:`matplotlib.figure.Figure` on an Agg canvas (no pyplot and its global state), with fixed
margins instead of ``tight_layout`` (which draws a figure to measure it before it is drawn
again to be saved) and legends at fixed corners (``loc="best"`` searches every data point).
matplotlib is imported only when a plot is drawn, so a run without plots never pays for it.
"""

from pathlib import Path

import numpy as np

__all__ = ["PLOT_FILES", "plot_run"]

# Every file plot_run may write: a new run removes an older run's copies before it starts.
PLOT_FILES = ("trajectories.png", "wheel_speeds.png", "gains.png", "localizer.png")


# Margins (fractions of the figure) that fit the labels of every figure below at its size;
# fixed so that a figure is drawn once, when it is saved.
_MARGINS = {"left": 0.11, "right": 0.97, "bottom": 0.1, "top": 0.9, "hspace": 0.12}


class _Figures:
    """Makes figures on an Agg canvas without pyplot."""

    def __init__(self):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        from orchestrator.report.matplotlib_agg import ensure_bundled_fonts

        ensure_bundled_fonts()
        self._canvas = FigureCanvasAgg
        self._figure = Figure

    def subplots(self, rows=1, columns=1, figsize=None, sharex=False, margins=None):
        fig = self._figure(figsize=figsize)
        self._canvas(fig)
        axes = fig.subplots(rows, columns, sharex=sharex)
        fig.subplots_adjust(**(margins or _MARGINS))
        return fig, axes


def _has(data, *names):
    return all(name in data for name in names)


def plot_run(data, out_dir, figures=PLOT_FILES):
    """Write the standard plots of a run and return their paths.

    Parameters
    ----------
    data : dict of str to array
        Recorded columns (``time`` and ``instance.port``).
    out_dir : path-like
        Folder for the PNG files.
    figures : sequence of str
        Which of :data:`PLOT_FILES` to draw (default all); a figure whose columns were not
        recorded is left out.
    """
    unknown = sorted(set(figures) - set(PLOT_FILES))
    if unknown:
        raise ValueError(f"unknown plot {', '.join(unknown)}; plots are {', '.join(PLOT_FILES)}")
    plt = _Figures()
    out_dir = Path(out_dir)
    written = []
    t = data["time"]

    if "trajectories.png" in figures and _has(data, "plant.x", "plant.y", "source.x", "source.y"):
        fig, ax = plt.subplots(figsize=(6, 7), margins={"left": 0.13, "right": 0.96,
                                                        "bottom": 0.08, "top": 0.94})
        ax.plot(data["source.x"], data["source.y"], label="source (true)", lw=2, color="tab:orange")
        ax.plot(data["plant.x"], data["plant.y"], label="robot (true)", lw=2, color="tab:blue")
        if _has(data, "plant.odom_x", "plant.odom_y"):
            ax.plot(data["plant.odom_x"], data["plant.odom_y"], "--", label="robot (odometry)",
                    color="tab:blue", alpha=0.6)
        ax.plot(data["plant.x"][:1], data["plant.y"][:1], "o", color="tab:blue")
        ax.plot(data["source.x"][:1], data["source.y"][:1], "o", color="tab:orange")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper left")
        ax.set_title("Trajectories in the plane")
        written.append(_save(fig, out_dir / "trajectories.png"))

    wheels = [("left", "controller_left"), ("right", "controller_right")]
    if "wheel_speeds.png" in figures and all(_has(data, f"plant.wheel_speed_{side}")
                                             for side, _ in wheels):
        fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
        for ax, (side, controller) in zip(axes, wheels):
            ax.plot(t, data[f"plant.wheel_speed_{side}"], label="measured (encoder)", lw=1)
            if f"plant.rim_speed_{side}" in data:
                ax.plot(t, data[f"plant.rim_speed_{side}"], label="true", lw=1, alpha=0.7)
            if f"planner.v_ref_{side}" in data:
                ax.plot(t, data[f"planner.v_ref_{side}"], "k--", label="reference", lw=1)
            ax.set_ylabel(f"{side} wheel [m/s]")
            ax.grid(True, alpha=0.3)
            ax.legend(loc="lower right", fontsize=8)
        axes[-1].set_xlabel("time [s]")
        fig.suptitle("Wheel speeds and their references")
        written.append(_save(fig, out_dir / "wheel_speeds.png"))

    if "gains.png" in figures and all(_has(data, f"{c}.kp", f"{c}.kd") for _, c in wheels):
        fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
        for ax, gain in zip(axes, ("kp", "kd")):
            for side, controller in wheels:
                ax.plot(t, data[f"{controller}.{gain}"], label=side, lw=1)
            ax.set_ylabel(gain)
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper right", fontsize=8)
        axes[-1].set_xlabel("time [s]")
        fig.suptitle("Scheduled controller gains")
        written.append(_save(fig, out_dir / "gains.png"))

    if "localizer.png" in figures and _has(data, "localizer.distance", "localizer.bearing",
                                           "plant.x", "source.x"):
        true_distance, true_bearing = _true_fix(data)
        fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
        valid = data.get("localizer.valid", np.ones_like(t)) > 0.5
        axes[0].plot(t, true_distance, label="true", lw=1)
        axes[0].plot(t[valid], data["localizer.distance"][valid], ".", ms=2, label="fix")
        axes[0].set_ylabel("distance [m]")
        axes[1].plot(t, np.degrees(true_bearing), label="true", lw=1)
        axes[1].plot(t[valid], np.degrees(data["localizer.bearing"][valid]), ".", ms=2,
                     label="fix")
        axes[1].set_ylabel("bearing [deg]")
        axes[1].set_xlabel("time [s]")
        for ax in axes:
            ax.grid(True, alpha=0.3)
            ax.legend(loc="upper right", fontsize=8)
        fig.suptitle("Localizer fixes against the truth (robot centre to source)")
        written.append(_save(fig, out_dir / "localizer.png"))
    return written


def _true_fix(data):
    dx = data["source.x"] - data["plant.x"]
    dy = data["source.y"] - data["plant.y"]
    bearing = np.arctan2(dy, dx) - data["plant.heading"]
    return np.hypot(dx, dy), (bearing + np.pi) % (2 * np.pi) - np.pi


def _save(fig, path):
    import io

    from orchestrator.run.folder import atomic_write_bytes

    path.parent.mkdir(parents=True, exist_ok=True)
    encoded = io.BytesIO()
    # zlib level 1: a third of the default level's encoding time for a slightly larger file
    fig.savefig(encoded, dpi=110, format="png", pil_kwargs={"compress_level": 1})
    atomic_write_bytes(path, encoded.getvalue(), fsync=False)
    return path
