"""What happened under faults: counts and extremes of a run, in one pass over its rows.

:func:`fault_summary` reads the recorded columns it needs from a row source
(:mod:`orchestrator.run.summary`: the rows kept while recording, or ``results.csv`` read back
in chunks); columns that were not recorded are left out of the summary, never guessed. It
keeps only running counts, so its memory does not grow with the run's length. The columns
are named by the system description (:mod:`orchestrator.system.sonotrack`). The figures:

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
- ``source_speed_at_end_m_s``: the source's speed over the last two rows;
- ``stopped_safely``: whether the robot came to rest without coming too close, asked only of
  a run whose source has stopped (``source_speed_at_end_m_s`` below :data:`STOPPED_SPEED`):
  then True when the body is slower than :data:`STOPPED_SPEED` at the end and was never
  closer to the source than ``stop_distance / 2``. While the source still moves at the end
  the robot is meant to follow it, not to stop, and the figure is None (``null``).
"""

import math

import numpy as np

from orchestrator.run.metrics import source_distance
from orchestrator.system.sonotrack import SONOTRACK

__all__ = ["FINAL_TOLERANCE", "SLIP_THRESHOLD", "SPEED_MARGIN", "STOPPED_SPEED", "fault_columns",
           "fault_summary", "survival"]

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
    """The recorded columns the fault figures read (``time`` first), for ``faults``.

    Parameters
    ----------
    faults : sequence of (str, Fault)
        The scenario's ``faults`` (each target's ``faults_active`` column is read).

    Returns
    -------
    list of str
    """
    targets = sorted({target for target, _ in faults})
    return (["time", SONOTRACK.body_speed, *SONOTRACK.wheel_slips, SONOTRACK.fix_attempts,
             SONOTRACK.fix_status, SONOTRACK.rejected_fixes, SONOTRACK.wheel_check_stops,
             SONOTRACK.odometry_check_stops, *SONOTRACK.position_columns]
            + [SONOTRACK.faults_active(t) for t in targets])


def fault_summary(rows, faults=(), stop_distance=0.5):
    """Fault figures of a run (see the module docstring), in one pass with running counts.

    Parameters
    ----------
    rows : row source
        The run's rows (:class:`~orchestrator.run.summary.RowTrace` or
        :class:`~orchestrator.run.summary.ResultRows`); of :func:`fault_columns` it reads
        those the run recorded.
    faults : sequence of (str, Fault)
        The scenario's ``faults``.
    stop_distance : float
        The planner's stop distance [m].

    Returns
    -------
    dict
    """
    header = set(rows.names)
    targets = sorted({target for target, _ in faults})
    wanted = fault_columns(faults)
    present = [c for c in wanted if c in header]
    have = set(present)
    missing = [c for c in wanted if c not in header]
    speed_column, slip_columns = SONOTRACK.body_speed, SONOTRACK.wheel_slips
    attempts_column, status_column = SONOTRACK.fix_attempts, SONOTRACK.fix_status

    names = _status_names()
    invalid, last_attempts, previous_time = {}, None, None
    slip_time, max_slip, max_speed = 0.0, 0.0, 0.0
    active_time = {t: 0.0 for t in targets}
    rejected = min_distance = last_speed = wheel_stops = odometry_stops = None
    source_tail = None   # the last two rows' (time, source x, source y)
    for chunk in rows.chunks(present):
        time = chunk["time"]
        # each row stands for the interval since the previous row
        dt = np.diff(time, prepend=time[0] if previous_time is None else previous_time)
        previous_time = time[-1]
        if speed_column in have:
            speed = np.abs(chunk[speed_column])
            max_speed = max(max_speed, float(speed.max()))
            last_speed = float(speed[-1])
        if set(slip_columns) <= have:
            slip = np.maximum(np.abs(chunk[slip_columns[0]]), np.abs(chunk[slip_columns[1]]))
            max_slip = max(max_slip, float(slip.max()))
            slip_time += float(dt[slip > SLIP_THRESHOLD].sum())
        if {attempts_column, status_column} <= have:
            attempts = chunk[attempts_column].astype(np.int64)
            status = chunk[status_column].astype(np.int64)
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
        if SONOTRACK.rejected_fixes in have:
            rejected = int(chunk[SONOTRACK.rejected_fixes][-1])
        if SONOTRACK.wheel_check_stops in have:
            wheel_stops = int(chunk[SONOTRACK.wheel_check_stops][-1])
        if SONOTRACK.odometry_check_stops in have:
            odometry_stops = int(chunk[SONOTRACK.odometry_check_stops][-1])
        for target in targets:
            column = SONOTRACK.faults_active(target)
            if column in have:
                active_time[target] += float(dt[chunk[column] > 0].sum())
        if set(SONOTRACK.position_columns) <= have:
            low = float(source_distance(chunk).min())
            min_distance = low if min_distance is None else min(min_distance, low)
            sx, sy = SONOTRACK.source_position
            tail = np.column_stack([time[-2:], chunk[sx][-2:], chunk[sy][-2:]])
            source_tail = tail if source_tail is None else np.vstack([source_tail, tail])[-2:]

    summary = {
        "faults": [{"kind": fault.kind, "target": target, "start_s": fault.start,
                    "end_s": None if math.isinf(fault.end) else fault.end,
                    **({"channel": fault.channel} if fault.channel else {}),
                    "magnitude": fault.magnitude} for target, fault in faults],
        "faults_active_s": {t: active_time[t] for t in targets
                            if SONOTRACK.faults_active(t) in have},
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
    source_speed = _speed_at_end(source_tail)
    if source_speed is not None:
        summary["source_speed_at_end_m_s"] = source_speed
    if last_speed is not None and min_distance is not None:
        moving = source_speed is not None and source_speed >= STOPPED_SPEED
        summary["stopped_safely"] = None if moving else bool(
            last_speed < STOPPED_SPEED and min_distance > 0.5 * stop_distance)
    return summary


def _speed_at_end(tail):
    """Speed [m/s] between the last two ``(time, x, y)`` rows; None with fewer rows."""
    if tail is None or len(tail) < 2 or not tail[1, 0] > tail[0, 0]:
        return None
    return float(np.hypot(*(tail[1, 1:] - tail[0, 1:])) / (tail[1, 0] - tail[0, 0]))


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
    values = {name: float(scenario.parameters.get(f"{SONOTRACK.planner}.{name}", default))
              for name, default in _PLANNER_DEFAULTS.items()}
    speed = np.abs(data[SONOTRACK.body_speed])
    distance = source_distance(data)
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
