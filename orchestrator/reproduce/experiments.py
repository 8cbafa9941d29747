"""The paper's experiments as data: cells, the conditions they vary and what they record.

A *cell* is one experimental condition (a scenario file plus fixed parameter overrides);
an *experiment* groups the cells that share a scenario and a stop time, and runs as one
sweep. Every cell is run ``runs`` times with the same Monte Carlo draws
(:mod:`orchestrator.reproduce.tolerances`), so run ``i`` of two cells differs only in the
cells' own settings: the comparisons between cells are paired.

The study's fixed choices are constants here, each with its reason; the report prints them
all (:func:`configuration`).
"""

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

from .acoustics import FIX_DEPENDENT, FREE_FIELD, ROOM

__all__ = ["TABLES", "PAPER_SPEEDS", "CONTROLLERS", "FEEDFORWARD", "FRICTIONS", "RECORDED",
           "TABLE13_TARGET", "TABLE13_A_MAX", "TABLE13_V_MAX", "STOP_DISTANCE",
           "TRACK_STOP_TIME", "PD_FORMS", "SEC62_SOURCE_START", "SEC62_SOURCE_END_Y",
           "SEC62_SOURCE_LENGTH", "SEC62_MODES",
           "TABLE67_TRACK_WIDTH", "Cell", "Experiment", "plan", "in_room", "t89_cell",
           "table13_stop_time", "configuration"]

TABLES = ("table1", "table2", "table3", "table6", "table7", "table8", "table9", "sec6_2")
PAPER_SPEEDS = (0.1, 0.2, 0.3, 0.4, 0.5)
SCENARIO_DIR = Path(__file__).resolve().parents[2] / "scenarios"

# Sec. 3.6: "the sound source was released at the location of (1.5, 1.5)" and "the level of
# acceleration was set to be 0.5 m/s^2"; v_max = 0.6 m/s is the paper's design limit (Eq. 43),
# needed because the outer wheel of the 1.5 m arc runs 1.10 x the centre speed (0.55 m/s at
# v = 0.5), which the tracking limit 0.4 m/s would cap.
TABLE13_TARGET = (1.5, 1.5)
TABLE13_A_MAX = 0.5
TABLE13_V_MAX = 0.6
# The paper's robot drives to the target (Table 2's distances are whole quarter circles), so
# the planner stops at the heard target itself (Tables 1-3 and 8-9).
STOP_DISTANCE = 0.0
# Sec. 6.2 runs until the source has ended its path (31 s straight, 33.3 s S-curve) and the
# robot has stopped; the scenarios' planner stop_distance (0.5 m) is kept: the paper mutes
# the source "to prevent collisions".
TRACK_STOP_TIME = 40.0
# Sec. 6.2: "when the initial sound source was located at 45 deg to the right of the robot".
# The distance is not printed; the shipped scenarios start the source 1 m from the robot, so
# it starts 1 m away at 45 deg right, facing forward (+y) like the robot.
SEC62_SOURCE_START = (math.sqrt(0.5), math.sqrt(0.5))
# The source stops where scenarios/room.toml's does, 0.5 m short of the far wall of the
# paper's 7 m room (y = 6 m with the robot 0.5 m from the near wall): 5.29 m of path instead
# of the default 6, in free field too, so that the two acoustic conditions share one geometry.
SEC62_SOURCE_END_Y = 6.0
SEC62_SOURCE_LENGTH = SEC62_SOURCE_END_Y - SEC62_SOURCE_START[1]
# Figs. 7-8 compare the curvature planner with rotate-then-go on both paths.
SEC62_MODES = ("curvature", "rotate_then_go")
# Tables 6-7 reproduce the paper's wheel figures only with a 0.40 m track (docs/errata.md):
# those cells run a robot whose planner and plant both have this track width.
TABLE67_TRACK_WIDTH = 0.40

CONTROLLERS = {"pid": "CPID", "fgs_pd": "CFGS-PD"}
# The controllers' motor-model feedforward (on by default in WheelController): the paper does
# not say whether its PD had one, and it decides the controller verdicts, so both are run.
FEEDFORWARD = {"ff_on": True, "ff_off": False}
# Friction conditions of the controller comparison. "nominal" keeps the plant's mu = 0.8. At
# "low" the planner's ramps (a_max = 0.4 m/s^2) need mu >= a/g = 0.041 just to follow the
# reference; 0.05 is the rounded value just above it, where the speed loops' transients exceed
# the traction and the wheels slip (peak slip ratio 0.3-1.7 in a probe run; below 1.2 % at
# mu = 0.1). It was chosen from that physics, not from the paper's numbers.
FRICTIONS = {"mu_nominal": None, "mu_low": 0.05}
# The PD form of FGS-PD (issue 14): when the WheelController build has an integral trim
# (parameter trim_ki, default on), its FGS-PD cells also run as the pure PD of Eq. (46)
# (trim_ki = 0), so the tables show what the choice of form changes. CPID has its own integral.
PD_FORMS = {"as_built": None, "pure_pd": 0.0}

RECORDED = ["source.x", "source.y", "source.emitting", "plant.x", "plant.y", "plant.heading",
            "plant.rim_speed_left", "plant.rim_speed_right", "plant.wheel_speed_left",
            "plant.wheel_speed_right", "plant.encoder_left", "plant.encoder_right",
            "plant.slip_left", "plant.slip_right", "planner.v_ref_left", "planner.v_ref_right",
            "planner.radius", "planner.curvature", "localizer.valid", "localizer.distance",
            "localizer.bearing", "localizer.true_distance", "localizer.true_bearing",
            "localizer.measurement_id", "localizer.fix_attempts"]


@dataclass(frozen=True)
class Cell:
    """One experimental condition.

    Attributes
    ----------
    name : str
        Unique key, e.g. ``"t13_v0.3_curvature"``.
    experiment : str
        The :class:`Experiment` (sweep) it belongs to.
    parameters : dict
        Overrides of this cell on top of the experiment's.
    labels : dict
        What the cell stands for (speed, mode, case, control, feedforward, friction, path).
    condition : str
        The acoustic condition (:mod:`orchestrator.reproduce.acoustics`): free field or room.
    """

    name: str
    experiment: str
    parameters: dict
    labels: dict
    condition: str = FREE_FIELD

    @property
    def key(self):
        """Unique over the study: the name in free field, ``room:<name>`` in the room."""
        return self.name if self.condition == FREE_FIELD else f"{self.condition}:{self.name}"


@dataclass
class Experiment:
    """Cells that share a scenario file, its overrides and a stop time (one sweep)."""

    name: str
    title: str
    scenario: str
    stop_time: float
    parameters: dict
    cells: list = field(default_factory=list)

    def base_scenario(self, stop_time_scale=1.0):
        """The scenario every cell of this experiment starts from."""
        from orchestrator.scenario import load_scenario

        scenario = load_scenario(SCENARIO_DIR / self.scenario)
        stop_time = max(1.0, math.ceil(self.stop_time * stop_time_scale))
        return scenario.with_overrides(name=self.name, stop_time=float(stop_time),
                                       outputs=RECORDED, parameters=self.parameters)


def table13_stop_time(speed):
    """Stop time [s] of a Tables 1-3 run: the path at ``speed`` with margin, whole seconds."""
    # ~2.5 m of path at v, 30 % margin for re-planned legs, plus turns, ramps and the first fix
    return float(math.ceil(3.25 / speed + 5.0))


def _both(parameter, value):
    return {f"controller_left.{parameter}": value, f"controller_right.{parameter}": value}


def t89_cell(case, control, ff, friction, form="as_built"):
    """Name of a Tables 8-9 cell (the built controller's form has no suffix)."""
    suffix = "" if form == "as_built" else f"_{form}"
    return f"t89_{case}_{control}_{ff}_{friction}{suffix}"


def plan(selected, speeds, forms=("as_built",), room=None):
    """The experiments (with their cells) needed for the selected tables.

    Parameters
    ----------
    selected : set of str
        Names from :data:`TABLES`.
    speeds : sequence of float
        Speeds of Tables 1-3.
    forms : sequence of str
        Keys of :data:`PD_FORMS` to run the FGS-PD cells of Tables 8-9 with.
    room : Room, optional
        The room condition (:func:`orchestrator.reproduce.acoustics.load_room`): the
        experiments of the selected :data:`~orchestrator.reproduce.acoustics.FIX_DEPENDENT`
        tables run once more in it, as ``<experiment>_room`` with the same cells.

    Returns
    -------
    list of Experiment
    """
    experiments = []
    if selected & {"table1", "table2", "table3"}:
        for speed in speeds:
            experiment = Experiment(
                f"table13_v{speed:g}", f"Tables 1-3, v = {speed:g} m/s", "static_case1.toml",
                table13_stop_time(speed),
                {"source.path": "static", "source.x0": TABLE13_TARGET[0],
                 "source.y0": TABLE13_TARGET[1], "planner.v_cruise": speed,
                 "planner.v_max": TABLE13_V_MAX, "planner.a_max": TABLE13_A_MAX,
                 "planner.stop_distance": STOP_DISTANCE})
            for mode in ("rotate_then_go", "curvature"):
                experiment.cells.append(Cell(f"t13_v{speed:g}_{mode}", experiment.name,
                                             {"planner.mode": mode},
                                             {"speed": speed, "mode": mode}))
            experiments.append(experiment)
    if selected & {"table6", "table7", "table8", "table9"}:
        for case, scenario in (("static", "static_case1.toml"),
                               ("dynamic", "dynamic_case2.toml")):
            experiment = Experiment(f"table89_{case}", f"Tables 6-9, Case {case}", scenario,
                                    12.0, {"planner.stop_distance": STOP_DISTANCE})
            if selected & {"table8", "table9"}:
                for control in CONTROLLERS:
                    for ff, on in FEEDFORWARD.items():
                        for friction, mu in FRICTIONS.items():
                            for form in (forms if control == "fgs_pd" else ("as_built",)):
                                parameters = {**_both("mode", control),
                                              **_both("feedforward", on)}
                                if mu is not None:
                                    parameters["plant.mu"] = mu
                                if PD_FORMS[form] is not None:
                                    # the trim is the paper form's (components/control)
                                    parameters.update(_both("form", "paper"))
                                    parameters.update(_both("trim_ki", PD_FORMS[form]))
                                experiment.cells.append(Cell(
                                    t89_cell(case, control, ff, friction, form),
                                    experiment.name, parameters,
                                    {"case": case, "control": control, "feedforward": ff,
                                     "friction": friction, "form": form}))
            if selected & {"table6", "table7"}:
                experiment.cells.append(Cell(
                    f"t67_{case}_track040", experiment.name,
                    {**_both("mode", "fgs_pd"), "planner.track_width": TABLE67_TRACK_WIDTH,
                     "plant.track_width": TABLE67_TRACK_WIDTH},
                    {"case": case, "control": "fgs_pd", "track_width": TABLE67_TRACK_WIDTH}))
            experiments.append(experiment)
    if "sec6_2" in selected:
        experiment = Experiment(
            "sec6_2", "Sec. 6.2, straight and S-curve", "s_curve.toml", TRACK_STOP_TIME,
            {"source.x0": SEC62_SOURCE_START[0], "source.y0": SEC62_SOURCE_START[1],
             "source.length": SEC62_SOURCE_LENGTH})
        for path in ("straight", "s_curve"):
            for mode in SEC62_MODES:
                experiment.cells.append(Cell(
                    f"sec62_{path}_{mode}_fgs_pd", experiment.name,
                    {"source.path": path, "planner.mode": mode, **_both("mode", "fgs_pd")},
                    {"path": path, "mode": mode, "control": "fgs_pd"}))
            experiment.cells.append(Cell(
                f"sec62_{path}_curvature_pid", experiment.name,
                {"source.path": path, "planner.mode": "curvature", **_both("mode", "pid")},
                {"path": path, "mode": "curvature", "control": "pid"}))
        experiments.append(experiment)
    if room is not None:
        experiments += [in_room(e, room) for e in experiments
                        if _tables_of(e.name) & set(FIX_DEPENDENT) & selected]
    return experiments


def _tables_of(experiment):
    """The tables an experiment (by name) serves."""
    if experiment.startswith("table13_"):
        return {"table1", "table2", "table3"}
    if experiment.startswith("table89_"):
        return {"table6", "table7", "table8", "table9"}
    return {"sec6_2"} if experiment == "sec6_2" else set()


def in_room(experiment, room):
    """The experiment once more in the room: its overrides plus the room's, the same cells."""
    name = f"{experiment.name}_{ROOM}"
    return Experiment(name, f"{experiment.title}, in the room", experiment.scenario,
                      experiment.stop_time, {**experiment.parameters, **room.parameters},
                      [replace(cell, experiment=name, condition=ROOM)
                       for cell in experiment.cells])


def configuration(forms=("as_built",), room=None):
    """The study's stated assumptions, as printed at the top of the report."""
    form = ("FGS-PD as built has an integral trim (trim_ki, docs/control.md); Tables 8-9 "
            "also run it as the pure PD of Eq. (46) (trim_ki = 0)" if "pure_pd" in forms else
            "FGS-PD as built: the PD of Eq. (46) (this WheelController build has no integral "
            "trim parameter)")
    return {
        "pd_form": form,
        "controller": "WheelController on each wheel; error e = v_ref - v_meas, every gain "
                      "positive. The paper's negative ranges (Kp in [-4, -3], Kd in [-2, -0.3]) "
                      "are read as magnitudes: kp 3..4, kd 0.3..2, 'Big' = the larger magnitude "
                      "(docs/control.md). CPID: kp 3, ki 0.5, kd 1 on the same normalised "
                      "signals.",
        "feedforward": "motor-model feedforward (volts_per_speed x v_ref) on by default; the "
                       "controller claims (Tables 8-9) are judged with it on and off",
        "friction": "plant.mu 0.8 nominal (+-25 %); the controller claims are also judged at "
                    f"mu = {FRICTIONS['mu_low']} (+-25 %), where the planned ramps just "
                    "exceed the traction and the wheels slip",
        "track_width": "0.289 m (Table 11) for every run; Tables 6-7 are also run with a "
                       f"{TABLE67_TRACK_WIDTH} m robot, the width the paper's wheel figures "
                       "imply (docs/errata.md)",
        "rates": "source and localizer 10 ms, planner, controllers and plant 20 ms "
                 "(scenarios/s_curve.toml); one localizer fix per 100 ms; results recorded "
                 "every 20 ms",
        "tables_1_3": f"static source at {TABLE13_TARGET} m, v_max {TABLE13_V_MAX} m/s, "
                      f"a_max {TABLE13_A_MAX} m/s^2, planner stop distance {STOP_DISTANCE} m",
        "tables_8_9": "scenarios static_case1.toml / dynamic_case2.toml, planner stop "
                      f"distance {STOP_DISTANCE} m, 12 s",
        "sec_6_2": "source starts 1 m away at 45 deg right of the robot (paper Sec. 6.2.1), "
                   "drives its straight or S-curve path at 0.2 m/s for "
                   f"{SEC62_SOURCE_LENGTH:.3g} m (ending 0.5 m short of the far wall of the "
                   "paper's 7 m room) and mutes at the end; "
                   f"planner stop distance 0.5 m; {TRACK_STOP_TIME:g} s",
        "acoustics": ("free field (the localizer's default) for every experiment" if room is None
                      else "free field for every experiment; Tables 1-3 and Sec. 6.2 (Figs. "
                      "7-8, 25, 29) also in the room, " + room.describe() + ", the robot at "
                      "(0, 0) facing +y as there: 0.5 m from the wall behind it, centred "
                      "across the room; run i shares its draws in both conditions"),
    }
