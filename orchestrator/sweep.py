"""Many runs at once: parameter grids and seeds on Dask, stored by a hash of their inputs.

Each run is :func:`orchestrator.run.run_scenario` in a Dask worker process (a
``LocalCluster`` by default, or a scheduler address for a real cluster). A finished run lives
in ``<out>/runs/<hash>/`` where the hash covers the scenario (parameters, steps, seed, the
``.ssd``'s content) and the FMU files, so a sweep that is stopped and started again skips what
is done. The table of all runs goes to ``<out>/sweep.csv`` and ``<out>/sweep.json``.
"""

import csv
import hashlib
import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path

from components.common.errors import ConfigError, SimulationError

__all__ = ["SweepResult", "expand_grid", "parse_assignment", "sweep"]


@dataclass
class SweepResult:
    """Rows of a sweep (one dict per run: its settings, hash, status and summary figures)."""

    rows: list = field(default_factory=list)
    out_dir: Path = None
    table_csv: Path = None
    table_json: Path = None
    computed: int = 0
    reused: int = 0


def parse_assignment(text):
    """Parse ``instance.parameter=v1,v2,...`` into ``(key, [values])`` (numbers where possible).

    Raises
    ------
    ConfigError
        If the text has no ``=`` or no values.
    """
    key, sep, values = text.partition("=")
    key = key.strip()
    if not sep or "." not in key or not values.strip():
        raise ConfigError(f"--set {text!r}: expected instance.parameter=value[,value...], "
                          "e.g. planner.v_cruise=0.2,0.3")
    return key, [_number(v.strip()) for v in values.split(",") if v.strip()]


def _number(text):
    lowered = text.lower()
    if lowered in ("true", "false"):
        return lowered == "true"
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return text


def expand_grid(grid, seeds):
    """All combinations of a ``{key: [values]}`` grid and the seeds, as (overrides, seed)."""
    keys = sorted(grid)
    combinations = itertools.product(*(grid[k] for k in keys)) if keys else [()]
    return [(dict(zip(keys, values)), seed)
            for values in combinations for seed in seeds]


def _fmu_digests(system):
    digests = {}
    for component in system.components:
        path = Path(component.fmu_path)
        if path.name not in digests:
            digests[path.name] = hashlib.sha256(path.read_bytes()).hexdigest()
    return digests


def _run_one(scenario_data, run_dir, fmu_dir):
    """Worker side: one run, its summary back (errors become a failed summary, not a crash)."""
    from orchestrator.run import run_scenario
    from orchestrator.scenario import scenario_from_dict

    scenario = scenario_from_dict(scenario_data)
    try:
        result = run_scenario(scenario, run_dir, progress=False, fmu_dir=fmu_dir, plots=False)
        return result.summary
    except SimulationError as exc:
        summary_path = Path(run_dir) / "summary.json"
        if summary_path.is_file():
            return json.loads(summary_path.read_text())
        return {"status": "failed", "error": str(exc)}


def sweep(base, grid, out_dir, seeds=None, fmu_dir=None, scheduler=None, workers=None,
          progress=True):
    """Run ``base`` over a parameter grid and seeds, resuming from finished runs.

    Parameters
    ----------
    base : Scenario
        The scenario every run starts from.
    grid : dict of str to list
        ``"instance.parameter"`` to the values to try; every combination runs.
    out_dir : path-like
        Folder of the sweep (``runs/<hash>/`` per run, ``sweep.csv``, ``sweep.json``).
    seeds : list of int, optional
        Seeds to run each combination with (default: the scenario's seed).
    fmu_dir : path-like, optional
        Folder of the FMUs, if not beside the ``.ssd``.
    scheduler : str, optional
        Address of a Dask scheduler; default a ``LocalCluster`` on this machine.
    workers : int, optional
        Worker processes of the local cluster (default: the number of CPUs).
    progress : bool
        Show a progress bar.

    Returns
    -------
    SweepResult
    """
    from orchestrator.system import load_system

    out_dir = Path(out_dir)
    seeds = list(seeds) if seeds else [base.seed]
    system = load_system(base.system, fmu_dir=fmu_dir)
    digests = _fmu_digests(system)
    planned = []
    problems = []
    for overrides, seed in expand_grid(grid, seeds):
        try:
            scenario = base.with_overrides(parameters=overrides, seed=seed)
        except ConfigError as exc:
            problems.append(str(exc))
            continue
        key = scenario.input_hash(extra=digests)[:16]
        planned.append((overrides, seed, scenario, key, out_dir / "runs" / key))
    if problems:
        raise ConfigError("; ".join(sorted(set(problems))))

    result = SweepResult(out_dir=out_dir)
    summaries = {}
    pending = []
    for overrides, seed, scenario, key, run_dir in planned:
        summary_path = run_dir / "summary.json"
        if summary_path.is_file():
            summaries[key] = json.loads(summary_path.read_text())
            result.reused += 1
        else:
            pending.append((scenario, key, run_dir))
    if pending:
        summaries.update(_compute(pending, fmu_dir, scheduler, workers, progress))
        result.computed = len(pending)
    for overrides, seed, scenario, key, run_dir in planned:
        row = {**overrides, "seed": seed, "hash": key, "run_dir": str(run_dir)}
        row.update({k: v for k, v in summaries[key].items() if not isinstance(v, (dict, list))})
        result.rows.append(row)
    result.table_json = out_dir / "sweep.json"
    result.table_json.write_text(json.dumps(result.rows, indent=2) + "\n")
    result.table_csv = out_dir / "sweep.csv"
    columns = list(dict.fromkeys(k for row in result.rows for k in row))
    with open(result.table_csv, "w", newline="") as f:
        writer = csv.DictWriter(f, columns)
        writer.writeheader()
        writer.writerows(result.rows)
    return result


def _compute(pending, fmu_dir, scheduler, workers, progress):
    from dask.distributed import Client, LocalCluster, as_completed

    if scheduler:
        client = Client(scheduler)
        cluster = None
    else:
        import os

        cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                               processes=True, dashboard_address=None)
        client = Client(cluster)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(pending), unit="run", desc="sweep")
    try:
        fmu_dir = str(fmu_dir) if fmu_dir is not None else None
        futures = {client.submit(_run_one, scenario.to_dict(), str(run_dir), fmu_dir,
                                 pure=False): key
                   for scenario, key, run_dir in pending}
        summaries = {}
        for future in as_completed(futures):
            summaries[futures[future]] = future.result()
            if bar is not None:
                bar.update(1)
        return summaries
    finally:
        if bar is not None:
            bar.close()
        client.close()
        if cluster is not None:
            cluster.close()
