"""Per-cell figures of a study, computed once and shared by the tables, claims and plots."""

import math

import numpy as np

from orchestrator.reproduce.geometry import tangent_arc_path

from .experiments import TABLE13_TARGET
from .following import following_figures
from .measures import arrival_figures, fix_figures, tracking_figures, wheel_profile
from .statistics import evidence, paired_difference

__all__ = ["START", "START_HEADING", "CASE_TARGETS", "Analysis", "reference_path"]

START, START_HEADING = (0.0, 0.0), 0.5 * math.pi
# The scenarios' own targets (static_case1.toml, dynamic_case2.toml).
CASE_TARGETS = {"static": [(1.41421356, 1.41421356)],
                "dynamic": [(0.70710678, 0.70710678), (1.41421356, 1.41421356)]}
SEC62_STOP_DISTANCE = 0.5       # m, the shipped scenarios' planner stop distance
# Vertices per ideal arc: arcs of R >= 0.707 m and <= 2.4 m length give chords under 6 mm and
# a chord error (sagitta) under 7e-6 m, far below the mm-level path errors measured.
ARC_POINTS = 401


def reference_path(labels):
    """The ideal path of a Tables 1-3 or 8-9 cell (from its labels)."""
    if "speed" in labels:
        if labels["mode"] == "rotate_then_go":
            return np.array([START, TABLE13_TARGET])
        return tangent_arc_path(START, START_HEADING, [TABLE13_TARGET], ARC_POINTS)
    return tangent_arc_path(START, START_HEADING, CASE_TARGETS[labels["case"]], ARC_POINTS)


class Analysis:
    """Figures of every run of a study, by cell; each computed at most once.

    Parameters
    ----------
    study : StudyRuns
    cells : dict
        Cell name -> :class:`~orchestrator.reproduce.experiments.Cell`.
    runs : int
        Runs per cell (lists are this long; a failed run gives None figures).
    """

    def __init__(self, study, cells, runs):
        self.study, self.cells, self.runs = study, cells, runs
        self._figures = {}

    def has(self, cell):
        """True if the cell was run."""
        return bool(self.study.of(cell))

    def figures(self, cell):
        """One dict of figures per run (None for a failed or missing run)."""
        if cell not in self._figures:
            labels = self.cells[cell].labels if cell in self.cells else {}
            out = []
            for run in self.study.of(cell):
                if not run.ok:
                    out.append(None)
                elif "path" in labels:
                    out.append({**tracking_figures(run, SEC62_STOP_DISTANCE),
                                **following_figures(run.data["time"], run.xy(),
                                                    run.source_xy(),
                                                    run.data["source.emitting"] > 0.5),
                                **fix_figures(run)})
                else:
                    figures = arrival_figures(run, reference_path(labels))
                    if "case" in labels:
                        segments = 2 if labels["case"] == "dynamic" else 1
                        figures["wheels"] = wheel_profile(run, segments)
                    out.append({**figures, **fix_figures(run)})
            out += [None] * (self.runs - len(out))
            self._figures[cell] = out
        return self._figures[cell]

    def values(self, cell, key, segment=None):
        """The figure ``key`` of every run of a cell (None where missing)."""
        values = []
        for figures in self.figures(cell):
            if figures is None:
                values.append(None)
            elif segment is not None:
                wheels = figures.get("wheels") or []
                values.append(wheels[segment].get(key) if segment < len(wheels) else None)
            else:
                values.append(figures.get(key))
        return values

    def estimate(self, cell, key, scale=1.0, segment=None):
        """Interval of a figure over a cell's runs, by the claims' rule
        (:func:`~orchestrator.reproduce.statistics.evidence`): the t-interval of the mean, or
        the median's rank-based interval where runs gave no value or the values separate."""
        return evidence([None if v is None else scale * v
                         for v in self.values(cell, key, segment)]).estimate

    def difference(self, cell_a, cell_b, key):
        """Interval of the mean paired difference a - b of a figure."""
        return paired_difference(self.values(cell_a, key), self.values(cell_b, key))

    def failed_runs(self, cell):
        """The failed runs of a cell: ``(index, summary)`` of each (summary as the run wrote
        it: ``error``, ``sim_time_s`` and the figures measured until it failed)."""
        return [(i, run.summary) for i, run in enumerate(self.study.of(cell)) if not run.ok]

    def failures(self):
        """Cells with failed runs: name -> number of failed runs."""
        failed = {}
        for cell, runs in self.study.cells.items():
            bad = sum(1 for r in runs if not r.ok)
            if bad:
                failed[cell] = bad
        return failed
