"""What happened under faults: counts and extremes of a run, read from ``results.csv`` in chunks.

:func:`fault_summary_from_csv` makes one pass over the recorded columns it needs (those that
are missing are left out of the summary, never guessed) and keeps only running counts, so its
memory does not grow with the run's length. The figures:

- ``faults``: each scheduled fault (kind, target, start, end) with the seconds its target
  reported it active (``<target>.faults_active`` > 0, only if that column was recorded);
- ``invalid_fixes``: failed localizer attempts by reason (:class:`FixStatus` names), read
  from ``localizer.fix_attempts`` and ``localizer.fix_status``: each row whose attempt count
  rose by one holds that attempt's status; attempts between two rows (never, with the default
  recording interval of 20 ms and fixes every 100 ms) are counted as ``"unrecorded"``;
- ``fixes_rejected_by_gate``: the planner's ``rejected_fixes`` at the end;
- ``wheel_check_stops``, ``odometry_check_stops``: the planner's ``wheel_faults`` and
  ``odometry_faults`` at the end (times its wheel check and odometry check stopped the robot);
- ``slip_time_s``: time with either wheel's |slip ratio| above :data:`SLIP_THRESHOLD`;
  ``max_slip_ratio``: largest |slip| of either wheel;
- ``max_body_speed_m_s``: largest |plant.speed|;
- ``stopped_safely``: at the end the body is slower than :data:`STOPPED_SPEED` and it was
  never closer to the source than ``stop_distance / 2``.
"""

import math

import numpy as np

__all__ = ["fault_columns", "fault_summary", "fault_summary_from_csv", "survival", "SLIP_THRESHOLD", "STOPPED_SPEED",
           "SPEED_MARGIN", "FINAL_TOLERANCE"]

# A tyre that slips more than this is past the peak of a typical rubber-on-floor curve
# (about 0.1-0.2): traction falls and the wheel speed no longer measures the body's.
SLIP_THRESHOLD = 0.2
# Slower than this, the robot counts as stopped (the encoder quantum at 20 ms is 26 mm/s).
STOPPED_SPEED = 0.03

def _status_names():
    from components.acoustics.localizer import FixStatus

    return FixStatus.NAMES


def _status_name(code, names):
    return names[code] if 0 <= code < len(names) else f"code {code}"


def fault_columns(faults=()):
    """The recorded columns the fault figures read (``time`` first), for ``faults``."""
    targets = sorted({target for target, _ in faults})
    return (["time", "plant.speed", "plant.slip_left", "plant.slip_right",
             "localizer.fix_attempts", "localizer.fix_status", "planner.rejected_fixes",
             "planner.wheel_faults", "planner.odometry_faults",
             "plant.x", "plant.y", "source.x", "source.y"]
            + [f"{t}.faults_active" for t in targets])


def fault_summary_from_csv(path, faults=(), stop_distance=0.5, chunk_rows=None):
    """Fault figures of a run (see the module docstring), read from its ``results.csv``.

    Parameters
    ----------
    path : path-like
        The run's ``results.csv``.
    faults : sequence of (str, Fault)
        The scenario's ``faults``.
    stop_distance : float
        The planner's stop distance [m].
    chunk_rows : int, optional
        Rows parsed at a time.

    Returns
    -------
    dict
    """
    from orchestrator.run.results import DEFAULT_CHUNK_ROWS, iter_result_chunks, read_header

    header = read_header(path)
    columns = [c for c in fault_columns(faults) if c in header]
    chunks = iter_result_chunks(path, columns, chunk_rows or DEFAULT_CHUNK_ROWS)
    return fault_summary(chunks, header, faults, stop_distance)


def fault_summary(chunks, recorded, faults=(), stop_distance=0.5):
    """Fault figures of a run from its rows in successive blocks (one pass, running counts).

    Parameters
    ----------
    chunks : iterable of dict of str to numpy.ndarray
        Successive blocks of rows, each holding every column of :func:`fault_columns` that
        is in ``recorded``.
    recorded : collection of str
        The columns the run recorded.
    faults : sequence of (str, Fault)
        The scenario's ``faults``.
    stop_distance : float
        The planner's stop distance [m].

    Returns
    -------
    dict
    """
    header = set(recorded)
    targets = sorted({target for target, _ in faults})
    wanted = fault_columns(faults)
    have = {c for c in wanted if c in header}
    missing = [c for c in wanted if c not in header]

    names = _status_names()
    invalid, last_attempts, previous_time = {}, None, None
    slip_time, max_slip, max_speed = 0.0, 0.0, 0.0
    active_time = {t: 0.0 for t in targets}
    rejected = min_distance = last_speed = wheel_stops = odometry_stops = None
    for chunk in chunks:
        time = chunk["time"]
        # each row stands for the interval since the previous row
        dt = np.diff(time, prepend=time[0] if previous_time is None else previous_time)
        previous_time = time[-1]
        if "plant.speed" in have:
            speed = np.abs(chunk["plant.speed"])
            max_speed = max(max_speed, float(speed.max()))
            last_speed = float(speed[-1])
        if {"plant.slip_left", "plant.slip_right"} <= have:
            slip = np.maximum(np.abs(chunk["plant.slip_left"]), np.abs(chunk["plant.slip_right"]))
            max_slip = max(max_slip, float(slip.max()))
            slip_time += float(dt[slip > SLIP_THRESHOLD].sum())
        if {"localizer.fix_attempts", "localizer.fix_status"} <= have:
            attempts = chunk["localizer.fix_attempts"].astype(np.int64)
            status = chunk["localizer.fix_status"].astype(np.int64)
            rise = np.diff(attempts, prepend=attempts[0] if last_attempts is None
                           else last_attempts)
            if last_attempts is None and attempts[0] > 0:
                rise[0] = attempts[0]
            last_attempts = int(attempts[-1])
            for row in np.flatnonzero(rise):
                if status[row] != 0:
                    name = _status_name(int(status[row]), names)
                    invalid[name] = invalid.get(name, 0) + 1
                if rise[row] > 1:
                    invalid["unrecorded"] = invalid.get("unrecorded", 0) + int(rise[row]) - 1
        if "planner.rejected_fixes" in have:
            rejected = int(chunk["planner.rejected_fixes"][-1])
        if "planner.wheel_faults" in have:
            wheel_stops = int(chunk["planner.wheel_faults"][-1])
        if "planner.odometry_faults" in have:
            odometry_stops = int(chunk["planner.odometry_faults"][-1])
        for target in targets:
            column = f"{target}.faults_active"
            if column in have:
                active_time[target] += float(dt[chunk[column] > 0].sum())
        if {"plant.x", "plant.y", "source.x", "source.y"} <= have:
            distance = np.hypot(chunk["plant.x"] - chunk["source.x"],
                                chunk["plant.y"] - chunk["source.y"])
            low = float(distance.min())
            min_distance = low if min_distance is None else min(min_distance, low)

    summary = {
        "faults": [{"kind": fault.kind, "target": target, "start_s": fault.start,
                    "end_s": None if math.isinf(fault.end) else fault.end,
                    **({"channel": fault.channel} if fault.channel else {}),
                    "magnitude": fault.magnitude} for target, fault in faults],
        "faults_active_s": {t: active_time[t] for t in targets
                            if f"{t}.faults_active" in have},
        "invalid_fixes": dict(sorted(invalid.items())),
        "invalid_fixes_total": int(sum(invalid.values())),
        "fixes_rejected_by_gate": rejected,
        "wheel_check_stops": wheel_stops,
        "odometry_check_stops": odometry_stops,
        "slip_threshold": SLIP_THRESHOLD,
        "slip_time_s": slip_time,
        "max_slip_ratio": max_slip,
        "max_body_speed_m_s": max_speed,
        # figures that need these columns are left out or empty, never guessed
        "not_recorded": missing,
    }
    if last_speed is not None and min_distance is not None:
        summary["stopped_safely"] = bool(last_speed < STOPPED_SPEED
                                         and min_distance > 0.5 * stop_distance)
    return summary


# The survival checks of issue 12 (docs/faults.md), with the planner defaults they fall back on.
SPEED_MARGIN = 1.05          # body speed at most 5 % above v_max
FINAL_TOLERANCE = 0.3        # m: final distance within this of stop_distance after a fault ends
_PLANNER_DEFAULTS = {"v_max": 0.4, "stop_distance": 0.5}


def survival(data, scenario):
    """The survival checks of a fault run, each True or False.

    Parameters
    ----------
    data : dict of str to numpy.ndarray
        The run's columns (``orchestrator.run.results.read_results``).
    scenario : Scenario
        The run's scenario (its faults, and the planner's ``v_max`` and ``stop_distance``).

    Returns
    -------
    dict
        ``finite`` (no NaN or inf in any column), ``speed`` (body speed <= 1.05 v_max),
        ``no_collision`` (distance > stop_distance / 2), and ``recovered`` (after faults
        that all end, or a floor patch the robot can leave, final distance within 0.3 m of
        stop_distance) or ``stopped`` (after a permanent fault without a region, final body
        speed below :data:`STOPPED_SPEED`).
    """
    values = {name: float(scenario.parameters.get(f"planner.{name}", default))
              for name, default in _PLANNER_DEFAULTS.items()}
    speed = np.abs(data["plant.speed"])
    distance = np.hypot(data["plant.x"] - data["source.x"], data["plant.y"] - data["source.y"])
    checks = {
        "finite": bool(all(np.all(np.isfinite(column)) for column in data.values())),
        "speed": bool(speed.max() <= SPEED_MARGIN * values["v_max"]),
        "no_collision": bool(distance.min() > 0.5 * values["stop_distance"]),
    }
    # A floor patch stays where it is, but the robot can drive off it: only a permanent fault
    # without a region is one the robot cannot leave behind.
    if any(fault.permanent and not fault.region for _, fault in scenario.faults):
        checks["stopped"] = bool(speed[-1] < STOPPED_SPEED)
    else:
        checks["recovered"] = bool(abs(distance[-1] - values["stop_distance"])
                                   <= FINAL_TOLERANCE)
    return checks
