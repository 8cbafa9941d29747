"""The paper's experiments in simulation, printed beside the paper's numbers.

:func:`reproduce` builds the scenarios of Sec. 3.6 (Tables 1-3), Sec. 4.2 (Tables 8-9) and
Sec. 6.2 (straight and S-curve tracking) from the shipped scenario files with
:meth:`~orchestrator.scenario.Scenario.with_overrides`, runs them with
:func:`orchestrator.sweep.sweep` (Dask workers, runs stored by input hash, so a second call
reuses finished runs) and measures every row from the recorded true trajectory. Tables 6-7
(the planner's wheel profiles) are recomputed from :mod:`components.planner.geometry`. The
paper's figures come from ``orchestrator/data/paper_tables.toml``.

Nothing here is tuned to the paper: each experiment uses the paper's stated conditions and the
system's defaults otherwise, and a claim the simulation does not support is reported as such.
Definitions of every measured quantity are in :data:`DEFINITIONS` and ``docs/reproduction.md``.
"""

import json
import math
import os
import sys
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from components.common.errors import ConfigError

__all__ = [
    "TABLES",
    "PAPER_SPEEDS",
    "DEFINITIONS",
    "ReportTable",
    "Claim",
    "ReproductionReport",
    "load_paper_tables",
    "path_length",
    "resample_path",
    "distance_to_path",
    "path_rmse",
    "tangent_arc_path",
    "circle_fit_radius",
    "arrival_time",
    "apex_offsets",
    "planner_profiles",
    "reproduce",
    "register_cli",
]

TABLES = ("table1", "table2", "table3", "table6", "table7", "table8", "table9", "sec6_2")
PAPER_SPEEDS = (0.1, 0.2, 0.3, 0.4, 0.5)

_SCENARIO_DIR = Path(__file__).resolve().parent.parent / "scenarios"

# Sec. 3.6: "the sound source was released at the location of (1.5, 1.5)" and "the level of
# acceleration was set to be 0.5 m/s^2"; v_max = 0.6 m/s is the paper's design limit (Eq. 43),
# needed because the outer wheel of the 1.5 m arc runs 1.10 x the centre speed (0.55 m/s at
# v = 0.5), which the tracking limit 0.4 m/s would cap.
TABLE13_TARGET = (1.5, 1.5)
TABLE13_A_MAX = 0.5
TABLE13_V_MAX = 0.6
# The paper's robot drives to the target (Table 2's distances are whole quarter circles), so
# the planner stops at the heard target itself. The localizer gives no fix closer than its
# min_range (0.4 m), so the last arc is planned from a fix at >= 0.4 m and then driven out.
STOP_DISTANCE = 0.0
# Sec. 6.2 keeps the scenarios' planner stop_distance (0.5 m): the paper mutes the source "to
# prevent collisions", so the follower is not meant to drive onto the leader.
TRACK_STOP_TIME = 40.0          # s; the S-curve source ends at 33.3 s, the straight at 31 s

# "Arrived": the true pose stays within 5 mm and 0.01 rad (0.6 deg) of the final pose for at
# least the last second. A wheel rocking by one encoder count (0.52 mm) at standstill stays far
# inside; a creep of 0.02 rad/s (seen with a standstill limit cycle) leaves the band in 0.5 s.
REST_POSITION = 0.005           # m
REST_HEADING = 0.01             # rad
REST_SETTLE = 1.0               # s
RESAMPLE_SPACING = 0.005        # m; path RMSE samples the path every 5 mm of arc length
# Sec. 6.2 verdict thresholds, fixed before looking at results: the follower "tracks" if it
# ends within one body length (0.35 m, Table 11) of its stop distance from the source's end and
# never falls more than 2 m behind; it does not collide if the centres stay >= one body length
# apart.
BODY_LENGTH = 0.35
# CFGS-PD counts as better than CPID only if its figure is at least 10 % lower.
CONTROLLER_MARGIN = 0.10
LOST_DISTANCE = 2.0

DEFINITIONS = {
    "distance_m": "length of the robot's true path (sum of distances between 20 ms samples "
                  "of plant.x, plant.y), the whole run",
    "error_m": "distance from the robot's true centre to the source at the end of the run "
               "(the run lasts until the robot is at rest)",
    "time": "time from t = 0 (source sounding, robot at rest) until the robot's true pose "
            "stays within 5 mm and 0.01 rad of its final pose (for at least the last 1 s of "
            "the run; else '-': not settled)",
    "radius_planner_m": "planner.radius output at the first accepted fix (Eq. 36 from the "
                        "heard distance and bearing)",
    "radius_fit_m": "radius of the least-squares circle (Kasa fit) through the robot's true "
                    "path while moving: the radius actually driven",
    "rmse_path_m": "RMS distance of the robot's true path, resampled every 5 mm of arc length, "
                   "from the ideal path of the mode: the straight segment start -> target for "
                   "rotate_then_go, the arc tangent to the start heading through the target "
                   "for curvature (Case 2: that arc, then the tangent arc from its end to the "
                   "second target)",
    "rmse_speed_m_s": "RMS of (planner wheel reference - true rim speed) over both wheels while "
                      "the robot moves (a secondary figure for Table 9)",
    "inward_offset_m": "at each apex of the source's S-curve (extreme lateral offset from its "
                       "start line), the source's lateral offset minus the robot's at the same "
                       "forward coordinate, signed towards the curve's centre: > 0 means the "
                       "robot runs inside the source's path",
}


# --------------------------------------------------------------------------- paper data


def load_paper_tables(path=None):
    """Read the paper's printed figures.

    Parameters
    ----------
    path : path-like, optional
        A TOML file; default ``orchestrator/data/paper_tables.toml`` (package data).

    Returns
    -------
    dict
        The TOML tables (``table1_without_curvature``, ``table2_with_curvature``, ...).

    Raises
    ------
    ConfigError
        If the file cannot be read or is not valid TOML.
    """
    try:
        if path is None:
            text = resources.files("orchestrator").joinpath("data/paper_tables.toml").read_text()
            where = "orchestrator/data/paper_tables.toml"
        else:
            where = str(path)
            text = Path(path).read_text()
        return tomllib.loads(text)
    except OSError as exc:
        raise ConfigError(f"{where}: cannot read the paper tables ({exc})") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{where}: not valid TOML ({exc})") from exc


# --------------------------------------------------------------------------- metrics


def path_length(xy):
    """Length [m] of a polyline given as an ``(n, 2)`` array of points (0 for n < 2)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    if len(xy) < 2:
        return 0.0
    return float(np.sum(np.hypot(*np.diff(xy, axis=0).T)))


def resample_path(xy, spacing):
    """Points every ``spacing`` metres of arc length along a polyline (ends included).

    Resampling by arc length weights each piece of the path by its length, not by the time
    spent on it, so a robot at rest or ramping slowly does not dominate a path RMSE.
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    if not spacing > 0:
        raise ConfigError(f"spacing = {spacing!r}: must be a number > 0")
    cumulative = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))))
    if len(xy) < 2 or cumulative[-1] == 0.0:
        return xy[:1].copy()
    keep = np.concatenate(([True], np.diff(cumulative) > 0))
    xy, cumulative = xy[keep], cumulative[keep]
    count = max(2, int(math.ceil(cumulative[-1] / spacing)) + 1)
    s = np.linspace(0.0, cumulative[-1], count)
    return np.column_stack([np.interp(s, cumulative, xy[:, 0]), np.interp(s, cumulative, xy[:, 1])])


def distance_to_path(points, polyline, chunk=256):
    """Shortest distance [m] from each point to a polyline (a single point is allowed).

    Works in chunks of points so that a long trajectory against a finely sampled reference
    does not build an ``n x m`` array of gigabytes.
    """
    from orchestrator.metrics import distance_to_polyline

    points = np.asarray(points, dtype=float).reshape(-1, 2)
    polyline = np.asarray(polyline, dtype=float).reshape(-1, 2)
    parts = [distance_to_polyline(points[i:i + chunk], polyline)
             for i in range(0, len(points), chunk)]
    return np.concatenate(parts) if parts else np.zeros(0)


def path_rmse(xy, reference, spacing=RESAMPLE_SPACING):
    """RMS distance [m] of a path from a reference polyline, sampled by arc length.

    Parameters
    ----------
    xy : (n, 2) array
        The driven path (e.g. the robot's true positions over time).
    reference : (m, 2) array
        The ideal path as a polyline (see :func:`tangent_arc_path`).
    spacing : float
        Arc-length spacing [m] of the samples of ``xy``.
    """
    samples = resample_path(xy, spacing)
    return float(np.sqrt(np.mean(distance_to_path(samples, reference) ** 2)))


def tangent_arc_path(start, heading, targets, points_per_arc=4001):
    """Polyline of the ideal curvature path: tangent arcs through successive targets.

    From the pose ``(start, heading)``, the arc tangent to the heading through the first
    target has signed curvature ``kappa = 2 sin(theta) / D`` (Eq. 36) and turns the heading by
    ``2 theta``; the next arc starts there with that heading. A target straight ahead gives a
    segment.

    Parameters
    ----------
    start : (2,) sequence
        Start point [m].
    heading : float
        Start heading [rad], counter-clockwise from +x.
    targets : sequence of (2,) sequences
        Points the path passes through, in order.
    points_per_arc : int
        Vertices per arc; 4001 keeps the chord error of a 0.7 m arc under 1e-7 m.

    Returns
    -------
    (m, 2) array
    """
    x, y = (float(v) for v in start)
    pieces = [np.array([[x, y]])]
    for tx, ty in targets:
        dx, dy = tx - x, ty - y
        distance = math.hypot(dx, dy)
        if distance == 0.0:
            continue
        theta = math.atan2(dy, dx) - heading
        theta = math.atan2(math.sin(theta), math.cos(theta))
        kappa = 2.0 * math.sin(theta) / distance
        if abs(kappa) < 1e-12:
            pieces.append(np.array([[tx, ty]]))
        else:
            radius = 1.0 / kappa      # signed: the centre lies to the left for kappa > 0
            cx, cy = x - radius * math.sin(heading), y + radius * math.cos(heading)
            angles = np.linspace(0.0, 2.0 * theta, points_per_arc)[1:]
            # a point at heading h on the circle: centre + radius (sin h, -cos h)
            h = heading + angles
            pieces.append(np.column_stack([cx + radius * np.sin(h), cy - radius * np.cos(h)]))
        heading = heading + 2.0 * theta
        x, y = float(tx), float(ty)
    return np.vstack(pieces)


def circle_fit_radius(xy):
    """Radius [m] of the least-squares circle through points (Kasa's algebraic fit).

    Solves ``x^2 + y^2 + a x + b y + c = 0`` in the least-squares sense; exact for points on
    a circle. Returns ``inf`` for collinear points.
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    if len(xy) < 3:
        return math.inf
    x, y = xy[:, 0], xy[:, 1]
    # centring first keeps the normal equations well conditioned for large radii
    mx, my = x.mean(), y.mean()
    u, v = x - mx, y - my
    spread = np.linalg.svd(np.column_stack([u, v]), compute_uv=False)
    if spread[0] == 0.0 or spread[1] <= 1e-9 * spread[0]:
        return math.inf             # collinear: the normal equations are singular
    system = np.column_stack([u, v, np.ones_like(u)])
    (a, b, c), *_ = np.linalg.lstsq(system, -(u * u + v * v), rcond=None)
    radius2 = 0.25 * (a * a + b * b) - c
    scale = max(float(np.max(np.hypot(u, v))), 1e-12)
    if radius2 <= 0 or math.sqrt(radius2) > 1e6 * scale:
        return math.inf
    return float(math.sqrt(radius2))


def arrival_time(time, xy, heading, position_tolerance=REST_POSITION,
                 heading_tolerance=REST_HEADING, settle=REST_SETTLE):
    """Time [s] from which the robot stays at its final pose, or None if it did not settle.

    The robot has arrived at the earliest sample time from which its position stays within
    ``position_tolerance`` of the final position and its heading within ``heading_tolerance``
    of the final heading. Net displacement is used, not sample-to-sample speed, so that a
    standstill limit cycle of one encoder count (a wheel rocking by a fraction of a mm) does
    not count as driving, while a slow creep or a late correcting leg does.

    Parameters
    ----------
    time : (n,) array
        Sample times [s].
    xy : (n, 2) array
        True centre positions [m].
    heading : (n,) array
        True heading [rad].
    position_tolerance : float
        Radius [m] around the final position.
    heading_tolerance : float
        Band [rad] around the final heading.
    settle : float
        The robot must have stayed put at least this long [s] before the end of the record,
        else it has not arrived (the run was too short, or it creeps).

    Returns
    -------
    float or None
        The arrival time; 0.0 if it never moved.
    """
    time = np.asarray(time, dtype=float)
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    heading = np.unwrap(np.asarray(heading, dtype=float))
    if len(time) < 2:
        return None
    away = ((np.hypot(*(xy - xy[-1]).T) > position_tolerance)
            | (np.abs(heading - heading[-1]) > heading_tolerance))
    outside = np.nonzero(away)[0]
    if len(outside) == 0:
        return 0.0
    arrived = float(time[outside[-1] + 1]) if outside[-1] + 1 < len(time) else None
    if arrived is None or time[-1] - arrived < settle:
        return None
    return arrived


def apex_offsets(source_xy, robot_xy, min_lateral=0.05):
    """Signed offsets of the robot's path inside the source's path at the source's apexes.

    The source's forward axis runs from its first to its last point; its lateral offset
    (left positive) from that axis has a largest and a smallest value, the apexes of an
    S-curve. At each apex with ``|lateral| >= min_lateral`` the robot's lateral offset at the
    same forward coordinate (linear interpolation at its first crossing) is compared with it.

    Returns
    -------
    list of dict
        Per apex: ``forward_m``, ``source_lateral_m``, ``robot_lateral_m`` (None if the robot
        never got there) and ``inward_offset_m`` = sign(source lateral) (source lateral - robot
        lateral): positive when the robot is nearer the start line, i.e. inside the curve (at
        an apex the path's centre of curvature lies towards the start line).
    """
    source_xy = np.asarray(source_xy, dtype=float).reshape(-1, 2)
    robot_xy = np.asarray(robot_xy, dtype=float).reshape(-1, 2)
    start = source_xy[0]
    axis = source_xy[-1] - start
    length = float(np.hypot(*axis))
    if length == 0.0:
        return []
    forward_unit = axis / length

    def frame(points):
        relative = points - start
        forward = relative @ forward_unit
        lateral = forward_unit[0] * relative[:, 1] - forward_unit[1] * relative[:, 0]
        return forward, lateral

    source_forward, source_lateral = frame(source_xy)
    robot_forward, robot_lateral = frame(robot_xy)
    apexes = []
    for index in sorted({int(np.argmax(source_lateral)), int(np.argmin(source_lateral))}):
        lateral = float(source_lateral[index])
        if abs(lateral) < min_lateral:
            continue
        forward = float(source_forward[index])
        crossing = np.nonzero((robot_forward[:-1] <= forward) & (robot_forward[1:] > forward))[0]
        robot_at = None
        if len(crossing):
            i = int(crossing[0])
            fraction = (forward - robot_forward[i]) / (robot_forward[i + 1] - robot_forward[i])
            step = robot_lateral[i + 1] - robot_lateral[i]
            robot_at = float(robot_lateral[i] + fraction * step)
        apexes.append({
            "forward_m": forward,
            "source_lateral_m": lateral,
            "robot_lateral_m": robot_at,
            "inward_offset_m": (None if robot_at is None
                                else math.copysign(1.0, lateral) * (lateral - robot_at)),
        })
    return apexes


def planner_profiles(track_width, v_cruise=0.3):
    """Tables 6-7 from the planner's geometry (Eqs. 36-42) for a given track width.

    Parameters
    ----------
    track_width : float
        Wheel distance ``L`` [m] (the paper's tables need 0.40 m; the robot has 0.289 m).
    v_cruise : float
        Centre cruise speed ``V`` [m/s].

    Returns
    -------
    dict
        ``case1`` (2 m at 45 deg right), ``case2_segment1`` (1 m at 45 deg right) and
        ``case2_segment2`` (1 m at 45 deg left), each with ``radius``, ``centre_length``,
        ``left_velocity``, ``right_velocity``, ``left_distance``, ``right_distance``.
    """
    from components.planner.geometry import (arc_curvature, arc_length, radius_of,
                                             wheel_arc_lengths, wheel_factors)

    profiles = {}
    for name, distance, bearing in (("case1", 2.0, -math.pi / 4),
                                    ("case2_segment1", 1.0, -math.pi / 4),
                                    ("case2_segment2", 1.0, math.pi / 4)):
        kappa = arc_curvature(distance, bearing)
        length = arc_length(distance, bearing)
        factor_left, factor_right = wheel_factors(kappa, track_width)
        left, right = wheel_arc_lengths(kappa, length, track_width)
        profiles[name] = {"radius": radius_of(kappa), "centre_length": length,
                          "left_velocity": factor_left * v_cruise,
                          "right_velocity": factor_right * v_cruise,
                          "left_distance": left, "right_distance": right}
    return profiles


# --------------------------------------------------------------------------- report objects


@dataclass
class ReportTable:
    """One table of the report.

    ``columns`` is a list of ``(key, header, format)``; a row value is either plain (a label)
    or ``{"sim": x, "paper": y}`` (shown as two columns). ``None`` prints as "-".
    """

    name: str
    title: str
    columns: list
    rows: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    def to_markdown(self):
        """The table as GitHub markdown, with its notes below."""
        headers, formats = [], []
        for key, header, fmt in self.columns:
            compared = any(isinstance(row.get(key), dict) for row in self.rows)
            if compared:
                headers += [f"{header} sim", f"{header} paper"]
                formats += [(key, "sim", fmt), (key, "paper", fmt)]
            else:
                headers.append(header)
                formats.append((key, None, fmt))
        lines = [f"### {self.title}", "", "| " + " | ".join(headers) + " |",
                 "|" + "|".join("---" for _ in headers) + "|"]
        for row in self.rows:
            cells = []
            for key, part, fmt in formats:
                value = row.get(key)
                if part is not None:
                    value = value.get(part) if isinstance(value, dict) else None
                cells.append(_format(value, fmt))
            lines.append("| " + " | ".join(cells) + " |")
        if self.notes:
            lines.append("")
            lines += [f"- {note}" for note in self.notes]
        return "\n".join(lines) + "\n"

    def to_dict(self):
        """JSON-able form."""
        return {"title": self.title, "columns": [c[0] for c in self.columns],
                "rows": _jsonable(self.rows), "notes": list(self.notes)}


@dataclass
class Claim:
    """A claim of the paper, the figure that tests it and the verdict."""

    source: str
    claim: str
    figure: str
    verdict: str            # "supported" / "not supported" / "not run"
    values: dict = field(default_factory=dict)

    def to_dict(self):
        """JSON-able form."""
        return _jsonable({"source": self.source, "claim": self.claim, "figure": self.figure,
                          "verdict": self.verdict, "values": self.values})


@dataclass
class ReproductionReport:
    """Result of :func:`reproduce`: tables, claims and the files written."""

    tables: dict
    claims: list
    settings: dict
    out_dir: Path
    markdown_path: Path = None
    json_path: Path = None
    figures: list = field(default_factory=list)
    runs: dict = field(default_factory=dict)

    def to_markdown(self):
        """The whole report as markdown."""
        lines = ["# Paper reproduction (simulation beside the paper's printed figures)", "",
                 "Definitions: docs/reproduction.md. Runs: " + str(self.out_dir / "runs"), ""]
        for table in self.tables.values():
            lines.append(table.to_markdown())
        if self.claims:
            lines += ["### Claims", "", "| source | claim | figure | verdict |",
                      "|---|---|---|---|"]
            lines += [f"| {c.source} | {c.claim} | {c.figure} | **{c.verdict}** |"
                      for c in self.claims]
            lines.append("")
        return "\n".join(lines)

    def to_dict(self):
        """JSON-able form (definitions, settings, tables, claims, runs)."""
        return {"definitions": DEFINITIONS, "settings": _jsonable(self.settings),
                "tables": {name: t.to_dict() for name, t in self.tables.items()},
                "claims": [c.to_dict() for c in self.claims],
                "runs": _jsonable(self.runs),
                "figures": [str(p) for p in self.figures]}


def _format(value, fmt):
    if value is None:
        return "-"
    if isinstance(value, float):
        if not math.isfinite(value):
            return "inf" if value > 0 else "nan"
        return format(value, fmt)
    return str(value)


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, Path):
        return str(value)
    return value


# --------------------------------------------------------------------------- runs

_RECORDED = ["source.x", "source.y", "source.emitting", "plant.x", "plant.y", "plant.heading",
             "plant.rim_speed_left", "plant.rim_speed_right", "planner.v_ref_left",
             "planner.v_ref_right", "planner.radius", "planner.state", "localizer.valid"]


@dataclass
class _Group:
    """One sweep: a base scenario and a grid; ``label`` names it in progress lines."""

    name: str
    label: str
    base: object
    grid: dict


def _table13_stop_time(speed):
    # ~2.5 m of path at v, 30 % margin for re-planned legs, plus turns, ramps and the first
    # fix; whole seconds are a multiple of every base step used here
    return float(math.ceil(3.25 / speed + 5.0))


def _plan(selected, speeds):
    from orchestrator.scenario import load_scenario

    groups = []
    modes = [m for m, t in (("rotate_then_go", ("table1", "table3")),
                            ("curvature", ("table2", "table3"))) if selected & set(t)]
    if modes:
        static = load_scenario(_SCENARIO_DIR / "static_case1.toml")
        for speed in speeds:
            base = static.with_overrides(
                name=f"table13_v{speed:g}", stop_time=_table13_stop_time(speed),
                outputs=_RECORDED,
                parameters={"source.path": "static", "source.x0": TABLE13_TARGET[0],
                            "source.y0": TABLE13_TARGET[1], "planner.v_cruise": speed,
                            "planner.v_max": TABLE13_V_MAX, "planner.a_max": TABLE13_A_MAX,
                            "planner.stop_distance": STOP_DISTANCE})
            groups.append(_Group(f"table13_v{speed:g}", f"Tables 1-3, v = {speed:g} m/s",
                                 base, {"planner.mode": modes}))
    if selected & {"table8", "table9"}:
        # Both wheels run the same law; a sweep grid is a product, so it also runs the two
        # mixed pairs (pid on one wheel, fgs_pd on the other). They cost two short runs and
        # keep one sweep per case; the report uses only the matched pairs.
        controls = ["pid", "fgs_pd"]
        for case in ("static_case1", "dynamic_case2"):
            scenario = load_scenario(_SCENARIO_DIR / f"{case}.toml")
            base = scenario.with_overrides(outputs=_RECORDED,
                                           parameters={"planner.stop_distance": STOP_DISTANCE})
            groups.append(_Group(f"table89_{case}", f"Tables 8-9, {case}", base,
                                 {"controller_left.mode": controls,
                                  "controller_right.mode": controls}))
    if "sec6_2" in selected:
        scenario = load_scenario(_SCENARIO_DIR / "s_curve.toml")
        base = scenario.with_overrides(stop_time=TRACK_STOP_TIME, outputs=_RECORDED)
        groups.append(_Group("sec6_2", "Sec. 6.2, straight and S-curve", base,
                             {"source.path": ["straight", "s_curve"]}))
    return groups


def _run_groups(groups, out_dir, fmu_dir, workers, scheduler, progress):
    """Every group's sweep, one after the other, against one Dask cluster.

    One cluster for all sweeps saves its start-up per group. The sweeps run in turn: running
    them side by side from threads (one Dask client each) hung on this machine once the first
    clients closed, and the groups are cut so that each keeps two workers busy.
    """
    from orchestrator.sweep import sweep

    cluster = None
    if scheduler is None:
        from dask.distributed import LocalCluster

        cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                               processes=True, dashboard_address=None)
        scheduler = cluster.scheduler_address
    results = {}
    try:
        for group in groups:
            result = sweep(group.base, group.grid, out_dir / "runs" / group.name,
                           fmu_dir=fmu_dir, scheduler=scheduler, progress=False)
            if progress:
                print(f"reproduce: {group.label}: {len(result.rows)} run(s), {result.computed} "
                      f"computed, {result.reused} reused", file=sys.stderr, flush=True)
            results[group.name] = result
    finally:
        if cluster is not None:
            cluster.close()
    return results


def _read_results(run_dir):
    import csv

    with open(Path(run_dir) / "results.csv", newline="") as stream:
        reader = csv.reader(stream)
        header = next(reader)
        rows = [[_cell(v) for v in row] for row in reader]
    data = np.array(rows, dtype=float) if rows else np.zeros((0, len(header)))
    return {name: data[:, i] for i, name in enumerate(header)}


def _cell(text):
    lowered = text.strip().lower()
    if lowered in ("true", "false"):
        return 1.0 if lowered == "true" else 0.0
    return float(text)


@dataclass
class _Run:
    """One finished run: its summary, recorded columns and derived figures."""

    label: str
    summary: dict
    data: dict
    run_dir: str

    @property
    def ok(self):
        return self.summary.get("status") == "ok" and len(self.data.get("time", ())) > 1

    def xy(self):
        return np.column_stack([self.data["plant.x"], self.data["plant.y"]])

    def figures(self, reference):
        """Distance, final error, arrival time, path RMSE against ``reference`` and more."""
        if not self.ok:
            return {"status": self.summary.get("status", "missing"),
                    "error": self.summary.get("error")}
        data, xy = self.data, self.xy()
        source = np.column_stack([data["source.x"], data["source.y"]])
        t = data["time"]
        arrival = arrival_time(t, xy, data["plant.heading"])
        moving = np.hypot(*(xy - xy[0]).T) > 1e-3
        radius = data["planner.radius"]
        first_fix = np.nonzero((radius > 0) & (radius < 1e5))[0]
        speed_error = np.concatenate([
            (data["planner.v_ref_left"] - data["plant.rim_speed_left"])[moving],
            (data["planner.v_ref_right"] - data["plant.rim_speed_right"])[moving]])
        return {
            "status": "ok",
            "distance_m": path_length(xy),
            "error_m": float(np.hypot(*(xy[-1] - source[-1]))),
            "arrival_s": arrival,
            "rmse_path_m": path_rmse(xy, reference) if reference is not None else None,
            "rmse_speed_m_s": (float(np.sqrt(np.mean(speed_error ** 2)))
                               if len(speed_error) else None),
            "radius_planner_m": float(radius[first_fix[0]]) if len(first_fix) else None,
            "radius_fit_m": circle_fit_radius(xy[moving]) if moving.sum() >= 3 else None,
            "first_heading_change_deg": _first_heading_change(xy, data["plant.heading"]),
            "final_xy": [float(xy[-1, 0]), float(xy[-1, 1])],
            "run_dir": self.run_dir,
        }


def _first_heading_change(xy, heading, moved=0.005):
    """True heading change [deg] before the centre first moves 5 mm (a turn on the spot)."""
    away = np.nonzero(np.hypot(*(xy - xy[0]).T) > moved)[0]
    if len(away) == 0:
        return None
    turned = np.unwrap(np.asarray(heading, dtype=float))
    return float(np.degrees(turned[away[0]] - turned[0]))


def _collect(results):
    runs = {}
    for name, result in results.items():
        for row in result.rows:
            run_dir = row["run_dir"]
            summary_path = Path(run_dir) / "summary.json"
            summary = json.loads(summary_path.read_text()) if summary_path.is_file() else row
            results_csv = Path(run_dir) / "results.csv"
            data = _read_results(run_dir) if results_csv.is_file() else {}
            left, right = row.get("controller_left.mode"), row.get("controller_right.mode")
            if left != right:
                continue            # a mixed pair of the Table 8-9 grid: not reported
            key = (name, row.get("planner.mode") or row.get("source.path") or left)
            runs[key] = _Run(name, summary, data, run_dir)
    return runs


# --------------------------------------------------------------------------- tables


def _paired(sim, paper):
    return {"sim": sim, "paper": paper}


def _ms(seconds):
    return None if seconds is None else 1000.0 * seconds


def _table13(selected, speeds, runs, paper, figures_out):
    tables, claims = {}, []
    start, heading = (0.0, 0.0), 0.5 * math.pi
    references = {"rotate_then_go": np.array([start, TABLE13_TARGET]),
                  "curvature": tangent_arc_path(start, heading, [TABLE13_TARGET])}
    per_mode = {"rotate_then_go": {}, "curvature": {}}
    for speed in speeds:
        for mode in per_mode:
            run = runs.get((f"table13_v{speed:g}", mode))
            if run is not None:
                per_mode[mode][speed] = run.figures(references[mode])
                figures_out[f"{mode}_v{speed:g}"] = per_mode[mode][speed]

    def paper_at(table, column, speed):
        values = dict(zip(paper[table]["v"], paper[table][column]))
        return values.get(round(speed, 3))

    def get(mode, speed, key):
        return per_mode[mode].get(speed, {}).get(key)

    if "table1" in selected:
        table = ReportTable("table1", "Table 1: rotate then go (without curvature), target "
                            "(1.5, 1.5) m, a_max 0.5 m/s^2",
                            [("v", "v [m/s]", ".1f"), ("distance_m", "distance [m]", ".3f"),
                             ("error_m", "error [m]", ".3f"), ("time_ms", "time [ms]", ".0f"),
                             ("turn_deg", "first turn [deg] (ideal -45)", ".1f")])
        for speed in speeds:
            table.rows.append({
                "v": speed,
                "distance_m": _paired(get("rotate_then_go", speed, "distance_m"),
                                      paper_at("table1_without_curvature", "distance_m", speed)),
                "error_m": _paired(get("rotate_then_go", speed, "error_m"),
                                   paper_at("table1_without_curvature", "error_m", speed)),
                "time_ms": _paired(_ms(get("rotate_then_go", speed, "arrival_s")),
                                   paper_at("table1_without_curvature", "time_ms", speed)),
                "turn_deg": get("rotate_then_go", speed, "first_heading_change_deg")})
        table.notes += [
            "The straight-line distance to (1.5, 1.5) is 2.121 m; the paper's error column "
            "equals its distance minus 2.000 m in every row.",
            "first turn: true heading change before the centre first moves 5 mm; the "
            "target lies 45 deg right (-45).",
            "Our rotate_then_go plans a new leg (turn, then straight) when a fix arrived during "
            "the last leg, so distance and time include any correcting leg."]
        tables["table1"] = table
        claims.append(_grows_with_speed("Table 1 / Sec. 3.6", "rotate then go: the error grows "
                                        "with speed", per_mode["rotate_then_go"], speeds))
        turns = [get("rotate_then_go", s, "first_heading_change_deg") for s in speeds]
        if len(speeds) > 1 and None not in (turns[0], turns[-1]):
            errors = [None if t is None else abs(t + 45.0) for t in turns]
            claims.append(Claim(
                "Sec. 3.6", "rotate then go: the rotation towards the target errs more at "
                "higher speed", f"error of the first turn on the spot {errors[0]:.1f} deg at "
                f"{speeds[0]:g} m/s, {errors[-1]:.1f} deg at {speeds[-1]:g} m/s",
                "supported" if errors[-1] > errors[0] else "not supported",
                {"turn_error_deg": dict(zip(map(str, speeds), errors))}))
    if "table2" in selected:
        table = ReportTable("table2", "Table 2: curvature, target (1.5, 1.5) m, a_max 0.5 m/s^2",
                            [("v", "v [m/s]", ".1f"),
                             ("radius_m", "radius (planner) [m]", ".3f"),
                             ("radius_fit_m", "radius driven (fit) [m]", ".3f"),
                             ("distance_m", "distance [m]", ".3f"),
                             ("error_m", "error [m]", ".3f"), ("time_ms", "time [ms]", ".0f")])
        for speed in speeds:
            table.rows.append({
                "v": speed,
                "radius_m": _paired(get("curvature", speed, "radius_planner_m"),
                                    paper_at("table2_with_curvature", "rotation_radius_m", speed)),
                "radius_fit_m": get("curvature", speed, "radius_fit_m"),
                "distance_m": _paired(get("curvature", speed, "distance_m"),
                                      paper_at("table2_with_curvature", "distance_m", speed)),
                "error_m": _paired(get("curvature", speed, "error_m"),
                                   paper_at("table2_with_curvature", "error_m", speed)),
                "time_ms": _paired(_ms(get("curvature", speed, "arrival_s")),
                                   paper_at("table2_with_curvature", "time_ms", speed))})
        table.notes += [
            "Ideal arc to (1.5, 1.5) from (0, 0) facing +y: R = 1.5 m, length (pi/2) 1.5 = "
            "2.356 m. The paper's distance is (pi/2) x its radius in every row, i.e. a quarter "
            "circle of that radius, which would end (R, R), not at (1.5, 1.5).",
            "radius driven (fit): the circle fitted to the true path (no paper value); the "
            "paper attributes its growing radius to the outward force at speed."]
        tables["table2"] = table
        claims.append(_grows_with_speed("Table 2 / Sec. 3.6", "curvature: the error grows with "
                                        "speed", per_mode["curvature"], speeds))
        fits = [get("curvature", s, "radius_fit_m") for s in speeds]
        if len(speeds) > 1 and None not in (fits[0], fits[-1]):
            claims.append(Claim(
                "Table 2 / Sec. 3.6", "curvature: the actual rotation radius enlarges with "
                "speed", f"fitted radius {fits[0]:.3f} m at {speeds[0]:g} m/s, {fits[-1]:.3f} m "
                f"at {speeds[-1]:g} m/s (paper 1.944 -> 2.488 m)",
                "supported" if fits[-1] > fits[0] + 0.01 else "not supported",
                {"radius_fit_m": dict(zip(map(str, speeds), fits))}))
    if "table3" in selected:
        table = ReportTable("table3", "Table 3: path RMSE from the ideal path of the mode",
                            [("v", "v [m/s]", ".1f"), ("trajectory", "trajectory", ""),
                             ("rmse_m", "RMSE [m]", ".4f")])
        better = []
        for speed in speeds:
            for mode, label, column in (("rotate_then_go", "non-curvature", "non_curvature"),
                                        ("curvature", "curvature", "curvature")):
                table.rows.append({"v": speed, "trajectory": label,
                                   "rmse_m": _paired(get(mode, speed, "rmse_path_m"),
                                                     paper_at("table3_rmse", column, speed))})
            pair = (get("curvature", speed, "rmse_path_m"),
                    get("rotate_then_go", speed, "rmse_path_m"))
            if None not in pair:
                better.append(pair[0] < pair[1])
        table.notes.append("Ideal paths: the segment (0, 0) -> (1.5, 1.5) for non-curvature "
                           "(the turn on the spot adds no length), the tangent arc R = 1.5 m "
                           "for curvature; the paper does not define its RMSE.")
        tables["table3"] = table
        if better:
            claims.append(Claim(
                "Table 3", "the curvature trajectory has a lower RMSE than rotate then go",
                f"lower at {sum(better)} of {len(better)} speeds",
                "supported" if all(better) else "not supported",
                {"curvature_lower": dict(zip(map(str, speeds), better))}))
    return tables, claims


def _grows_with_speed(source, claim, figures, speeds):
    errors = [figures.get(s, {}).get("error_m") for s in speeds]
    if len(speeds) < 2 or None in (errors[0], errors[-1]):
        return Claim(source, claim, "needs two speeds", "not run")
    text = ", ".join(f"{s:g}: {e:.3f}" if e is not None else f"{s:g}: -"
                     for s, e in zip(speeds, errors))
    return Claim(source, claim, f"final error [m] by speed {text}",
                 "supported" if errors[-1] > errors[0] else "not supported",
                 {"error_m": dict(zip(map(str, speeds), errors))})


def _table67(selected, paper):
    tables = {}
    wide, robot = planner_profiles(0.40), planner_profiles(0.289)
    note = ("Track width erratum (DESIGN.md): the paper's wheel figures need L = 0.40 m; "
            "the robot's own L = 0.289 m (Table 11) is shown beside them. Acceleration: the "
            "paper reaches the cruise speed in 1 s, so it prints v / (1 s); our planner ramps "
            "at a_max instead.")
    if "table6" in selected:
        printed = paper["table6_static_profile"]
        table = ReportTable("table6", "Table 6: Case 1 profile (2 m at 45 deg right, V 0.3 m/s)",
                            [("quantity", "quantity", ""), ("l040", "L=0.40 sim", ".3f"),
                             ("l0289", "L=0.289 sim", ".3f"), ("paper", "paper", ".3f")])
        for side in ("left", "right"):
            for key, label in (("velocity", "velocity [m/s]"),
                               ("acceleration", "acceleration [m/s^2] (1 s ramp)"),
                               ("distance", "distance [m]")):
                source_key = "velocity" if key == "acceleration" else key
                table.rows.append({
                    "quantity": f"{side} {label}",
                    "l040": wide["case1"][f"{side}_{source_key}"],
                    "l0289": robot["case1"][f"{side}_{source_key}"],
                    "paper": printed[side][key]})
        table.rows.append({"quantity": "radius [m]", "l040": wide["case1"]["radius"],
                           "l0289": robot["case1"]["radius"],
                           "paper": paper["table7_dynamic_profile"]["static_radius_m"]})
        table.rows.append({"quantity": "centre distance [m]",
                           "l040": wide["case1"]["centre_length"],
                           "l0289": robot["case1"]["centre_length"],
                           "paper": paper["table7_dynamic_profile"]["static_moving_distance_m"]})
        table.notes.append(note)
        tables["table6"] = table
    if "table7" in selected:
        printed = paper["table7_dynamic_profile"]
        table = ReportTable("table7", "Table 7: Case 2 profile (1 m at 45 deg right, then 1 m "
                            "at 45 deg left, V 0.3 m/s)",
                            [("quantity", "quantity", ""), ("l040", "L=0.40 sim", ".3f"),
                             ("l0289", "L=0.289 sim", ".3f"), ("paper", "paper", ".3f")])
        for segment in ("segment1", "segment2"):
            ours_wide, ours_robot = wide[f"case2_{segment}"], robot[f"case2_{segment}"]
            for side in ("left", "right"):
                for key in ("velocity", "distance"):
                    table.rows.append({
                        "quantity": f"{segment} {side} {key}",
                        "l040": ours_wide[f"{side}_{key}"], "l0289": ours_robot[f"{side}_{key}"],
                        "paper": printed[segment][f"{side}_{key}"]})
            table.rows.append({"quantity": f"{segment} radius [m]", "l040": ours_wide["radius"],
                               "l0289": ours_robot["radius"],
                               "paper": printed["dynamic_radius_m"][int(segment[-1]) - 1]})
        table.rows.append({"quantity": "centre distance, both arcs [m]",
                           "l040": wide["case2_segment1"]["centre_length"]
                           + wide["case2_segment2"]["centre_length"],
                           "l0289": robot["case2_segment1"]["centre_length"]
                           + robot["case2_segment2"]["centre_length"],
                           "paper": printed["dynamic_moving_distance_m"]})
        table.notes += [note, "Segment 1's printed left distance 2.214 m equals Case 1's centre "
                        "distance; by symmetry with segment 2 (0.785 / 1.413) it should read "
                        "about 1.413 m (likely a misprint)."]
        tables["table7"] = table
    return tables


def _table89(selected, runs, paper, figures_out):
    tables, claims = {}, []
    start, heading = (0.0, 0.0), 0.5 * math.pi
    # Ideal paths from the scenarios' own target points (static_case1.toml, dynamic_case2.toml).
    references = {
        "static_case1": tangent_arc_path(start, heading, [(1.41421356, 1.41421356)]),
        "dynamic_case2": tangent_arc_path(start, heading, [(0.70710678, 0.70710678),
                                                           (1.41421356, 1.41421356)]),
    }
    printed = paper["table8_curvature_tracking"]
    rmse_printed = paper["table9_rmse"]
    labels = {"pid": "CPID", "fgs_pd": "CFGS-PD"}
    cases = {"static_case1": "static", "dynamic_case2": "dynamic"}
    figures = {}
    for case in cases:
        for control in labels:
            run = runs.get((f"table89_{case}", control))
            if run is not None:
                figures[(case, control)] = run.figures(references[case])
                figures_out[f"{case}_{control}"] = figures[(case, control)]

    def paper_value(table, column, case, control):
        for c, k, v in zip(table["case"], table["control"], table[column]):
            if c == cases[case] and k == labels[control]:
                return v
        return None

    if "table8" in selected:
        table = ReportTable("table8", "Table 8: curvature tracking, Case 1 (static) and Case 2 "
                            "(dynamic), CPID vs CFGS-PD",
                            [("case", "case", ""), ("control", "control", ""),
                             ("distance_m", "distance [m]", ".3f"), ("time_s", "time [s]", ".2f"),
                             ("error_m", "error [m]", ".3f")])
        for (case, control), fig in figures.items():
            table.rows.append({
                "case": cases[case], "control": labels[control],
                "distance_m": _paired(fig.get("distance_m"),
                                      paper_value(printed, "distance_m", case, control)),
                "time_s": _paired(fig.get("arrival_s"),
                                  paper_value(printed, "time_s", case, control)),
                "error_m": _paired(fig.get("error_m"),
                                   paper_value(printed, "error_m", case, control))})
        table.notes.append("Scenarios static_case1.toml and dynamic_case2.toml as shipped, "
                           "with planner.stop_distance = 0 (the paper's robot drives to the "
                           "target) and both controller_*.mode set. Error: distance to the "
                           "(second) target at the end.")
        tables["table8"] = table
        claims += _controller_claims("Table 8", "final error", "error_m", figures, cases)
    if "table9" in selected:
        table = ReportTable("table9", "Table 9: RMSE, CPID vs CFGS-PD",
                            [("case", "case", ""), ("control", "control", ""),
                             ("rmse_m", "path RMSE [m]", ".4f"),
                             ("rmse_speed", "wheel-speed RMS error [m/s]", ".4f")])
        for (case, control), fig in figures.items():
            table.rows.append({
                "case": cases[case], "control": labels[control],
                "rmse_m": _paired(fig.get("rmse_path_m"),
                                  paper_value(rmse_printed, "rmse", case, control)),
                "rmse_speed": fig.get("rmse_speed_m_s")})
        table.notes.append("The paper does not say what Table 9's RMSE measures; it follows "
                           "Fig. 17 (trajectories) and Table 3 (path RMSE), so the paper "
                           "value is set beside our path RMSE from the ideal arc(s). The "
                           "wheel-speed RMS error is given without a paper value.")
        tables["table9"] = table
        claims += _controller_claims("Table 9", "path RMSE", "rmse_path_m", figures, cases)
    return tables, claims


def _controller_claims(source, what, key, figures, cases):
    claims = []
    for case, label in cases.items():
        pid, fgs = figures.get((case, "pid"), {}), figures.get((case, "fgs_pd"), {})
        a, b = pid.get(key), fgs.get(key)
        if a is None or b is None:
            continue
        # The paper reports 2-11x lower figures with CFGS-PD; a difference of a few per cent
        # (a tenth of a millimetre here) is within run-to-run detail, so "lower" needs 10 %.
        lower = b <= (1.0 - CONTROLLER_MARGIN) * a
        change = (b - a) / a if a else math.inf
        claims.append(Claim(source, f"Case {label}: CFGS-PD has a lower {what} than CPID",
                            f"CFGS-PD {b:.4f} m, CPID {a:.4f} m ({change:+.0%})",
                            "supported" if lower else "not supported",
                            {"fgs_pd": b, "pid": a, "relative_change": change}))
    return claims


def _sec62(runs, figures_out):
    tables, claims = {}, []
    table = ReportTable("sec6_2", "Sec. 6.2: tracking the moving source (straight, S-curve)",
                        [("path", "source path", ""), ("final_gap_m", "final gap [m]", ".3f"),
                         ("max_gap_m", "largest gap [m]", ".3f"),
                         ("min_gap_m", "smallest gap [m]", ".3f"),
                         ("rmse_m", "path RMSE from source path [m]", ".3f"),
                         ("mute_s", "source mutes at [s]", ".2f"),
                         ("arrival_s", "robot at rest at [s]", ".2f")])
    for path in ("straight", "s_curve"):
        run = runs.get(("sec6_2", path))
        if run is None or not run.ok:
            claims.append(Claim("Sec. 6.2", f"{path}: run", "run failed or missing", "not run"))
            continue
        data, xy = run.data, run.xy()
        source = np.column_stack([data["source.x"], data["source.y"]])
        gap = np.hypot(*(xy - source).T)
        emitting = data["source.emitting"] > 0.5
        silent = np.nonzero(~emitting)[0]
        mute_time = float(data["time"][silent[0]]) if len(silent) else None
        stays_silent = bool(len(silent)) and not emitting[silent[0]:].any()
        # the reference the run summary uses: robot start -> source start -> source path
        reference = np.vstack([xy[:1], source])
        stop_distance = float(run.summary.get("stop_distance_m", 0.5))
        figures = {"final_gap_m": float(gap[-1]), "max_gap_m": float(gap.max()),
                   "min_gap_m": float(gap.min()), "rmse_m": path_rmse(xy, reference),
                   "mute_s": mute_time, "stays_silent": stays_silent,
                   "arrival_s": arrival_time(data["time"], xy, data["plant.heading"]),
                   "stop_distance_m": stop_distance, "run_dir": run.run_dir}
        if path == "s_curve":
            figures["apexes"] = apex_offsets(source, xy)
        figures_out[f"sec6_2_{path}"] = figures
        table.rows.append({"path": path, **{k: v for k, v in figures.items()
                                            if k not in ("apexes", "run_dir")}})
        tracks = (abs(gap[-1] - stop_distance) <= BODY_LENGTH and gap.max() <= LOST_DISTANCE)
        claims.append(Claim(
            "Sec. 6.2", f"{path}: the robot tracks the source",
            f"final gap {gap[-1]:.3f} m (stop distance {stop_distance:g} m), largest gap "
            f"{gap.max():.3f} m, path RMSE {figures['rmse_m']:.3f} m",
            "supported" if tracks else "not supported",
            {k: figures[k] for k in ("final_gap_m", "max_gap_m", "rmse_m")}))
        if path == "s_curve":
            offsets = [a["inward_offset_m"] for a in figures["apexes"]]
            known = [o for o in offsets if o is not None]
            text = ", ".join(f"{o:+.3f} m" if o is not None else "not reached" for o in offsets)
            claims.append(Claim(
                "Sec. 6.2.2", "S-curve: the robot runs inside the source's path",
                f"inward offset at the {len(offsets)} apexes: {text}",
                "supported" if known and len(known) == len(offsets) and min(known) > 0
                else "not supported", {"inward_offset_m": offsets}))
        claims.append(Claim(
            "Sec. 6.2.1", f"{path}: the source mutes at the end and the robots do not collide",
            f"muted at {mute_time if mute_time is None else round(mute_time, 2)} s "
            f"({'stays silent' if stays_silent else 'not silent at the end'}), smallest gap "
            f"{gap.min():.3f} m (body length {BODY_LENGTH} m)",
            "supported" if stays_silent and gap.min() >= BODY_LENGTH else "not supported",
            {"mute_s": mute_time, "min_gap_m": float(gap.min())}))
    table.notes.append("Scenarios straight and s_curve as shipped (curvature mode, v_cruise "
                       "0.3 m/s, stop_distance 0.5 m, FGS-PD), run to 40 s so the source "
                       "reaches its end (31 s straight, 33.3 s S-curve) and the robot stops.")
    tables["sec6_2"] = table
    return tables, claims


# --------------------------------------------------------------------------- plots


def _plot(runs, out_dir, speeds):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    start, heading = (0.0, 0.0), 0.5 * math.pi
    panels = [(mode, title) for mode, title in (("rotate_then_go", "Table 1: rotate then go"),
                                                 ("curvature", "Table 2: curvature"))
              if any((f"table13_v{s:g}", mode) in runs for s in speeds)]
    if panels:
        fig, axes = plt.subplots(1, len(panels), figsize=(6 * len(panels), 6), squeeze=False)
        for ax, (mode, title) in zip(axes[0], panels):
            ideal = (np.array([start, TABLE13_TARGET]) if mode == "rotate_then_go"
                     else tangent_arc_path(start, heading, [TABLE13_TARGET]))
            ax.plot(*ideal.T, "k--", lw=1, label="ideal")
            for speed in speeds:
                run = runs.get((f"table13_v{speed:g}", mode))
                if run is not None and run.ok:
                    ax.plot(*run.xy().T, lw=1.3, label=f"v = {speed:g} m/s")
            ax.plot(*TABLE13_TARGET, "r*", ms=12, label="source")
            ax.set(title=title, xlabel="x [m]", ylabel="y [m]")
            ax.set_aspect("equal", adjustable="datalim")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8)
        written.append(_save(fig, out_dir / "table1_2_trajectories.png"))
    cases = [("static_case1", "Case 1 (static)"), ("dynamic_case2", "Case 2 (dynamic)")]
    if any((f"table89_{c}", k) in runs for c, _ in cases for k in ("pid", "fgs_pd")):
        fig, axes = plt.subplots(1, 2, figsize=(12, 6))
        for ax, (case, title) in zip(axes, cases):
            for control, label in (("pid", "CPID"), ("fgs_pd", "CFGS-PD")):
                run = runs.get((f"table89_{case}", control))
                if run is not None and run.ok:
                    ax.plot(*run.xy().T, lw=1.3, label=label)
                    ax.plot(run.data["source.x"], run.data["source.y"], "r*", ms=10)
            ax.set(title=f"Table 8: {title}", xlabel="x [m]", ylabel="y [m]")
            ax.set_aspect("equal", adjustable="datalim")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8)
        written.append(_save(fig, out_dir / "table8_trajectories.png"))
    if any(("sec6_2", p) in runs for p in ("straight", "s_curve")):
        fig, axes = plt.subplots(1, 2, figsize=(10, 7))
        for ax, path in zip(axes, ("straight", "s_curve")):
            run = runs.get(("sec6_2", path))
            if run is not None and run.ok:
                ax.plot(run.data["source.x"], run.data["source.y"], color="tab:orange", lw=2,
                        label="source")
                ax.plot(*run.xy().T, color="tab:blue", lw=1.5, label="robot")
            ax.set(title=f"Sec. 6.2: {path}", xlabel="x [m]", ylabel="y [m]")
            ax.set_aspect("equal", adjustable="datalim")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8)
        written.append(_save(fig, out_dir / "sec6_2_trajectories.png"))
    return written


def _save(fig, path):
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# --------------------------------------------------------------------------- entry points


def _check_selection(tables, speeds):
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


def reproduce(out_dir, fmu_dir=None, workers=None, progress=True, tables=None, speeds=None,
              scheduler=None):
    """Run the paper's experiments and write them beside the paper's numbers.

    Parameters
    ----------
    out_dir : path-like
        Folder for ``reproduction.md``, ``reproduction.json``, the PNGs and ``runs/`` (one
        sweep folder per experiment group; finished runs are reused by input hash).
    fmu_dir : path-like, optional
        Folder of the FMUs, if not beside ``fmus/SystemStructure.ssd``.
    workers : int, optional
        Worker processes of the local Dask cluster (default: the number of CPUs).
    progress : bool
        Print a line per finished experiment group on stderr.
    tables : sequence of str, optional
        Subset of :data:`TABLES` (default all). Table 3 needs the runs of Tables 1 and 2 and
        runs them; Table 9 shares Table 8's runs.
    speeds : sequence of float, optional
        Subset of :data:`PAPER_SPEEDS` for Tables 1-3 (default all five).
    scheduler : str, optional
        Address of a running Dask scheduler instead of a local cluster.

    Returns
    -------
    ReproductionReport

    Raises
    ------
    ConfigError
        For an unknown table or speed (naming the valid choices), or a scenario problem.

    Examples
    --------
    >>> report = reproduce("runs/reproduce", tables=("table1",), speeds=(0.3,))  # doctest: +SKIP
    >>> print(report.to_markdown())                                              # doctest: +SKIP
    """
    selected, speeds = _check_selection(tables, speeds)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paper = load_paper_tables()
    groups = _plan(selected, speeds)
    results = (_run_groups(groups, out_dir, fmu_dir, workers, scheduler, progress)
               if groups else {})
    runs = _collect(results)

    report_tables, claims, figures = {}, [], {}
    if selected & {"table1", "table2", "table3"}:
        t, c = _table13(selected, speeds, runs, paper, figures)
        report_tables.update(t)
        claims += c
    report_tables.update(_table67(selected, paper))
    if selected & {"table8", "table9"}:
        t, c = _table89(selected, runs, paper, figures)
        report_tables.update(t)
        claims += c
    if "sec6_2" in selected:
        t, c = _sec62(runs, figures)
        report_tables.update(t)
        claims += c
    ordered = {name: report_tables[name] for name in (*TABLES,) if name in report_tables}

    settings = {"tables": sorted(selected, key=TABLES.index), "speeds": list(speeds),
                "table13_target_m": list(TABLE13_TARGET), "table13_a_max_m_s2": TABLE13_A_MAX,
                "table13_v_max_m_s": TABLE13_V_MAX, "stop_distance_m": STOP_DISTANCE,
                "sec6_2_stop_time_s": TRACK_STOP_TIME,
                "runs_computed": sum(r.computed for r in results.values()),
                "runs_reused": sum(r.reused for r in results.values())}
    report = ReproductionReport(ordered, claims, settings, out_dir, runs=figures)
    report.figures = _plot(runs, out_dir, speeds)
    report.markdown_path = out_dir / "reproduction.md"
    report.markdown_path.write_text(report.to_markdown())
    report.json_path = out_dir / "reproduction.json"
    report.json_path.write_text(json.dumps(report.to_dict(), indent=2) + "\n")
    return report


def register_cli(subparsers):
    """Add the ``reproduce`` sub-command to an ``argparse`` sub-parser set.

    ``sonotrack reproduce [--out DIR] [--workers N] [--fmu-dir DIR] [--tables T,...] [--quiet]``
    calls :func:`reproduce` and prints the tables and the report's path.
    """
    parser = subparsers.add_parser(
        "reproduce", help="the paper's experiments in simulation beside the paper's numbers")
    parser.add_argument("--out", default="runs/reproduce",
                        help="report folder (default: runs/reproduce)")
    parser.add_argument("--workers", type=int, help="local Dask worker processes (default: CPUs)")
    parser.add_argument("--fmu-dir", help="folder of the FMUs (default: beside the .ssd)")
    parser.add_argument("--tables", help=f"comma-separated subset of {','.join(TABLES)}")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    parser.set_defaults(func=_cmd_reproduce)
    return parser


def _cmd_reproduce(args):
    tables = ([t.strip() for t in args.tables.split(",") if t.strip()]
              if getattr(args, "tables", None) else None)
    report = reproduce(args.out, fmu_dir=args.fmu_dir, workers=args.workers,
                       progress=not args.quiet, tables=tables)
    print(report.to_markdown())
    print(f"report: {report.markdown_path.resolve()}")
    return 0
