"""PNG plots of a run: trajectories, wheel speeds, scheduled gains, localizer fixes.

What each figure shows, so that a person reads it without the code:

- every figure is titled with the scenario and the wheel controller's law
  (:class:`PlotContext`), so plots of two runs never look alike by title;
- time axes shade the stretches in which an injected fault was active (read from the
  ``<instance>.faults_active`` columns the run records);
- the trajectories show the robot's true path and its odometry in different colours and
  dashes, the source's path broken where the source jumps (a target that moves faster than
  :data:`JUMP_SPEED` between two rows was moved, not driven), and a circle of the planner's
  stop distance around the source's last position, where the robot is meant to end;
- the wheel speeds draw the encoder's measurement as thin grey steps underneath, with the
  true rim speed and the reference on top, so the encoder's quantum does not hide them;
- legends sit outside the axes, never over the data.

Drawing stays cheap because each figure is laid out once: figures are made with
:class:`matplotlib.figure.Figure` on an Agg canvas (no pyplot and its global state), with fixed
margins instead of ``tight_layout`` (which draws a figure to measure it before it is drawn
again to be saved). matplotlib is imported only when a plot is drawn, so a run without plots
never pays for it. :func:`draw_figures` returns the figures unsaved (the tests read their
artists); :func:`plot_run` saves them.
"""

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from orchestrator.system.sonotrack import SONOTRACK

__all__ = ["JUMP_SPEED", "PLOT_FILES", "PlotContext", "break_jumps", "draw_figures",
           "fault_spans", "plot_run"]

# Every file plot_run may write: a new run removes an older run's copies before it starts.
PLOT_FILES = ("trajectories.png", "wheel_speeds.png", "gains.png", "localizer.png")

# m/s between two recorded rows above which a position moved by a jump, not by driving: ten
# times the planner's default top speed (0.4 m/s) and far above what the motors can reach.
JUMP_SPEED = 4.0

# Margins (fractions of the figure) that fit the labels of every figure below at its size and
# leave the right-hand strip to the legend; fixed so a figure is drawn once, when it is saved.
_MARGINS = {"left": 0.09, "right": 0.78, "bottom": 0.1, "top": 0.86, "hspace": 0.12}
_LEGEND = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "fontsize": 8,
           "borderaxespad": 0.0}
_FAULT_SHADE = {"color": "tab:red", "alpha": 0.12, "lw": 0}


@dataclass(frozen=True)
class PlotContext:
    """What the plots say about the run beside its data.

    Attributes
    ----------
    scenario : str
        The scenario's name.
    controller : str
        The wheel controllers' law (``fgs_pd``, ``pid``, ``pd``).
    stop_distance : float or None
        The planner's stop distance [m]; None draws no stop circle.
    """

    scenario: str = ""
    controller: str = ""
    stop_distance: float = None

    def title(self, what):
        """``what``, then the scenario and the controller on a second line."""
        about = ", ".join(part for part in (self.scenario and f"scenario {self.scenario}",
                                            self.controller and f"controller {self.controller}")
                          if part)
        return f"{what}\n{about}" if about else what

    def to_dict(self):
        """JSON-able form (the renderer's request carries it)."""
        return asdict(self)


class _Figures:
    """Makes figures on an Agg canvas without pyplot."""

    def __init__(self):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        from orchestrator.report.matplotlib_agg import ensure_bundled_fonts

        ensure_bundled_fonts()
        self._canvas = FigureCanvasAgg
        self._figure = Figure

    def subplots(self, rows=1, columns=1, figsize=None, sharex=False, margins=None):
        fig = self._figure(figsize=figsize)
        self._canvas(fig)
        axes = fig.subplots(rows, columns, sharex=sharex)
        fig.subplots_adjust(**(margins or _MARGINS))
        return fig, axes


def _has(data, *names):
    return all(name in data for name in names)


def break_jumps(x, y, t, speed=JUMP_SPEED):
    """``(x, y)`` with a NaN between two rows where the position jumped.

    Parameters
    ----------
    x, y, t : numpy.ndarray
        Positions [m] and their times [s].
    speed : float
        Above this apparent speed [m/s] between two rows, the step is a jump.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The same points, a NaN row inserted after each jump's first point, so a line plot
        does not draw the jump as motion.

    Examples
    --------
    >>> break_jumps(np.array([0.0, 0.01, 1.0]), np.zeros(3), np.array([0.0, 0.02, 0.04]))[0]
    array([0.  , 0.01,  nan, 1.  ])
    """
    step = np.hypot(np.diff(x), np.diff(y))
    dt = np.diff(t)
    jumps = np.flatnonzero(step > speed * np.where(dt > 0, dt, np.inf)) + 1
    return np.insert(x, jumps, np.nan), np.insert(y, jumps, np.nan)


def fault_spans(data):
    """``[(start, end), ...]`` [s]: where any recorded ``faults_active`` column is > 0.

    Each span runs from the first row a fault is active to the first row it is not (or the
    last row); overlapping faults of several instances merge.
    """
    t = data["time"]
    columns = [SONOTRACK.faults_active(i) for i in
               (SONOTRACK.source, SONOTRACK.localizer, SONOTRACK.planner, SONOTRACK.plant,
                *SONOTRACK.wheel_controllers)]
    active = np.zeros(t.shape, dtype=bool)
    for column in columns:
        if column in data:
            active |= np.asarray(data[column]) > 0
    edges = np.diff(active.astype(np.int8), prepend=0, append=0)
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [(float(t[s]), float(t[min(e, len(t) - 1)])) for s, e in zip(starts, ends)]


def _shade(ax, spans):
    for number, (start, end) in enumerate(spans):
        ax.axvspan(start, end, label="fault active" if number == 0 else None, **_FAULT_SHADE)


def _trajectories(figures, data, context, spans):
    from matplotlib.patches import Circle

    fig, ax = figures.subplots(figsize=(7.5, 6.5), margins={"left": 0.1, "right": 0.7,
                                                            "bottom": 0.09, "top": 0.88})
    t = data["time"]
    (rx, ry), (sx, sy) = SONOTRACK.robot_position, SONOTRACK.source_position
    source_x, source_y = break_jumps(data[sx], data[sy], t)
    ax.plot(source_x, source_y, label="source (true)", lw=2, color="tab:orange")
    before = np.flatnonzero(np.isnan(source_x)) - 1   # the last point before each jump
    if len(before):
        ax.plot(source_x[before], source_y[before], "*", ms=11, mfc="none",
                color="tab:orange", label="source before it jumped")
    ax.plot(data[rx], data[ry], label="robot (true)", lw=2, color="tab:blue", zorder=3)
    ox, oy = SONOTRACK.odometry_position
    if _has(data, ox, oy):
        ax.plot(data[ox], data[oy], ls=(0, (4, 2)), label="robot (odometry)", lw=1.3,
                color="tab:green", zorder=4)
    if spans:
        active = np.zeros(t.shape, dtype=bool)
        for start, end in spans:
            active |= (t >= start) & (t <= end)
        ax.plot(np.where(active, data[rx], np.nan), np.where(active, data[ry], np.nan),
                lw=3.5, color="tab:red", alpha=0.6, label="robot, fault active", zorder=2)
    ax.plot(data[rx][:1], data[ry][:1], "o", color="tab:blue", label="start")
    ax.plot(data[rx][-1:], data[ry][-1:], "s", color="tab:blue", label="robot at the end")
    ax.plot(data[sx][-1:], data[sy][-1:], "*", ms=11, color="tab:orange",
            label="source at the end")
    if context.stop_distance:
        ax.add_patch(Circle((float(data[sx][-1]), float(data[sy][-1])), context.stop_distance,
                            fill=False, ls="--", color="tab:gray",
                            label=f"stop distance {context.stop_distance:g} m"))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(**_LEGEND)
    fig.suptitle(context.title("Trajectories in the plane"))
    return fig


def _wheel_speeds(figures, data, context, spans):
    t = data["time"]
    fig, axes = figures.subplots(2, 1, figsize=(9, 6), sharex=True)
    for ax, side in zip(axes, SONOTRACK.sides):
        # the encoder's 26 mm/s steps underneath, thin and light: the true speed and the
        # reference must stay visible above them
        ax.plot(t, data[SONOTRACK.wheel_speed(side)], drawstyle="steps-post", lw=0.8,
                color="0.6", label="measured (encoder)", zorder=1)
        if SONOTRACK.rim_speed(side) in data:
            ax.plot(t, data[SONOTRACK.rim_speed(side)], lw=1.6, color="tab:blue",
                    label="true rim speed", zorder=3)
        if SONOTRACK.wheel_reference(side) in data:
            ax.plot(t, data[SONOTRACK.wheel_reference(side)], "--", lw=1.3, color="k",
                    label="reference", zorder=4)
        _shade(ax, spans)
        ax.set_ylabel(f"{side} wheel [m/s]")
        ax.grid(True, alpha=0.3)
        ax.legend(**_LEGEND)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(context.title("Wheel speeds and their references"))
    return fig


def _gains(figures, data, context, spans):
    t = data["time"]
    fig, axes = figures.subplots(2, 1, figsize=(9, 5), sharex=True)
    for ax, gain in zip(axes, ("kp", "kd")):
        for side in SONOTRACK.sides:
            ax.plot(t, data[SONOTRACK.gain(side, gain)], label=f"{side} wheel", lw=1)
        _shade(ax, spans)
        ax.set_ylabel(gain)
        ax.grid(True, alpha=0.3)
        ax.legend(**_LEGEND)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(context.title("Controller gains"))
    return fig


def _localizer(figures, data, context, spans):
    t = data["time"]
    distance, bearing, valid = SONOTRACK.fix_columns
    true_distance, true_bearing = _true_fix(data)
    fig, axes = figures.subplots(2, 1, figsize=(9, 5), sharex=True)
    good = np.asarray(data.get(valid, np.ones_like(t))) > 0.5
    axes[0].plot(t, true_distance, label="true", lw=1)
    axes[0].plot(t[good], data[distance][good], ".", ms=2, label="valid fix")
    if context.stop_distance:
        axes[0].axhline(context.stop_distance, color="tab:gray", ls="--", lw=1,
                        label="stop distance")
    axes[0].set_ylabel("distance [m]")
    axes[1].plot(t, np.degrees(true_bearing), label="true", lw=1)
    axes[1].plot(t[good], np.degrees(data[bearing][good]), ".", ms=2, label="valid fix")
    axes[1].set_ylabel("bearing [deg]")
    axes[1].set_xlabel("time [s]")
    for ax in axes:
        _shade(ax, spans)
        ax.grid(True, alpha=0.3)
        ax.legend(**_LEGEND)
    fig.suptitle(context.title("Localizer fixes against the truth (robot centre to source)"))
    return fig


def draw_figures(data, figures=PLOT_FILES, context=None):
    """The figures of a run, drawn but not saved.

    Parameters
    ----------
    data : dict of str to array
        Recorded columns (``time`` and ``instance.port``).
    figures : sequence of str
        Which of :data:`PLOT_FILES` to draw (default all); a figure whose columns were not
        recorded is left out.
    context : PlotContext or dict, optional
        Scenario, controller and stop distance for the titles and the stop circle.

    Returns
    -------
    dict of str to matplotlib.figure.Figure
        File name to figure, in the order of :data:`PLOT_FILES`.

    Raises
    ------
    ValueError
        For a name that is not one of :data:`PLOT_FILES`.
    """
    unknown = sorted(set(figures) - set(PLOT_FILES))
    if unknown:
        raise ValueError(f"unknown plot {', '.join(unknown)}; plots are {', '.join(PLOT_FILES)}")
    if isinstance(context, dict):
        context = PlotContext(**context)
    context = context or PlotContext()
    spans = fault_spans(data)
    needs = {
        "trajectories.png": (_trajectories, SONOTRACK.position_columns),
        "wheel_speeds.png": (_wheel_speeds, tuple(SONOTRACK.wheel_speed(s)
                                                  for s in SONOTRACK.sides)),
        "gains.png": (_gains, SONOTRACK.gain_columns),
        "localizer.png": (_localizer, SONOTRACK.fix_columns[:2] + SONOTRACK.position_columns
                          + (SONOTRACK.robot_heading,)),
    }
    plt = _Figures()
    drawn = {}
    for name in PLOT_FILES:
        draw, columns = needs[name]
        if name in figures and _has(data, *columns):
            drawn[name] = draw(plt, data, context, spans)
    return drawn


def plot_run(data, out_dir, figures=PLOT_FILES, context=None):
    """Write the standard plots of a run and return their paths.

    Parameters
    ----------
    data : dict of str to array
        Recorded columns (``time`` and ``instance.port``).
    out_dir : path-like
        Folder for the PNG files.
    figures : sequence of str
        Which of :data:`PLOT_FILES` to draw (see :func:`draw_figures`).
    context : PlotContext or dict, optional
        See :func:`draw_figures`.

    Returns
    -------
    list of pathlib.Path
    """
    out_dir = Path(out_dir)
    return [_save(fig, out_dir / name)
            for name, fig in draw_figures(data, figures, context).items()]


def _true_fix(data):
    (rx, ry), (sx, sy) = SONOTRACK.robot_position, SONOTRACK.source_position
    dx = data[sx] - data[rx]
    dy = data[sy] - data[ry]
    bearing = np.arctan2(dy, dx) - data[SONOTRACK.robot_heading]
    return np.hypot(dx, dy), (bearing + np.pi) % (2 * np.pi) - np.pi


def _save(fig, path):
    import io

    from orchestrator.run.folder import atomic_write_bytes

    path.parent.mkdir(parents=True, exist_ok=True)
    encoded = io.BytesIO()
    # zlib level 1: a third of the default level's encoding time for a slightly larger file
    fig.savefig(encoded, dpi=110, format="png", pil_kwargs={"compress_level": 1})
    atomic_write_bytes(path, encoded.getvalue(), fsync=False)
    return path
