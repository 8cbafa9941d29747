"""The acoustic condition of a study cell: free field, or the paper's room.

The paper's experiments ran in a 7 m x 7 m laboratory. The experiments whose results depend
on the localizer's fixes (:data:`FIX_DEPENDENT`: Tables 1-3, Sec. 6.2 with Figs. 7-8 and the
estimates of Figs. 25 and 29) run twice, once in free field (the localizer's default) and once
in the room of ``scenarios/room.toml``: every ``localizer.*`` parameter of that scenario, and
the source's ``emit_period`` that its ``burst_period`` follows (:func:`load_room`). Nothing
else differs between the two conditions, so run *i* of a cell in free field and in the room
share their draws and their geometry.

The room's frame is that of ``scenarios/room.toml``: the robot starts at (0, 0) facing +y,
0.5 m from the wall behind it and centred across the room. Every experiment keeps that start,
so it fits when its source stays inside the box; :func:`room_problems` checks, before any
run, that the microphones at the start and every point of the source's path lie inside the
room (the S-curve's lateral peak is exactly its amplitude, ``paths.py``), and reports the
smallest clearance to a wall. The robot then drives between its start and where it hears the
source; a body that still leaves the room stops its run with one line (the localizer's
refusal), which the study counts as a failed run.
"""

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

from components.common.errors import ConfigError

__all__ = ["FREE_FIELD", "ROOM", "CONDITIONS", "CONDITION_LABELS", "FIX_DEPENDENT",
           "ROOM_SCENARIO", "Room", "load_room", "scenario_parameters", "experiment_points",
           "room_problems",
           "check_room_fits"]

FREE_FIELD, ROOM = "free_field", "room"
CONDITIONS = (FREE_FIELD, ROOM)
CONDITION_LABELS = {FREE_FIELD: "free field", ROOM: "room"}
# The tables whose experiments hear the source through the localizer's fixes and are judged
# on them (the list); Tables 6-9 compare wheel controllers on the same fixes and stay
# in free field.
FIX_DEPENDENT = ("table1", "table2", "table3", "sec6_2")
ROOM_SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "room.toml"
# The source's burst period, which the room's localizer.burst_period must equal.
_SOURCE_KEYS = ("source.emit_period",)


@dataclass(frozen=True)
class Room:
    """The room condition: the localizer's (and source's) parameters, and the box they set.

    Attributes
    ----------
    parameters : dict
        ``instance.parameter`` -> value, applied on top of an experiment's overrides.
    source : str
        Where the parameters were read (a path relative to the repository, for the report).
    """

    parameters: dict
    source: str

    @property
    def box(self):
        """``(x_min, x_max, y_min, y_max)`` of the room in the world frame [m]."""
        p = self.parameters
        x0, y0 = p["localizer.room_origin_x"], p["localizer.room_origin_y"]
        return (x0, x0 + p["localizer.room_length_x"], y0, y0 + p["localizer.room_length_y"])

    def describe(self):
        """One line: size, RT60, heights and where the settings come from."""
        p = self.parameters
        x_min, x_max, y_min, y_max = self.box
        reverberation = (f"RT60 {p['localizer.rt60']:g} s" if p.get("localizer.rt60", 0) > 0
                         else "absorptions " + ", ".join(
                             f"{k.split('_')[-1]} {p[f'localizer.absorption_{k}']:g}"
                             for k in ("walls", "floor", "ceiling")
                             if f"localizer.absorption_{k}" in p))
        return (f"{p['localizer.room_length_x']:g} x {p['localizer.room_length_y']:g} x "
                f"{p.get('localizer.room_height', 2.7):g} m, x in [{x_min:g}, {x_max:g}] m, "
                f"y in [{y_min:g}, {y_max:g}] m, {reverberation}, speaker "
                f"{p.get('localizer.source_height', 0.3):g} m, microphones "
                f"{p.get('localizer.mic_height', 0.2):g} m ({self.source})")


def load_room(path=None):
    """The room condition from a scenario file's ``localizer.*`` and ``source.emit_period``.

    Parameters
    ----------
    path : path-like, optional
        A scenario TOML with ``localizer.room = true`` (default ``scenarios/room.toml``).

    Returns
    -------
    Room

    Raises
    ------
    ConfigError
        If the file cannot be read or does not switch the room on.
    """
    path = Path(ROOM_SCENARIO if path is None else path)
    flat = scenario_parameters(path)
    chosen = {k: v for k, v in flat.items()
              if k.startswith("localizer.") or k in _SOURCE_KEYS}
    if chosen.get("localizer.room") is not True:
        raise ConfigError(f"{path}: localizer.room = {chosen.get('localizer.room')!r}; the "
                          "room condition needs a scenario with localizer.room = true")
    try:
        shown = path.resolve().relative_to(ROOM_SCENARIO.parents[1]).as_posix()
    except ValueError:
        shown = path.name
    return Room(chosen, shown)


def scenario_parameters(path):
    """A scenario file's ``[parameters]`` as ``{"instance.parameter": value}`` (TOML only)."""
    try:
        parameters = tomllib.loads(Path(path).read_text(encoding="utf-8")).get("parameters", {})
    except (OSError, tomllib.TOMLDecodeError) as error:
        raise ConfigError(f"{path}: cannot read the scenario ({error})") from error
    return {f"{instance}.{name}": value for instance, table in parameters.items()
            if isinstance(table, dict) for name, value in table.items()}


def _defaults(part):
    from components.common.ranges import load_ranges

    return {name: entry.start for name, entry in load_ranges(part).parameters.items()}


def experiment_points(parameters):
    """What must lie inside the room for an experiment: named points ``(label, x, y)``.

    The microphones at the robot's start (within ``mic_spacing + |array_offset|`` of its
    reference point, whatever its heading: four points of that circle's bounding square) and
    the source's path (static: its point; straight: both ends; S-curve: the corners of the
    rectangle of its forward extent and its lateral peak ``|amplitude|``).

    Parameters
    ----------
    parameters : dict
        The experiment's overrides; missing values are the FMUs' defaults (``ranges.toml``).
    """
    plant, source, localizer = _defaults("plant"), _defaults("source"), _defaults("acoustics")

    def value(instance, defaults, name):
        return float(parameters.get(f"{instance}.{name}", defaults[name]))

    x, y = value("plant", plant, "x0"), value("plant", plant, "y0")
    reach = (value("localizer", localizer, "mic_spacing")
             + abs(value("localizer", localizer, "array_offset")))
    points = [("microphones at the start", x + dx, y + dy)
              for dx, dy in ((-reach, -reach), (-reach, reach), (reach, -reach), (reach, reach))]
    sx, sy = value("source", source, "x0"), value("source", source, "y0")
    path = parameters.get("source.path", source["path"])
    if path == "static":
        return points + [("source", sx, sy)]
    heading = value("source", source, "heading0")
    length = value("source", source, "length")
    lateral = abs(value("source", source, "amplitude")) if path == "s_curve" else 0.0
    forward, left = (math.cos(heading), math.sin(heading)), (-math.sin(heading),
                                                             math.cos(heading))
    for along in (0.0, length):
        for side in ((-lateral, lateral) if lateral else (0.0,)):
            points.append((f"source path ({path})", sx + along * forward[0] + side * left[0],
                           sy + along * forward[1] + side * left[1]))
    return points


def room_problems(experiments, room):
    """Experiments whose geometry leaves the room, and each one's smallest clearance.

    Parameters
    ----------
    experiments : iterable
        Objects with ``name``, ``scenario`` (a file in ``scenarios/``), ``parameters`` and
        ``cells`` (each cell with ``parameters``); the scenario's own parameters come first.
    room : Room

    Returns
    -------
    problems : list of str
        One line per point outside (experiment, what, where, the room's bounds).
    clearance : dict
        Experiment name -> smallest distance [m] of its points from a wall (negative: outside).
    """
    x_min, x_max, y_min, y_max = room.box
    problems, clearance = [], {}
    for experiment in experiments:
        base = {**scenario_parameters(ROOM_SCENARIO.parent / experiment.scenario),
                **experiment.parameters}
        for cell in experiment.cells or [None]:
            parameters = {**base, **(cell.parameters if cell else {})}
            for label, x, y in experiment_points(parameters):
                inside = min(x - x_min, x_max - x, y - y_min, y_max - y)
                clearance[experiment.name] = min(clearance.get(experiment.name, math.inf),
                                                 inside)
                if inside < 0:      # once per experiment and point, whichever cells share it
                    problems.append(f"{experiment.name}: {label} at ({x:.4g}, {y:.4g}) m "
                                    f"is outside the room (x in [{x_min:g}, {x_max:g}], y in "
                                    f"[{y_min:g}, {y_max:g}] m, {room.source})")
    return sorted(set(problems)), clearance


def check_room_fits(experiments, room):
    """Raise :class:`ConfigError` listing every experiment point outside the room.

    Returns the smallest clearance per experiment (see :func:`room_problems`).
    """
    problems, clearance = room_problems(experiments, room)
    if problems:
        raise ConfigError("the room does not hold the experiments' geometry:\n  "
                          + "\n  ".join(problems))
    return clearance
