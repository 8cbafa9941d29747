"""Plot the scheduled gains Kp and Kd over (e, de) as a PNG.

Both defuzzifications side by side (weighted average of Eqs. 51-52, the default, and the
Mamdani centre of gravity), gains by Eq. (50) with the paper's ranges on our sign convention
(kp 3..4, kd 0.3..2 on e = v_ref - v_meas). Run: ``.venv/bin/python benchmarks/gain_surface.py``.
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from components.control import DEFAULTS, FuzzyGainScheduler, scheduled_gain  # noqa: E402


def surfaces(method, n=121):
    """Return e [m/s], de [m/s^2] grids and the Kp, Kd surfaces for one method."""
    engine = FuzzyGainScheduler(DEFAULTS["e_range"], DEFAULTS["de_range"], method=method)
    e = np.linspace(-DEFAULTS["e_range"], DEFAULTS["e_range"], n)
    de = np.linspace(-DEFAULTS["de_range"], DEFAULTS["de_range"], n)
    kp = np.empty((n, n))
    kd = np.empty((n, n))
    for i, de_i in enumerate(de):
        for j, e_j in enumerate(e):
            kp_n, kd_n = engine.evaluate(e_j, de_i)
            kp[i, j] = scheduled_gain(kp_n, DEFAULTS["kp_min"], DEFAULTS["kp_max"])
            kd[i, j] = scheduled_gain(kd_n, DEFAULTS["kd_min"], DEFAULTS["kd_max"])
    return e, de, kp, kd


def main(out=ROOT / "benchmarks" / "results" / "gain_surface.png"):
    fig = plt.figure(figsize=(11, 9))
    for row, method in enumerate(("weighted", "mamdani")):
        e, de, kp, kd = surfaces(method)
        grid_e, grid_de = np.meshgrid(e, de)
        for col, (name, z, bounds) in enumerate(
                (("Kp", kp, ("kp_min", "kp_max")), ("Kd", kd, ("kd_min", "kd_max")))):
            ax = fig.add_subplot(2, 2, 2 * row + col + 1, projection="3d")
            ax.plot_surface(grid_e, grid_de, z, cmap="viridis", linewidth=0)
            ax.set_xlabel("e [m/s]")
            ax.set_ylabel("de [m/s$^2$]")
            ax.set_zlabel(name)
            ax.set_zlim(DEFAULTS[bounds[0]], DEFAULTS[bounds[1]])
            ax.set_title(f"{name}, {method}")
    fig.suptitle("FGS-PD gains, e = v_ref - v_meas (Zhao-Tomizuka-Isaka rules)")
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
