"""PNG plots of a run: trajectories, wheel speeds, scheduled gains, localizer fixes."""

from pathlib import Path

import numpy as np

__all__ = ["PLOT_FILES", "plot_run"]

# Every file plot_run may write: a new run removes an older run's copies before it starts.
PLOT_FILES = ("trajectories.png", "wheel_speeds.png", "gains.png", "localizer.png")


def _figure():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _has(data, *names):
    return all(name in data for name in names)


def plot_run(data, out_dir):
    """Write the standard plots of a run and return their paths.

    Parameters
    ----------
    data : dict of str to array
        Recorded columns (``time`` and ``instance.port``).
    out_dir : path-like
        Folder for the PNG files.
    """
    plt = _figure()
    out_dir = Path(out_dir)
    written = []
    t = data["time"]

    if _has(data, "plant.x", "plant.y", "source.x", "source.y"):
        fig, ax = plt.subplots(figsize=(6, 7))
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
        ax.legend()
        ax.set_title("Trajectories in the plane")
        written.append(_save(fig, out_dir / "trajectories.png"))

    wheels = [("left", "controller_left"), ("right", "controller_right")]
    if all(_has(data, f"plant.wheel_speed_{side}") for side, _ in wheels):
        fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
        for ax, (side, controller) in zip(axes, wheels):
            ax.plot(t, data[f"plant.wheel_speed_{side}"], label="measured (encoder)", lw=1)
            if f"plant.rim_speed_{side}" in data:
                ax.plot(t, data[f"plant.rim_speed_{side}"], label="true", lw=1, alpha=0.7)
            if f"planner.v_ref_{side}" in data:
                ax.plot(t, data[f"planner.v_ref_{side}"], "k--", label="reference", lw=1)
            ax.set_ylabel(f"{side} wheel [m/s]")
            ax.grid(True, alpha=0.3)
            ax.legend(loc="best", fontsize=8)
        axes[-1].set_xlabel("time [s]")
        fig.suptitle("Wheel speeds and their references")
        written.append(_save(fig, out_dir / "wheel_speeds.png"))

    if all(_has(data, f"{c}.kp", f"{c}.kd") for _, c in wheels):
        fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
        for ax, gain in zip(axes, ("kp", "kd")):
            for side, controller in wheels:
                ax.plot(t, data[f"{controller}.{gain}"], label=side, lw=1)
            ax.set_ylabel(gain)
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8)
        axes[-1].set_xlabel("time [s]")
        fig.suptitle("Scheduled controller gains")
        written.append(_save(fig, out_dir / "gains.png"))

    if _has(data, "localizer.distance", "localizer.bearing", "plant.x", "source.x"):
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
            ax.legend(fontsize=8)
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

    from orchestrator.outputs import atomic_write_bytes

    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    encoded = io.BytesIO()
    fig.savefig(encoded, dpi=110, format="png")
    atomic_write_bytes(path, encoded.getvalue(), fsync=False)
    import matplotlib.pyplot as plt

    plt.close(fig)
    return path
