"""One PNG per fault run: the paths, the distance with the fixes, the speeds and slip."""

import math
from pathlib import Path

import numpy as np

__all__ = ["plot_fault_run"]


def plot_fault_run(data, scenario, path, dpi=80):
    """Write the figure of a fault run and return its path.

    Three panels, the faults' active stretches shaded: the robot's and the source's paths
    (the robot's positions while a fault is active drawn in red); the true distance with the
    localizer's valid fixes and ``stop_distance``; body speed, both rim speeds and the larger
    |slip ratio|.

    Parameters
    ----------
    data : dict of str to numpy.ndarray
        The run's columns.
    scenario : Scenario
        The run's scenario (its faults and name).
    path : path-like
        The PNG file.
    """
    from matplotlib.patches import Rectangle

    from orchestrator.report.matplotlib_agg import pyplot

    plt = pyplot()
    t = data["time"]
    active = np.zeros(t.shape, dtype=bool)
    for _, fault in scenario.faults:
        active |= (t >= fault.start) & (t < fault.end)
    fig, (paths, distance, speeds) = plt.subplots(
        1, 3, figsize=(12, 3.6), gridspec_kw={"width_ratios": [1, 2, 2]})

    paths.plot(data["source.x"], data["source.y"], color="tab:orange", lw=2, label="source")
    paths.plot(data["plant.x"], data["plant.y"], color="tab:blue", lw=1.5, label="robot")
    paths.plot(np.where(active, data["plant.x"], np.nan), np.where(active, data["plant.y"], np.nan),
               color="tab:red", lw=2.5, label="robot, fault on")
    for _, fault in scenario.faults:
        if fault.kind == "reflecting_wall":
            paths.axvline(fault.magnitude, color="k", lw=3, label="wall")
        if fault.region:
            x0, y0, x1, y1 = fault.region
            paths.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, alpha=0.2,
                                      color="tab:cyan", label="mu patch"))
    paths.set_aspect("equal", adjustable="datalim")
    paths.set_xlabel("x [m]")
    paths.set_ylabel("y [m]")
    paths.legend(fontsize=7, loc="lower right")
    paths.grid(True, alpha=0.3)

    def shade(ax):
        for _, fault in scenario.faults:
            end = min(fault.end, t[-1]) if not math.isinf(fault.end) else t[-1]
            ax.axvspan(fault.start, end, color="tab:red", alpha=0.12)

    true = np.hypot(data["plant.x"] - data["source.x"], data["plant.y"] - data["source.y"])
    distance.plot(t, true, color="k", lw=1.5, label="true distance")
    if "localizer.valid" in data and "localizer.distance" in data:
        valid = data["localizer.valid"] > 0.5
        distance.plot(t[valid], data["localizer.distance"][valid], ".", ms=2, color="tab:green",
                      label="valid fix (held)")
    stop = float(scenario.parameters.get("planner.stop_distance", 0.5))
    distance.axhline(stop, color="tab:gray", ls="--", lw=1, label="stop_distance")
    distance.axhspan(stop - 0.3, stop + 0.3, color="tab:gray", alpha=0.1)
    shade(distance)
    distance.set_xlabel("time [s]")
    distance.set_ylabel("distance [m]")
    distance.legend(fontsize=7)
    distance.grid(True, alpha=0.3)

    speeds.plot(t, data["plant.speed"], color="k", lw=1.5, label="body speed")
    for side, colour in (("left", "tab:blue"), ("right", "tab:purple")):
        column = f"plant.rim_speed_{side}"
        if column in data:
            speeds.plot(t, data[column], color=colour, lw=0.8, label=f"rim {side}")
    v_max = float(scenario.parameters.get("planner.v_max", 0.4))
    speeds.axhline(1.05 * v_max, color="tab:red", ls=":", lw=1, label="1.05 v_max")
    if "plant.slip_left" in data:
        slip = np.maximum(np.abs(data["plant.slip_left"]), np.abs(data["plant.slip_right"]))
        speeds.plot(t, slip, color="tab:brown", lw=0.8, label="max |slip|")
    shade(speeds)
    speeds.set_xlabel("time [s]")
    speeds.set_ylabel("m/s (slip: 1)")
    speeds.legend(fontsize=7, ncol=2)
    speeds.grid(True, alpha=0.3)

    kinds = ", ".join(sorted({fault.kind for _, fault in scenario.faults}))
    fig.suptitle(f"{scenario.name}: {kinds} (shaded: fault active)", fontsize=10)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
