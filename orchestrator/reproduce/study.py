"""The study's entry point: plan the cells, run them, judge the claims, write the report."""

import math
import os
import time
from pathlib import Path

from components.common.errors import ConfigError
from orchestrator.processes import BesideEach

from .acoustics import CONDITIONS, FIX_DEPENDENT, FREE_FIELD, ROOM, check_room_fits, load_room
from .analysis import Analysis
from .experiments import PAPER_SPEEDS, TABLES, configuration, plan
from .figures import figure_jobs, named, room_figure_jobs
from .measures import DEFINITIONS
from .paper import load_paper_tables
from .report import Report
from .runs import run_study
from .side_by_side import side_by_side
from .operating_point import median_operating_point
from .tables_control import controller_tables
from .tables_motion import motion_tables, profile_tables
from .tables_tracking import condition_summary, tracking_tables
from .tolerances import load_tolerances

__all__ = ["RUNS_PER_CELL", "check_selection", "reproduce"]

RUNS_PER_CELL = 20


def check_selection(tables, speeds):
    """Validate a table and speed selection; returns ``(set of tables, sorted speeds)``.

    Raises
    ------
    ConfigError
        Naming the unknown table or speed and the valid choices.
    """
    if tables is None:
        selected = set(TABLES)
    else:
        if isinstance(tables, str):
            tables = [tables]
        unknown = [t for t in tables if t not in TABLES]
        if unknown:
            raise ConfigError(f"tables: {', '.join(map(repr, unknown))} not known; valid "
                              f"choices: {', '.join(TABLES)}")
        selected = set(tables)
    speeds = tuple(PAPER_SPEEDS if speeds is None else speeds)
    bad = [s for s in speeds if round(float(s), 3) not in PAPER_SPEEDS]
    if bad or not speeds:
        raise ConfigError(f"speeds: {bad or 'empty'} not among the paper's speeds; valid "
                          f"choices: {', '.join(f'{s:g}' for s in PAPER_SPEEDS)}")
    return selected, tuple(sorted(round(float(s), 3) for s in set(speeds)))


def _fix_dependent_claims(analysis, selected, speeds, paper):
    """The claims of the fix-dependent tables (Tables 1-3, Sec. 6.2) on one condition's runs."""
    selected = selected & set(FIX_DEPENDENT)
    claims = motion_tables(analysis, selected, speeds, paper)[1]
    if "sec6_2" in selected:
        claims += tracking_tables(analysis)[1]
    return claims


def reproduce(out_dir, fmu_dir=None, workers=None, progress=True, tables=None, speeds=None,
              scheduler=None, runs=RUNS_PER_CELL, study_seed=0, stop_time_scale=1.0,
              tolerances=None, conditions=CONDITIONS, room=None):
    """Run the paper's experiments as a Monte Carlo study and write the report.

    Parameters
    ----------
    out_dir : path-like
        Folder for ``reproduction.{json,md,html}``, ``figures/`` and ``runs/`` (finished runs
        are reused by input hash: a second call, or one after an interruption, resumes).
    fmu_dir : path-like, optional
        Folder of the FMUs, if not beside ``fmus/SystemStructure.ssd``.
    workers : int, optional
        Worker processes of the local Dask cluster (default: the CPUs).
    progress : bool
        A progress bar over every run on stderr.
    tables : sequence of str, optional
        Subset of :data:`TABLES` (default all).
    speeds : sequence of float, optional
        Subset of the paper's speeds for Tables 1-3 (default all five; a trend needs two).
    scheduler : str, optional
        Address of a running Dask scheduler instead of the local engine
        (:class:`orchestrator.sweep.engine.LocalEngine`).
    runs : int
        Monte Carlo runs per cell (default 20; >= 2 for an interval).
    study_seed : int
        Seed of the draws (physics and localizer noise).
    stop_time_scale : float
        Factor on every stop time; 1 for the study, less only for a quick test of the code.
    tolerances : path-like, optional
        Tolerance file instead of ``orchestrator/data/tolerances.toml``.
    conditions : sequence of str
        Acoustic conditions (:data:`~orchestrator.reproduce.acoustics.CONDITIONS`): free field
        always; with ``"room"`` the fix-dependent tables run in the room too and the report
        sets both side by side.
    room : path-like, optional
        Scenario whose ``localizer.*`` parameters are the room (default ``scenarios/room.toml``).

    Returns
    -------
    Report

    Raises
    ------
    ConfigError
        For an unknown table or speed, bad run count, tolerance file or scenario problem.
    """
    if isinstance(runs, bool) or not isinstance(runs, int) or runs < 1:
        raise ConfigError(f"runs = {runs!r}: must be an integer >= 1 (>= 2 for an interval)")
    if not 0.0 < float(stop_time_scale) <= 1.0:
        raise ConfigError(f"stop_time_scale = {stop_time_scale!r}: must be in (0, 1]")
    selected, speeds = check_selection(tables, speeds)
    unknown = [c for c in conditions if c not in CONDITIONS]
    if unknown or FREE_FIELD not in conditions:
        raise ConfigError(f"conditions: {list(conditions)!r}: valid choices are "
                          f"{', '.join(CONDITIONS)}, and {FREE_FIELD} must be among them")
    room_condition = (load_room(room) if ROOM in conditions and selected & set(FIX_DEPENDENT)
                      else None)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paper = load_paper_tables()
    tolerance_list = load_tolerances(tolerances)
    pd_gains = (median_operating_point(fmu_dir) if selected & {"table8", "table9"}
                else (math.nan, math.nan))
    experiments = plan(selected, speeds, pd_gains, room_condition)
    clearance = (check_room_fits([e for e in experiments if e.cells[0].condition == ROOM],
                                 room_condition) if room_condition else {})
    started = time.perf_counter()
    study = run_study(experiments, tolerance_list, runs, out_dir, fmu_dir=fmu_dir,
                      workers=workers, scheduler=scheduler, progress=progress,
                      study_seed=study_seed, stop_time_scale=stop_time_scale)
    run_seconds = time.perf_counter() - started
    by_condition = {}
    for experiment in experiments:
        for cell in experiment.cells:
            by_condition.setdefault(cell.condition, {})[cell.name] = cell
    cells = by_condition[FREE_FIELD]
    analysis = Analysis(study.condition(cells.values()), cells, runs)
    room_analysis = None
    if room_condition is not None:
        room_cells = by_condition[ROOM]
        room_analysis = Analysis(study.condition(room_cells.values()), room_cells, runs)

    jobs = figure_jobs(analysis.study, analysis, out_dir, speeds)
    if room_analysis is not None:
        jobs += room_figure_jobs(room_analysis.study, out_dir)
    # the figures are drawn in forked children from the same runs while this process judges,
    # one child a worker: once the runs are done those cores are free (measured on the
    # --runs 2 study: 14 s of drawing, which one child kept going 11 s after the judging)
    drawing = BesideEach(jobs, workers or os.cpu_count() or 1)

    report_tables, claims, ratios = {}, [], []
    for builder in (lambda: motion_tables(analysis, selected, speeds, paper),
                    lambda: controller_tables(analysis, selected, paper)):
        t, c, r = builder()
        report_tables.update(t)
        claims += c
        ratios += r
    t, r = profile_tables(analysis, selected, paper)
    report_tables.update(t)
    ratios += r
    if "sec6_2" in selected:
        t, c = tracking_tables(analysis)
        report_tables.update(t)
        claims += c
    summary = condition_summary(claims)
    ordered = {name: report_tables[name] for name in TABLES if name in report_tables}
    if summary.rows:
        ordered = {"conditions": summary, **ordered}
    ratios.sort(key=lambda c: int(c.table.split()[-1]))

    compared = None
    if room_analysis is not None:
        compared = side_by_side(_fix_dependent_claims(analysis, selected, speeds, paper),
                                _fix_dependent_claims(room_analysis, selected, speeds, paper),
                                {FREE_FIELD: analysis, ROOM: room_analysis}, room_condition,
                                clearance)
    all_cells = sum(len(c) for c in by_condition.values())
    settings = {"tables": sorted(selected, key=TABLES.index), "speeds": list(speeds),
                "conditions": sorted(by_condition, key=CONDITIONS.index),
                "runs_per_cell": runs, "cells": all_cells, "runs_total": all_cells * runs,
                "runs_computed": study.computed, "runs_reused": study.reused,
                "failed_runs": analysis.failures(), "study_seed": study_seed,
                "stop_time_scale": stop_time_scale, "workers": workers or os.cpu_count(),
                "scheduler": "given" if scheduler else "local",
                "run_time_s": run_seconds, "fixed_pd_gains": list(pd_gains)}
    report = Report(configuration(pd_gains, room_condition), tolerance_list, DEFINITIONS, ordered,
                    claims, ratios, settings=settings, side_by_side=compared, out_dir=out_dir)
    report.figures = named(drawing.result())
    report.settings["wall_time_s"] = time.perf_counter() - started
    return report.write(out_dir)
