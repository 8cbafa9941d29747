"""Two or more finished runs side by side: ``sonotrack compare RUN_DIR...``.

:func:`compare_runs` reads each run folder's ``summary.json`` and ``results.csv`` (thinned
for drawing) and writes, into one folder:

- ``comparison_trajectories.png``: every run's robot path over its source's path, one colour
  per run, the source's jumps not drawn as motion;
- ``comparison_wheel_speeds.png``: both wheels' true rim speeds (the encoder's measurement
  where the true speed was not recorded), one colour per run;
- ``comparison.md``: the table of the runs' summary figures (one column per run) and the two
  figures with their captions.

A folder that is not a run folder, or whose run did not finish, is refused with one line
naming it; nothing is written then.
"""

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from components.common.errors import ConfigError
from orchestrator.system.sonotrack import SONOTRACK

__all__ = ["COMPARED_FIELDS", "Comparison", "compare_runs", "comparison_rows"]

# The rows of the table, in order: what the run was, then its figures (docs/metrics.md).
COMPARED_FIELDS = ("scenario", "controller", "seed", "stop_distance_m",
                   "final_distance_to_source_m", "min_distance_to_source_m",
                   "final_position_error_m", "path_rmse_m", "sim_time_s", "wall_time_s",
                   "realtime_factor")
_PLOT_ROWS = 2000
_FIGURE_NAMES = ("comparison_trajectories.png", "comparison_wheel_speeds.png")


@dataclass
class Comparison:
    """What :func:`compare_runs` wrote (absolute paths) and the table it holds."""

    labels: list
    rows: list
    markdown: Path = None
    figures: list = field(default_factory=list)

    def text(self):
        """The table as aligned text lines (one column per run), as the CLI prints it."""
        width = max(len(row[0]) for row in self.rows)
        lines = [f"  {'':{width}s}  " + "  ".join(f"{label:>12s}" for label in self.labels)]
        for name, *values in self.rows:
            lines.append(f"  {name:{width}s}  " + "  ".join(
                f"{value:>12.4g}" if isinstance(value, float) else f"{str(value):>12s}"
                for value in values))
        return "\n".join(lines)


def _labels(run_dirs):
    """Each folder's name, or its last two parts where names repeat."""
    names = [p.name for p in run_dirs]
    if len(set(names)) == len(names):
        return names
    return ["/".join(p.parts[-2:]) for p in run_dirs]


def _load(run_dir):
    from orchestrator.run.folder import RESULTS_NAME, read_summary
    from orchestrator.run.results import read_results

    if not run_dir.is_dir():
        raise ConfigError(f"{run_dir}: no such run folder (give folders written by "
                          "`sonotrack run`, e.g. runs/s_curve)")
    summary = read_summary(run_dir)
    if summary is None:
        raise ConfigError(f"{run_dir}: no readable summary.json; not a run folder")
    if summary.get("status") != "ok":
        raise ConfigError(f"{run_dir}: summary.json status is {summary.get('status')!r}, not "
                          "'ok'; compare finished runs only")
    results = run_dir / RESULTS_NAME
    if not results.is_file():
        raise ConfigError(f"{run_dir}: no {RESULTS_NAME} beside its summary.json")
    return summary, read_results(results, max_rows=_PLOT_ROWS)


def comparison_rows(summaries, fields=COMPARED_FIELDS):
    """``[[field, value of run 1, value of run 2, ...], ...]`` for the fields any run has."""
    return [[name] + [summary.get(name) for summary in summaries] for name in fields
            if any(name in summary for summary in summaries)]


def _colours(count):
    from matplotlib import colormaps

    palette = colormaps["tab10"]
    return [palette(i % 10) for i in range(count)]


def _trajectories(figures, runs, labels):
    from orchestrator.run.plots import break_jumps

    fig, ax = figures.subplots(figsize=(7.5, 6.5), margins={"left": 0.1, "right": 0.66,
                                                            "bottom": 0.09, "top": 0.9})
    (rx, ry), (sx, sy) = SONOTRACK.robot_position, SONOTRACK.source_position
    for (summary, data), label, colour in zip(runs, labels, _colours(len(runs))):
        if all(c in data for c in (rx, ry)):
            ax.plot(data[rx], data[ry], lw=2, color=colour, label=f"{label}: robot")
        if all(c in data for c in (sx, sy)):
            ax.plot(*break_jumps(data[sx], data[sy], data["time"]), ":", lw=1.5,
                    color=colour, label=f"{label}: source")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    fig.suptitle(f"Trajectories of {len(runs)} runs (solid: robot, dotted: source)")
    return fig


def _wheel_speeds(figures, runs, labels):
    fig, axes = figures.subplots(2, 1, figsize=(9, 6), sharex=True,
                                 margins={"left": 0.09, "right": 0.72, "bottom": 0.1,
                                          "top": 0.9, "hspace": 0.12})
    for ax, side in zip(axes, SONOTRACK.sides):
        for (summary, data), label, colour in zip(runs, labels, _colours(len(runs))):
            column = next((c for c in (SONOTRACK.rim_speed(side), SONOTRACK.wheel_speed(side))
                           if c in data), None)
            if column is not None:
                kind = "true" if column == SONOTRACK.rim_speed(side) else "encoder"
                ax.plot(data["time"], data[column], lw=1.2, color=colour,
                        label=f"{label} ({kind})")
        ax.set_ylabel(f"{side} wheel [m/s]")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(f"Wheel speeds of {len(runs)} runs")
    return fig


def compare_runs(run_dirs, out_dir):
    """Compare finished runs: two overlaid figures and a Markdown table of their figures.

    Parameters
    ----------
    run_dirs : sequence of path-like
        Run folders (each with ``summary.json`` saying ``ok`` and ``results.csv``); two or more.
    out_dir : path-like
        Folder for ``comparison.md`` and the two PNGs (created).

    Returns
    -------
    Comparison

    Raises
    ------
    ConfigError
        Fewer than two folders, a folder given twice, or one that is not a finished run
        (one line naming it), before anything is written.
    """
    from orchestrator.report.document import Document
    from orchestrator.report.markdown import write_markdown
    from orchestrator.run.plots import _Figures, _save

    run_dirs = [Path(p).resolve() for p in run_dirs]
    if len(run_dirs) < 2:
        raise ConfigError(f"compare needs two or more run folders, got {len(run_dirs)}")
    if len(set(run_dirs)) != len(run_dirs):
        twice = next(p for p in run_dirs if run_dirs.count(p) > 1)
        raise ConfigError(f"{twice}: given twice; give each run folder once")
    runs = [_load(p) for p in run_dirs]
    labels = _labels(run_dirs)
    out_dir = Path(out_dir).resolve()
    figures = _Figures()
    paths = [_save(draw(figures, runs, labels), out_dir / name)
             for draw, name in zip((_trajectories, _wheel_speeds), _FIGURE_NAMES)]
    rows = comparison_rows([summary for summary, _ in runs])
    document = Document(f"Comparison of {len(runs)} runs",
                        intro="Figures defined in docs/metrics.md of the sonotrack repository.")
    document.section("Summary figures").table(["figure"] + labels, rows)
    section = document.section("Figures")
    section.figure(_FIGURE_NAMES[0], "Robot paths (solid) over their sources' paths (dotted), "
                                     "one colour per run.")
    section.figure(_FIGURE_NAMES[1], "Wheel speeds, true rim speed where recorded (else the "
                                     "encoder's), one colour per run.")
    markdown = write_markdown(document, out_dir / "comparison.md")
    return Comparison(labels, rows, markdown.resolve(), paths)
