"""Plot helpers shared by the study's figures: traces over runs, bands, saving.

A time series over a cell's runs is drawn as its mean with the 95 % interval of the mean
(the same Student-t interval as the tables), shaded; trajectories as every run, thin.
"""

import numpy as np
from scipy import stats

from orchestrator.report.matplotlib_agg import pyplot

from .statistics import CONFIDENCE

__all__ = ["traces", "band", "paths", "save", "COLOURS"]

COLOURS = {"pid": "tab:red", "cpid": "tab:red", "fgs_pd": "tab:blue",
           "fgs_pd_paper": "tab:purple", "pd_median": "tab:gray", "curvature": "tab:blue",
           "rotate_then_go": "tab:orange", "source": "tab:green", "ideal": "k"}


def traces(runs, column, transform=None):
    """``(time, matrix)`` of a column over the finished runs, cut to the shortest run.

    ``transform(run)`` may compute the series instead of reading ``column``.
    """
    series = [(run.data["time"], transform(run) if transform else run.data[column])
              for run in runs if run.ok]
    if not series:
        return np.zeros(0), np.zeros((0, 0))
    n = min(len(t) for t, _ in series)
    return series[0][0][:n], np.vstack([s[:n] for _, s in series])


def band(ax, time, matrix, label, colour, linestyle="-"):
    """Mean line and shaded 95 % interval of the mean over the rows of ``matrix``."""
    if matrix.size == 0:
        return
    mean = matrix.mean(axis=0)
    ax.plot(time, mean, color=colour, linestyle=linestyle, lw=1.4,
            label=f"{label} (mean of {len(matrix)})")
    if len(matrix) > 1:
        half = (stats.t.ppf(0.5 + CONFIDENCE / 2, len(matrix) - 1)
                * matrix.std(axis=0, ddof=1) / np.sqrt(len(matrix)))
        ax.fill_between(time, mean - half, mean + half, color=colour, alpha=0.25, lw=0)


def paths(ax, runs, colour, label, alpha=0.35, source=False):
    """Every run's true path (thin), the first one labelled."""
    first = True
    for run in runs:
        if not run.ok:
            continue
        xy = run.source_xy() if source else run.xy()
        count = sum(r.ok for r in runs)
        ax.plot(*xy.T, color=colour, lw=0.8, alpha=alpha,
                label=(f"{label} ({count} runs)" if count > 1 else label) if first else None)
        first = False


def save(fig, path):
    """Lay out, write the PNG and close the figure; returns the path."""
    plt = pyplot()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
