"""What a sweep runs: ``--set`` grids and seeds expanded into runs, each checked and keyed.

Everything is checked before any run starts, and all problems are reported together: a bad
``--set`` or ``--seeds`` text, a value given twice, an instance or parameter that does not
exist (naming the valid ones), a value the scenario schema refuses. Each planned run gets the
key of everything it reads (:mod:`orchestrator.sweep.inputs`), its folder
``<out>/runs/<key>/`` and the scenario it will run.
"""

import itertools
from dataclasses import dataclass, field
from pathlib import Path

from components.common.errors import ConfigError
from orchestrator.scenario.overrides import assignment_hint, parse_value
from orchestrator.scenario.schema import SEED_MAX

__all__ = ["PlannedRun", "expand_grid", "parse_assignment", "parse_seeds", "plan_runs",
           "plan_scenarios", "varied_parameters"]


@dataclass
class PlannedRun:
    """One run of a sweep.

    Attributes
    ----------
    settings : dict
        What distinguishes it in the table (grid values, ``seed``).
    scenario : orchestrator.scenario.Scenario
        The scenario it runs.
    key : str
        Key of everything it reads (16 hex digits); its folder is ``runs/<key>``.
    run_dir : pathlib.Path
        Its folder (absolute).
    digests : dict
        SHA-256 of every file it reads (see :func:`orchestrator.sweep.inputs.input_digests`).
    """

    settings: dict
    scenario: object
    key: str
    run_dir: Path
    digests: dict = field(default_factory=dict)


def parse_assignment(text):
    """Parse ``instance.parameter=v1,v2,...`` into ``(key, [values])`` (numbers where possible).

    Raises
    ------
    ConfigError
        If the text has no ``=``, no instance, no values, or a value twice.
    """
    key, sep, values = text.partition("=")
    key = key.strip()
    instance, dot, name = key.partition(".")
    if not sep:
        raise ConfigError(assignment_hint(text, example_values="0.2,0.3"))
    if not (instance and dot and name) or not values.strip():
        raise ConfigError(f"--set {text!r}: expected instance.parameter=value[,value...], "
                          "e.g. planner.v_cruise=0.2,0.3")
    parsed = [parse_value(v.strip()) for v in values.split(",") if v.strip()]
    seen = []
    for value in parsed:
        if any(type(value) is type(s) and value == s for s in seen):
            raise ConfigError(f"--set {text!r}: value {value!r} is given twice")
        seen.append(value)
    return key, parsed


def parse_seeds(text):
    """``"1,2,5"`` or ``"1..10"`` (inclusive) into a list of distinct seeds.

    Raises
    ------
    ConfigError
        If the text is neither form, a range is empty (``5..1``), a seed repeats or lies
        outside 0..2**31-1.
    """
    form = "expected a list such as 1,2,3 or an inclusive range such as 1..10"
    text = str(text).strip()
    try:
        if ".." in text:
            first, last = (int(part) for part in text.split("..", 1))
        else:
            seeds = [int(part) for part in text.split(",")]
    except ValueError:
        raise ConfigError(f"--seeds {text!r}: {form}") from None
    if ".." in text:
        if last < first:
            raise ConfigError(f"--seeds {text!r}: the range is empty ({first} > {last}); "
                              f"{form}")
        if last - first >= 1_000_000:
            raise ConfigError(f"--seeds {text!r}: {last - first + 1} seeds; at most 1000000 "
                              "runs per sweep")
        seeds = list(range(first, last + 1))
    if not seeds:
        raise ConfigError(f"--seeds {text!r}: {form}")
    for seed in seeds:
        if not 0 <= seed <= SEED_MAX:
            raise ConfigError(f"--seeds {text!r}: seed {seed} is outside 0..{SEED_MAX}")
    if len(set(seeds)) != len(seeds):
        twice = sorted({s for s in seeds if seeds.count(s) > 1})
        raise ConfigError(f"--seeds {text!r}: seed {twice[0]} is given twice")
    return seeds


def expand_grid(grid, seeds):
    """All combinations of a ``{key: [values]}`` grid and the seeds, as (overrides, seed)."""
    keys = sorted(grid)
    combinations = itertools.product(*(grid[k] for k in keys)) if keys else [()]
    return [(dict(zip(keys, values)), seed)
            for values in combinations for seed in seeds]


def _check_names(system, grid):
    """Problems with grid keys naming no instance or no parameter (each with the choices)."""
    problems = []
    instances = {c.name: c for c in system.components}
    for key in sorted(grid):
        instance, _, name = key.partition(".")
        if instance not in instances:
            problems.append(f"--set {key}: no instance {instance!r}; instances are "
                            f"{', '.join(instances)}")
            continue
        parameters = [v.name for v in instances[instance].model_description.modelVariables
                      if v.causality == "parameter"]
        if name not in parameters:
            problems.append(f"--set {key}: {instance} has no parameter {name!r}; its "
                            f"parameters are {', '.join(parameters)}")
    return problems


def _absolute_files(overrides):
    """File-valued overrides (a waypoint CSV) as absolute paths, from the working folder.

    A ``--set`` value is typed on the command line, so a relative file name means one in the
    folder the command runs in; made absolute here, it names the same file for every worker,
    whatever their working folder (the table keeps the value as given).
    """
    from orchestrator.files.paths import names_a_file

    return {key: str(Path(value).resolve()) if names_a_file(value) else value
            for key, value in overrides.items()}


def plan_runs(base, grid, out_dir, seeds=None, fmu_dir=None, system=None, allow_outside=False):
    """Expand, check and key the runs of a sweep.

    Parameters
    ----------
    base : orchestrator.scenario.Scenario
        The scenario every run starts from.
    grid : dict of str to list
        ``"instance.parameter"`` to values; every combination runs.
    out_dir : path-like
        The sweep's folder.
    seeds : list of int, optional
        Seeds (default: the scenario's).
    fmu_dir : path-like, optional
        Folder of the FMUs, if not beside the ``.ssd``.
    system : orchestrator.system.System, optional
        The base scenario's system, if already loaded.
    allow_outside : bool
        Let the ``.ssd`` name files outside its folder (see :mod:`orchestrator.files.paths`).

    Returns
    -------
    list of PlannedRun
        In grid order; runs with the same key appear once.

    Raises
    ------
    ConfigError
        Listing every problem found.
    """
    from orchestrator.run.parameters import instance_parameters
    from orchestrator.system import load_system

    seeds = list(seeds) if seeds else [base.seed]
    if system is None:
        system = load_system(base.system, fmu_dir=fmu_dir, allow_outside=allow_outside)
    problems = _check_names(system, grid)
    if problems:
        raise ConfigError("; ".join(problems))
    runs = (({**overrides, "seed": seed}, system, base,
             {"parameters": _absolute_files(overrides), "seed": seed})
            for overrides, seed in expand_grid(grid, seeds))
    return _plan(runs, out_dir, instance_parameters)


def plan_scenarios(scenarios, out_dir, settings=None, fmu_dir=None, allow_outside=False,
                   systems=None):
    """Check and key a list of scenarios (e.g. Monte Carlo draws) as runs of one sweep.

    Parameters
    ----------
    scenarios : list of orchestrator.scenario.Scenario
        The runs, each complete (parameters, seed).
    out_dir : path-like
        The sweep's folder.
    settings : list of dict, optional
        What names each run in the table (default: its scenario's name and seed, and every
        parameter whose value is not the same in all the scenarios: a Monte Carlo row carries
        each drawn value, see :func:`varied_parameters`).
    fmu_dir : path-like, optional
        Folder of the FMUs, if not beside the ``.ssd``.
    allow_outside : bool
        Let the ``.ssd`` name files outside its folder (see :mod:`orchestrator.files.paths`).
    systems : dict, optional
        ``.ssd`` path (as in ``scenario.system``) to its system, already loaded with the same
        ``fmu_dir``.

    Returns
    -------
    list of PlannedRun
        In the given order; runs with the same key appear once.

    Raises
    ------
    ConfigError
        Listing every problem found.
    """
    from orchestrator.run.parameters import instance_parameters
    from orchestrator.system import load_system

    scenarios = list(scenarios)
    if settings is None:
        varied = varied_parameters(scenarios)
        settings = [{"scenario": s.name, "seed": s.seed,
                     **{k: s.parameters.get(k) for k in varied}} for s in scenarios]
    settings = list(settings)
    if len(settings) != len(scenarios):
        raise ConfigError(f"{len(settings)} settings for {len(scenarios)} scenarios")
    systems = dict(systems or {})

    def runs():
        for scenario, named in zip(scenarios, settings):
            if scenario.system not in systems:  # each .ssd loaded once, when first needed
                systems[scenario.system] = load_system(scenario.system, fmu_dir=fmu_dir,
                                                       allow_outside=allow_outside)
            yield named, systems[scenario.system], scenario, None

    return _plan(runs(), out_dir, instance_parameters)


def varied_parameters(scenarios):
    """The parameters (``instance.parameter``) whose value differs between ``scenarios``, or
    that some of them do not set, sorted.

    Examples
    --------
    >>> from types import SimpleNamespace as S
    >>> varied_parameters([S(parameters={"plant.mass": 4.4, "planner.mode": "curvature"}),
    ...                    S(parameters={"plant.mass": 4.6, "planner.mode": "curvature"})])
    ['plant.mass']
    """
    keys = sorted({k for s in scenarios for k in s.parameters})
    missing = object()
    return [k for k in keys
            if len({repr(s.parameters.get(k, missing)) for s in scenarios}) > 1]


def _plan(runs, out_dir, check_parameters):
    """The planning loop of :func:`plan_runs` and :func:`plan_scenarios`.

    Each run is checked, keyed by everything it reads and kept once per key; the problems of
    all runs are raised together at the end.

    Parameters
    ----------
    runs : iterable of (dict, orchestrator.system.System, Scenario, dict or None)
        Per run: its settings (its row in the table), its system, its scenario, and the
        changes to make to that scenario (keywords of ``Scenario.with_overrides``; None to run
        it as it is). Read one at a time, so a system can be loaded when first needed.
    out_dir : path-like
        The sweep's folder.
    check_parameters : callable
        ``check_parameters(system, scenario)`` raises ConfigError if the scenario's parameters
        do not fit the system's instances (the run layer's ``instance_parameters``).

    Returns
    -------
    list of PlannedRun
    """
    from orchestrator.sweep.inputs import input_digests, run_key

    out_dir = Path(out_dir).resolve()
    planned, keys, cache, problems = [], set(), {}, []
    for settings, system, scenario, changes in runs:
        try:
            if changes is not None:
                scenario = scenario.with_overrides(**changes)
            check_parameters(system, scenario)
        except ConfigError as exc:
            problems.append(str(exc))
            continue
        digests = input_digests(scenario, system, cache)
        key = run_key(scenario, digests)
        if key not in keys:
            keys.add(key)
            planned.append(PlannedRun(dict(settings), scenario, key, out_dir / "runs" / key,
                                      digests))
    _raise_problems(problems)
    return planned


def _raise_problems(problems):
    """Raise one ConfigError listing each distinct problem once (one line for a single one)."""
    if problems:
        unique = list(dict.fromkeys(problems))
        raise ConfigError(unique[0] if len(unique) == 1 else
                          f"{len(unique)} problems:\n" + "\n".join(f"  {p}" for p in unique))
