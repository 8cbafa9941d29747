"""The paper's experiments in simulation: a Monte Carlo study beside the paper's numbers.

:func:`reproduce` plans the cells of Sec. 3.6 (Tables 1-3), Sec. 4.2 (Tables 6-9, under
four controller arms, feedforward on / off, five frictions and two readings of CPID's ki) and Sec. 6.2 (straight and S-curve tracking,
Figs. 7-8 and 23-30), runs each cell many times with the seed and the physical parameters
drawn within the tolerances of ``orchestrator/data/tolerances.toml`` (through
:func:`orchestrator.sweep.sweep`, resumable), and writes ``reproduction.json``,
``reproduction.md``, ``reproduction.html`` and ``figures/*.png``. Every figure is a mean with
its 95 % interval; every claim of the paper gets a verdict (supported, weaker than claimed, no
effect, contradicted, inconclusive) from its effect beside the paper's own magnitude, with a
sign test, the lost runs and a reason measured in its cells. Nothing is tuned to the paper.

Modules: :mod:`.experiments` (cells as data), :mod:`.tolerances` (draws), :mod:`.runs`
(sweeps, reading runs), :mod:`.measures` (per-run figures), :mod:`.analysis` (per-cell
figures), :mod:`.statistics` (intervals), :mod:`.claims` (claims, verdicts, measured reasons),
:mod:`.operating_point` (the fixed-PD arm's gains), :mod:`.following` (Sec. 6.2's bounds),
:mod:`.tables_motion`, :mod:`.tables_control` and :mod:`.tables_tracking` (tables, claims,
paper ratios), :mod:`.acoustics` (free field or the
room of ``scenarios/room.toml`` for the fix-dependent tables), :mod:`.side_by_side` (their
claims in both conditions), :mod:`.figures` and :mod:`.plotting`, :mod:`.report` (JSON,
Markdown, HTML), :mod:`.study` and :mod:`.cli`.
"""

from .cli import register_cli
from .experiments import PAPER_SPEEDS, TABLES, configuration, plan
from .paper import load_paper_tables
from .statistics import Estimate, mean_interval, paired_difference
from .study import RUNS_PER_CELL, check_selection, reproduce
from .tables_motion import formula_profiles
from .tolerances import load_tolerances

__all__ = ["PAPER_SPEEDS", "RUNS_PER_CELL", "TABLES", "Estimate", "check_selection",
           "configuration", "formula_profiles", "load_paper_tables", "load_tolerances",
           "mean_interval", "paired_difference", "plan", "register_cli", "reproduce"]
