"""The paper's figures of Secs. 3.6, 4.2 and 6.2 from the simulated runs, named after them.

Each PNG (``figures/figNN_<what>.png``) shows the same quantities and axes as the paper's
figure, from every Monte Carlo run of the cells it needs: paths as thin lines per run, time
series as a mean with its 95 % interval. Where two controllers or modes would lie on top of
each other, a panel shows their paired difference instead. :func:`write_figures` returns a
:class:`~orchestrator.reproduce.report.Figure` per file with the series it drew;
:func:`figure_jobs` gives the same figures as one function each, to draw them side by side.
"""

from functools import partial

import numpy as np

from orchestrator.reproduce.geometry import distance_to_polyline
from orchestrator.report.matplotlib_agg import pyplot

from .analysis import CASE_TARGETS, reference_path
from .experiments import (CONTROLLERS, FRICTIONS, NOMINAL_FRICTION, SEC62_STARTS, sec62_cell,
                          t89_cell)
from .following import BODY_LENGTH, source_lane
from .plotting import COLOURS, band, paths, save, traces
from .report import Figure

__all__ = ["figure_jobs", "named", "room_figure_jobs", "write_figures", "write_room_figures"]

_LABEL = {**CONTROLLERS, "curvature": "curvature",
          "rotate_then_go": "rotate then go (without curvature)"}
# Sec. 6.2's figures show the paper's start (1 m); the 3 m start is in the tables.
_START = "start_1m"
_START_TEXT = f"source {SEC62_STARTS[_START]:g} m at 45 deg right"
# The paper's comparison in Figs. 13-16: CPID against CFGS-PD as printed.
_PAPER_ARMS = ("cpid", "fgs_pd_paper")


def _condition_text(ff, mu):
    return f"feedforward {ff[3:]}, mu {FRICTIONS[mu] or 0.8:g}"


def _axes_xy(ax, title):
    ax.set(title=title, xlabel="x [m] (right)", ylabel="y [m] (forward)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")


def _deviation(reference):
    return lambda run: distance_to_polyline(run.xy(), reference)


def _sec62_compare(study, out, path, number):
    """Figs. 7-8: curvature vs rotate-then-go on the straight / S-curve path."""
    plt = pyplot()
    cells = {m: study.of(sec62_cell(path, _START, m, "fgs_pd"))
             for m in ("curvature", "rotate_then_go")}
    if not any(cells.values()):
        return None
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 5.5))
    source_runs = cells["curvature"] or cells["rotate_then_go"]
    paths(a, source_runs[:1], COLOURS["source"], "source path", alpha=1.0, source=True)
    for mode, runs in cells.items():
        paths(a, runs, COLOURS[mode], _LABEL[mode])
    _axes_xy(a, f"Fig. {number}: {path.replace('_', '-')} path, with / without curvature")
    reference = source_runs[0].source_xy() if source_runs and source_runs[0].ok else None
    series = ["source path"] + [_LABEL[m] for m in cells]
    if reference is not None:
        # the source's lane belongs to neither mode's plan (following.py)
        ref = source_lane(reference)
        for mode, runs in cells.items():
            t, m = traces(runs, None, _deviation(ref))
            band(b, t, m, _LABEL[mode], COLOURS[mode])
    b.set(title="distance from the source's lane", xlabel="time [s]",
          ylabel="distance [m]")
    b.grid(True, alpha=0.3)
    b.legend(fontsize=7)
    name = f"fig{number:02d}_{'straight' if path == 'straight' else 'scurve'}_curvature.png"
    return Figure(f"Fig. {number}", f"{path} source path, {_START_TEXT}, CFGS-PD (default "
                  "form), feedforward on, mu 0.8: curvature planner vs rotate then go; right: "
                  "distance from the source's lane (its path extended backwards; a reference "
                  "that is neither mode's plan), mean and 95 % interval",
                  save(fig, out / name), series)


def _tracking(study, out, case, number, ff="ff_on", mu=NOMINAL_FRICTION):
    """Figs. 13 / 15: paths of CPID and CFGS-PD as printed, deviation from the ideal and its
    paired difference, in one stated condition."""
    plt = pyplot()
    cells = {c: study.of(t89_cell(case, c, ff, mu)) for c in _PAPER_ARMS}
    if not any(cells.values()):
        return None
    reference = reference_path({"case": case})
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(15, 5))
    a.plot(*reference.T, "k--", lw=1, label="ideal arc(s)")
    targets = np.array(CASE_TARGETS[case])
    a.plot(*targets.T, "g*", ms=12, label="source / target(s)")
    for control, runs in cells.items():
        paths(a, runs, COLOURS[control], _LABEL[control])
    _axes_xy(a, f"Fig. {number}: Case {1 if case == 'static' else 2} ({case}), "
             f"{_condition_text(ff, mu)}")
    deviation = {}
    for control, runs in cells.items():
        t, m = traces(runs, None, _deviation(reference))
        band(b, t, m, _LABEL[control], COLOURS[control])
        deviation[control] = (t, m)
    b.set(title="distance from the ideal path", xlabel="time [s]", ylabel="distance [m]")
    b.grid(True, alpha=0.3)
    b.legend(fontsize=7)
    (t1, m1), (_, m2) = deviation["fgs_pd_paper"], deviation["cpid"]
    n = min(m1.shape[0], m2.shape[0])
    k = min(m1.shape[1] if m1.size else 0, m2.shape[1] if m2.size else 0)
    if n and k:
        band(c, t1[:k], m1[:n, :k] - m2[:n, :k], "CFGS-PD as printed - CPID (paired)",
             "tab:purple")
    c.axhline(0.0, color="k", lw=0.8)
    c.set(title="paired difference of that distance",
          xlabel="time [s]", ylabel="difference [m]")
    c.grid(True, alpha=0.3)
    c.legend(fontsize=7)
    name = f"fig{number:02d}_{case}_tracking.png"
    return Figure(f"Fig. {number}", f"Case {case}, {_condition_text(ff, mu)}: paths of CPID "
                  "and CFGS-PD as printed, their distance from the ideal path and its paired "
                  "difference",
                  save(fig, out / name),
                  ["ideal", _LABEL["cpid"], _LABEL["fgs_pd_paper"],
                   f"{_LABEL['fgs_pd_paper']} - CPID"])


def _wheel(study, out, cells, number, title, name, slip=True):
    """Left-wheel velocity profiles, one panel per controller, plus error and slip, every
    panel from the same cells."""
    plt = pyplot()
    cells = {k: v for k, v in cells.items() if v}
    if not cells:
        return None
    rows = len(cells) + 1 + (1 if slip else 0)
    fig, axes = plt.subplots(rows, 1, figsize=(10, 2.6 * rows), sharex=True)
    series = []
    for ax, (control, runs) in zip(axes, cells.items()):
        t, ref = traces(runs, "planner.v_ref_left")
        band(ax, t, ref, "reference v_ref_left", "k", "--")
        t, speed = traces(runs, "plant.rim_speed_left")
        band(ax, t, speed, f"{_LABEL[control]} left rim speed", COLOURS[control])
        ax.set(title=f"{_LABEL[control]}: left wheel", ylabel="speed [m/s]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
        series.append(_LABEL[control])
    error_ax = axes[len(cells)]
    for control, runs in cells.items():
        t, m = traces(runs, None, lambda r: r.data["planner.v_ref_left"]
                      - r.data["plant.rim_speed_left"])
        band(error_ax, t, m, f"{_LABEL[control]} v_ref - rim speed", COLOURS[control])
    error_ax.axhline(0.0, color="k", lw=0.6)
    error_ax.set(title="left-wheel speed error", ylabel="error [m/s]")
    error_ax.grid(True, alpha=0.3)
    error_ax.legend(fontsize=7)
    if slip:
        slip_ax = axes[-1]
        for control, runs in cells.items():
            t, m = traces(runs, "plant.slip_left")
            band(slip_ax, t, m, f"{_LABEL[control]} left slip ratio", COLOURS[control])
        slip_ax.set(title="left-wheel longitudinal slip ratio", ylabel="slip ratio [1]")
        slip_ax.grid(True, alpha=0.3)
        slip_ax.legend(fontsize=7)
        series.append("slip")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(f"Fig. {number}: {title}", fontsize=10)
    return Figure(f"Fig. {number}", title + ": speed, speed error and slip ratio of the same "
                  "cells (mean and 95 % interval over the runs)",
                  save(fig, out / name), series)


def _comparison(analysis, out):
    """Fig. 17: error at arrival and path RMSE of both cases, every arm and condition.

    Each point is the cell's estimate by the claims' rule (mean and t-interval, or median and
    its rank-based interval where runs never arrived or the values separate). A symmetric-log
    axis (linear within 1 mm of zero): the figures span mm to m, and an interval that reaches
    zero or below is drawn as it is, never clipped or hidden.
    """
    plt = pyplot()
    if not analysis.has(t89_cell("static", "cpid", "ff_on", NOMINAL_FRICTION)):
        return None
    conditions = ([(ff, NOMINAL_FRICTION) for ff in ("ff_on", "ff_off")]
                  + [("ff_on", mu) for mu in FRICTIONS if mu != NOMINAL_FRICTION])
    arms = [(arm, "per_second") for arm in CONTROLLERS] + [("cpid", "per_sample")]
    fig, axes = plt.subplots(2, 1, figsize=(15, 9))
    width = 0.8 / len(arms)
    for ax, key, title in ((axes[0], "error_at_arrival_m", "error at arrival [m]"),
                           (axes[1], "rmse_path_m", "path RMSE [m]")):
        labels, x, drawn, tops = [], 0, set(), []
        below = ax.get_xaxis_transform()     # x in data, y in axes fractions
        for case in ("static", "dynamic"):
            for ff, mu in conditions:
                for number, (arm, units) in enumerate(arms):
                    cell = t89_cell(case, arm, ff, mu, units)
                    if not analysis.has(cell):
                        continue
                    e = analysis.estimate(cell, key)
                    where = x + (number - (len(arms) - 1) / 2) * width
                    if e.missing:   # runs without the figure (never arrived) are said, not hidden
                        ax.text(where, 0.02, f"{e.n}/{e.n + e.missing}", transform=below,
                                rotation=90, fontsize=6, ha="center", va="bottom",
                                color=COLOURS[arm])
                    if not e.n:
                        continue
                    label = _LABEL[arm] + (", ki per sample" if units == "per_sample" else "")
                    err = [[e.mean - e.low], [e.high - e.mean]] if e.n > 1 else None
                    ax.errorbar(where, e.mean, yerr=err,
                                fmt="o" if units == "per_second" else "s", capsize=2,
                                color=COLOURS[arm],
                                label=label if label not in drawn else None)
                    drawn.add(label)
                    tops += [v for v in (e.mean, e.high) if np.isfinite(v)]
                labels.append(f"{case}\n{_condition_text(ff, mu).replace(', ', chr(10))}")
                x += 1
        ax.set_xticks(range(len(labels)), labels, fontsize=7)
        ax.set_yscale("symlog", linthresh=1e-3)
        if tops:   # room above the highest finite bound (an infinite one runs off the top)
            ax.set_ylim(top=2.0 * max(tops))
        ax.set(title=f"Fig. 17: {title}, estimate and 95 % interval", ylabel=title)
        ax.grid(True, alpha=0.3, which="both")
        if drawn:
            ax.legend(fontsize=7, ncol=3)
    return Figure("Fig. 17", "static and dynamic curvature tracking: error at arrival and path "
                  "RMSE by controller arm, feedforward and friction (symmetric-log axis, "
                  "linear within 1 mm of zero); n/20 at the foot of a cell: the runs with a "
                  "value (the others never arrived or failed)",
                  save(fig, out / "fig17_static_dynamic_comparison.png"),
                  [_LABEL[a] + (", ki per sample" if u == "per_sample" else "")
                   for a, u in arms])


def _relative(run):
    """True and estimated source position in the robot frame (x right, y forward, theta)."""
    d = run.data
    dx, dy = d["source.x"] - d["plant.x"], d["source.y"] - d["plant.y"]
    psi = d["plant.heading"]
    forward = dx * np.cos(psi) + dy * np.sin(psi)
    right = dx * np.sin(psi) - dy * np.cos(psi)
    valid = d["localizer.valid"] > 0.5
    distance, bearing = d["localizer.distance"], d["localizer.bearing"]
    return {"true": (right, forward, np.degrees(np.arctan2(right, forward)),
                     np.hypot(right, forward)),
            "heard": (-distance * np.sin(bearing), distance * np.cos(bearing),
                      -np.degrees(bearing), distance),
            "valid": valid}


def _estimates(study, out, path, number, name, which, where=""):
    """Figs. 25 / 29 (x, y, theta) and 26 / 30 (distance, angle) of the heard source."""
    plt = pyplot()
    runs = [r for r in study.of(sec62_cell(path, _START, "curvature", "fgs_pd")) if r.ok]
    if not runs:
        return None
    run = runs[0]
    rel = _relative(run)
    t, valid = run.data["time"], rel["valid"]
    panels = ([(0, "x (right) [m]"), (1, "y (forward) [m]"), (2, "theta (right +) [deg]")]
              if which == "xyt" else [(3, "distance [m]"), (2, "angle (right +) [deg]")])
    fig, axes = plt.subplots(len(panels), 1, figsize=(10, 2.8 * len(panels)), sharex=True)
    for ax, (index, label) in zip(axes, panels):
        ax.plot(t, rel["true"][index], color="k", lw=1.2, label="true (from the poses)")
        ax.plot(t[valid], rel["heard"][index][valid], ".", ms=3, color="tab:blue",
                label="heard (localizer fix)")
        error = rel["heard"][index][valid] - rel["true"][index][valid]
        if len(error):
            ax.set_title(f"{label.split(' [')[0]}: heard - true median "
                         f"{np.median(error):+.3g}, RMS {np.sqrt(np.mean(error ** 2)):.3g}",
                         fontsize=9)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    axes[-1].set_xlabel("time [s]")
    what = "estimated source x, y, theta" if which == "xyt" else "distance and angle"
    fig.suptitle(f"Fig. {number}: {what}, {path} path{where}, {_START_TEXT} (run 1 of "
                 f"{len(runs)}), robot frame", fontsize=10)
    return Figure(f"Fig. {number}", f"{path} path{where}: {what} of the source relative to "
                  "the robot, "
                  "heard vs true (first run; the tables hold all runs)",
                  save(fig, out / name), ["true", "heard"])


def _sec62_tracking(study, out, path, number, name):
    """Figs. 23 / 27: source and robot paths (start, mute point) and the gap over time."""
    plt = pyplot()
    runs = study.of(sec62_cell(path, _START, "curvature", "fgs_pd"))
    if not runs:
        return None
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 6))
    paths(a, runs[:1], COLOURS["source"], "source (master) path", alpha=1.0, source=True)
    paths(a, runs, COLOURS["fgs_pd"], "robot (slave), curvature, CFGS-PD")
    first = runs[0]
    if first.ok:
        emitting = first.data["source.emitting"] > 0.5
        silent = np.nonzero(~emitting)[0]
        if len(silent):
            a.plot(*first.source_xy()[silent[0]], "rx", ms=10, mew=2, label="source mutes")
        a.plot(0.0, 0.0, "ks", label="robot start")
        a.plot(*first.source_xy()[0], "g^", label="source start (45 deg right)")
    _axes_xy(a, f"Fig. {number}: {path} path tracking")
    t, gap = traces(runs, None, lambda r: np.hypot(*(r.xy() - r.source_xy()).T))
    band(b, t, gap, "gap robot - source", "tab:blue")
    b.axhline(SEC62_STARTS[_START], color="tab:red", ls="--", label="starting gap")
    b.axhline(BODY_LENGTH, color="k", ls=":", label="body length (collision)")
    b.set(title="gap between the robots", xlabel="time [s]", ylabel="gap [m]")
    b.grid(True, alpha=0.3)
    b.legend(fontsize=7)
    return Figure(f"Fig. {number}", f"{path} path, {_START_TEXT}, curvature with CFGS-PD "
                  "(default form), feedforward on, mu 0.8: the robot follows the source (every "
                  "run) and the gap over time beside the starting gap and one body length",
                  save(fig, out / name), ["source", "robot", "gap"])


def _speed_trends(analysis, out, speeds):
    """Tables 1-3 over speed: error, fitted radius, path RMSE; means with intervals."""
    plt = pyplot()
    if not speeds or not analysis.has(f"t13_v{speeds[0]:g}_curvature"):
        return None
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    for ax, key, title in ((axes[0], "error_at_arrival_m", "error at arrival [m]"),
                           (axes[1], "radius_fit_m", "radius driven [m]"),
                           (axes[2], "rmse_path_m", "path RMSE [m]")):
        for offset, mode in ((-0.004, "rotate_then_go"), (0.004, "curvature")):
            if key == "radius_fit_m" and mode == "rotate_then_go":
                continue
            estimates = [analysis.estimate(f"t13_v{s:g}_{mode}", key) for s in speeds]
            ok = [(s, e) for s, e in zip(speeds, estimates) if e.n]
            if ok:
                ax.errorbar([s + offset for s, _ in ok], [e.mean for _, e in ok],
                            yerr=[[e.mean - e.low if e.n > 1 else 0 for _, e in ok],
                                  [e.high - e.mean if e.n > 1 else 0 for _, e in ok]],
                            fmt="o-", capsize=3, color=COLOURS[mode], label=_LABEL[mode])
        ax.set(title=f"Tables 1-3: {title} over speed", xlabel="v [m/s]", ylabel=title)
        ax.grid(True, alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7)
        else:   # an empty panel says why instead of looking like a plotting fault
            ax.text(0.5, 0.5, "no run arrived" if key == "error_at_arrival_m" else "no run",
                    transform=ax.transAxes, ha="center", va="center")
    return Figure("Tables 1-3", "error at arrival, driven radius and path RMSE over the speed "
                  "(mean and 95 % interval)", save(fig, out / "table1_3_speed_trends.png"),
                  [_LABEL["rotate_then_go"], _LABEL["curvature"]])


def room_figure_jobs(study, out_dir):
    """Figs. 25 and 29 from the room's runs (``fig25_straight_estimates_room.png``, ...), one
    function each (returning its Figure, or None); see :func:`named`."""
    out = out_dir / "figures"
    out.mkdir(parents=True, exist_ok=True)
    return [partial(_estimates, study, out, path, number, f"fig{number}_{tag}_estimates_room.png",
                    "xyt", where=" in the room")
            for path, number, tag in (("straight", 25, "straight"), ("s_curve", 29, "scurve"))]


def write_room_figures(study, out_dir):
    """Figs. 25 and 29 from the room's runs; returns the Figure records written."""
    return named([job() for job in room_figure_jobs(study, out_dir)])


def figure_jobs(study, analysis, out_dir, speeds):
    """Every figure the study's cells allow, as functions of no argument, one a figure, in the
    report's order: each draws its PNG and returns its Figure (None if its cells are missing).
    They share nothing, so they may run in any order and process; see :func:`named`."""
    out = out_dir / "figures"
    out.mkdir(parents=True, exist_ok=True)
    jobs = [partial(_speed_trends, analysis, out, speeds),
            partial(_sec62_compare, study, out, "straight", 7),
            partial(_sec62_compare, study, out, "s_curve", 8)]
    for case, number in (("static", 13), ("dynamic", 15)):
        jobs.append(partial(_tracking, study, out, case, number))
        for mu in (NOMINAL_FRICTION, "mu0.05"):
            tag = "" if mu == NOMINAL_FRICTION else f"_{mu.replace('.', '')}"
            jobs.append(partial(
                _wheel, study, out,
                {c: study.of(t89_cell(case, c, "ff_on", mu)) for c in _PAPER_ARMS},
                number + 1, f"left wheel, Case {1 if case == 'static' else 2} ({case}), "
                f"{_condition_text('ff_on', mu)}", f"fig{number + 1}_{case}_left_wheel{tag}.png"))
    jobs.append(partial(_comparison, analysis, out))
    for path, base, tag in (("straight", 23, "straight"), ("s_curve", 27, "scurve")):
        cells = {c: study.of(sec62_cell(path, _START, "curvature", c)) for c in ("cpid", "fgs_pd")}
        jobs += [
            partial(_sec62_tracking, study, out, path, base, f"fig{base}_{tag}_tracking.png"),
            partial(_wheel, study, out, cells, base + 1, f"left wheel, {path} path, "
                    f"{_START_TEXT}, curvature, feedforward on, mu 0.8",
                    f"fig{base + 1}_{tag}_left_wheel.png"),
            partial(_estimates, study, out, path, base + 2, f"fig{base + 2}_{tag}_estimates.png",
                    "xyt"),
            partial(_estimates, study, out, path, base + 3,
                    f"fig{base + 3}_{tag}_distance_angle.png", "da")]
    return jobs


def write_figures(study, analysis, out_dir, speeds):
    """Write every figure the study's cells allow; returns the Figure records written."""
    return named([job() for job in figure_jobs(study, analysis, out_dir, speeds)])


def named(figures):
    """The figures drawn (the jobs' values without the Nones), each ``path`` made relative to
    the report's folder (``figures/<name>.png``)."""
    written = [f for f in figures if f is not None]
    for figure in written:
        figure.path = f"figures/{figure.path.name}"
    return written
