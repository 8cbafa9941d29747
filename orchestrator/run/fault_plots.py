"""One PNG per fault run: the paths, the distance with the fixes, the speeds and slip."""

import math
from pathlib import Path

import numpy as np

from orchestrator.system.sonotrack import SONOTRACK

__all__ = ["plot_fault_run"]


def plot_fault_run(data, scenario, path, dpi=80):
    """Write the figure of a fault run and return its path.

    Three panels, the faults' active stretches shaded, legends under the panels (off the
    data): the robot's and the source's paths (the robot's positions while a fault is active
    drawn in red, the stop distance as a circle around the source's last position); the true
    distance with the localizer's valid fixes and ``stop_distance``; body speed, both rim
    speeds and the larger |slip ratio|. The title names the scenario, the faults and the
    wheel controllers' law.

    Parameters
    ----------
    data : dict of str to numpy.ndarray
        The run's columns.
    scenario : Scenario
        The run's scenario (its faults and name).
    path : path-like
        The PNG file.
    """
    from matplotlib.patches import Circle, Rectangle

    from orchestrator.report.matplotlib_agg import pyplot

    plt = pyplot()
    t = data["time"]
    active = np.zeros(t.shape, dtype=bool)
    for _, fault in scenario.faults:
        active |= (t >= fault.start) & (t < fault.end)
    fig, (paths, distance, speeds) = plt.subplots(
        1, 3, figsize=(12, 4.6), gridspec_kw={"width_ratios": [1, 2, 2]})
    (rx, ry), (sx, sy) = SONOTRACK.robot_position, SONOTRACK.source_position
    stop = float(scenario.parameters.get(
        f"{SONOTRACK.planner}.{SONOTRACK.stop_distance_parameter}", 0.5))
    below = {"loc": "upper center", "bbox_to_anchor": (0.5, -0.2), "fontsize": 7}

    paths.plot(data[sx], data[sy], color="tab:orange", lw=2, label="source")
    paths.plot(data[rx], data[ry], color="tab:blue", lw=1.5, label="robot")
    paths.plot(np.where(active, data[rx], np.nan), np.where(active, data[ry], np.nan),
               color="tab:red", lw=2.5, label="robot, fault on")
    paths.add_patch(Circle((float(data[sx][-1]), float(data[sy][-1])), stop, fill=False,
                           ls="--", color="tab:gray", label="stop distance"))
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
    paths.legend(ncol=2, **below)
    paths.grid(True, alpha=0.3)

    def shade(ax):
        for _, fault in scenario.faults:
            end = min(fault.end, t[-1]) if not math.isinf(fault.end) else t[-1]
            ax.axvspan(fault.start, end, color="tab:red", alpha=0.12)

    true = np.hypot(data[rx] - data[sx], data[ry] - data[sy])
    distance.plot(t, true, color="k", lw=1.5, label="true distance")
    fix_distance, _, fix_valid = SONOTRACK.fix_columns
    if fix_valid in data and fix_distance in data:
        valid = data[fix_valid] > 0.5
        distance.plot(t[valid], data[fix_distance][valid], ".", ms=2, color="tab:green",
                      label="valid fix (held)")
    distance.axhline(stop, color="tab:gray", ls="--", lw=1, label="stop_distance")
    distance.axhspan(stop - 0.3, stop + 0.3, color="tab:gray", alpha=0.1)
    shade(distance)
    distance.set_xlabel("time [s]")
    distance.set_ylabel("distance [m]")
    distance.legend(ncol=3, **below)
    distance.grid(True, alpha=0.3)

    speeds.plot(t, data[SONOTRACK.body_speed], color="k", lw=1.5, label="body speed")
    for side, colour in zip(SONOTRACK.sides, ("tab:blue", "tab:purple")):
        column = SONOTRACK.rim_speed(side)
        if column in data:
            speeds.plot(t, data[column], color=colour, lw=0.8, label=f"rim {side}")
    v_max = float(scenario.parameters.get("planner.v_max", 0.4))
    speeds.axhline(1.05 * v_max, color="tab:red", ls=":", lw=1, label="1.05 v_max")
    left, right = SONOTRACK.wheel_slips
    if left in data:
        slip = np.maximum(np.abs(data[left]), np.abs(data[right]))
        speeds.plot(t, slip, color="tab:brown", lw=0.8, label="max |slip|")
    shade(speeds)
    speeds.set_xlabel("time [s]")
    speeds.set_ylabel("m/s (slip: 1)")
    speeds.legend(ncol=3, **below)
    speeds.grid(True, alpha=0.3)

    kinds = ", ".join(sorted({fault.kind for _, fault in scenario.faults}))
    law = scenario.parameters.get(f"{SONOTRACK.controller('left')}."
                                  f"{SONOTRACK.controller_mode_parameter}", "fgs_pd (default)")
    fig.suptitle(f"scenario {scenario.name}, controller {law}: {kinds} "
                 "(shaded: fault active)", fontsize=10)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi, bbox_inches="tight")   # the legends under the panels too
    plt.close(fig)
    return path
