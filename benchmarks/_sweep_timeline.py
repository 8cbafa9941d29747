"""Timeline of one sweep's process tree: where sweep_scaling.py's local-engine wall time goes.

:func:`install` wraps, in the sweep's process (before the engine forks its workers, which
inherit the wrappers), the calls the breakdown splits a sweep into: the engine's start (Dask
import and fork), planning, each result's merge into the table, table writes and the
engine's close; in the workers, the warm-up and every task. Each event has its wall interval
(``time.perf_counter``: CLOCK_MONOTONIC, one clock for every process of the machine) and the
CPU time of its process during it. Workers append their events to ``<folder>/<pid>.jsonl``.

:func:`breakdown` turns the events of one sweep into the figures of the JSON's
``breakdown.local`` section. Timing wrappers cost microseconds per call against runs of about
a hundred milliseconds; the instrumented sweep is an extra child, not one of the timed ones.
"""

import json
import os
import statistics
import time
from pathlib import Path

__all__ = ["PARENT", "breakdown", "events", "install", "mark", "serial_breakdown"]

PARENT = []
_STATE = {"folder": None, "original": {}}


def _clock():
    return time.perf_counter(), time.process_time()


def _event(name, started, ended, **extra):
    # cpu: the process's CPU time during the event; cpu_total: since the process started
    return {"name": name, "pid": os.getpid(), "start": started[0], "end": ended[0],
            "cpu": ended[1] - started[1], "cpu_total": ended[1], **extra}


def mark(name):
    """Record an instant of the sweep's process (``start``/``end`` equal)."""
    now = _clock()
    PARENT.append(_event(name, now, now))


def _worker_event(event):
    path = Path(_STATE["folder"]) / f"{os.getpid()}.jsonl"
    with open(path, "a", encoding="utf-8") as stream:
        stream.write(json.dumps(event) + "\n")


def timed_run_task(task, warm=None):
    """``worker.run_task``, its interval written to this worker's event file."""
    started = _clock()
    try:
        return _STATE["original"]["run_task"](task, warm)
    finally:
        _worker_event(_event("task", started, _clock(), key=task.key))


def timed_warm_up(tasks, folder, warm=None):
    """``worker.warm_up``, its interval written to this worker's event file."""
    started = _clock()
    try:
        return _STATE["original"]["warm_up"](tasks, folder, warm)
    finally:
        _worker_event(_event("warm_up", started, _clock()))


def _wrap_parent(owner, attribute, name):
    original = getattr(owner, attribute)

    def timed(*args, **kwargs):
        started = _clock()
        try:
            return original(*args, **kwargs)
        finally:
            PARENT.append(_event(name, started, _clock()))

    setattr(owner, attribute, timed)


def install(folder):
    """Wrap the sweep's calls; workers write their events into ``folder``."""
    from orchestrator.sweep import engine, plan, runs, worker

    _STATE["folder"] = str(folder)
    _STATE["original"].update(run_task=worker.run_task, warm_up=worker.warm_up)
    worker.run_task = timed_run_task  # runs and engine import these at call time
    worker.warm_up = timed_warm_up
    _wrap_parent(engine.LocalEngine, "start", "engine_start")
    _wrap_parent(engine.LocalEngine, "close", "engine_close")
    _wrap_parent(plan, "plan_runs", "plan")
    _wrap_parent(runs._Table, "write", "table_write")
    original_run = engine.LocalEngine.run

    def run(self, function, tasks, on_result):
        def merged(key, result):
            started = _clock()
            try:
                on_result(key, result)
            finally:
                PARENT.append(_event("merge", started, _clock()))

        started = _clock()
        try:
            return original_run(self, function, tasks, on_result=merged)
        finally:
            PARENT.append(_event("engine_run", started, _clock()))

    engine.LocalEngine.run = run


def events():
    """The sweep's process's events and its workers' (JSON-ready), after the sweep."""
    workers = []
    for path in sorted(Path(_STATE["folder"]).glob("*.jsonl")):
        workers += [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()]
    return {"parent": PARENT, "workers": workers, "parent_cpu_s": time.process_time()}


def breakdown(recorded, spawned, exited):
    """Figures of one instrumented sweep (seconds; instants relative to the child's spawn).

    Parameters
    ----------
    recorded : dict
        :func:`events` of the child.
    spawned, exited : float
        ``perf_counter`` just before the child was started and just after it exited.
    """
    parent = {}
    for event in recorded["parent"]:
        parent.setdefault(event["name"], []).append(event)
    workers = {}
    for event in recorded["workers"]:
        workers.setdefault(event["pid"], []).append(event)

    def first(name):
        return parent[name][0] if name in parent else None

    def since(instant):
        return None if instant is None else instant - spawned

    run_start = first("engine_run")["start"]
    per_worker, busy, first_task_starts, last_task_ends = [], [], [], []
    task_walls, task_cpus = [], []
    for pid, events in sorted(workers.items()):
        warm_up = [e for e in events if e["name"] == "warm_up"]
        # (the warm-up's own run goes through run_task too: it is part of the warm-up)
        tasks = sorted((e for e in events if e["name"] == "task" and e["key"] != "warm-up"),
                       key=lambda e: e["start"])
        if not tasks:
            continue
        gaps = [b["start"] - a["end"] for a, b in zip(tasks, tasks[1:])]
        worker_busy = sum(e["end"] - e["start"] for e in tasks)
        busy.append(worker_busy)
        first_task_starts.append(tasks[0]["start"])
        last_task_ends.append(tasks[-1]["end"])
        task_walls += [e["end"] - e["start"] for e in tasks]
        task_cpus += [e["cpu"] for e in tasks]
        per_worker.append({
            "tasks": len(tasks),
            "warm_up_start_s": since(warm_up[0]["start"]) if warm_up else None,
            "warm_up_s": warm_up[0]["end"] - warm_up[0]["start"] if warm_up else None,
            "warm_up_cpu_s": warm_up[0]["cpu"] if warm_up else None,
            "first_task_start_s": since(tasks[0]["start"]),
            "first_task_s": tasks[0]["end"] - tasks[0]["start"],
            "first_task_cpu_s": tasks[0]["cpu"],
            "busy_s": worker_busy,
            "gaps_between_tasks_s": sum(gaps),
            "last_task_end_s": since(tasks[-1]["end"]),
        })
    parallel_start, parallel_end = min(first_task_starts), max(last_task_ends)
    merges = parent.get("merge", [])
    writes = parent.get("table_write", [])
    close = first("engine_close")
    start = first("engine_start")
    plan = first("plan")
    wall = exited - spawned
    sweep_end = first("sweep_end")["start"]
    parallel = parallel_end - parallel_start
    return {
        "wall_s": wall,
        "interpreter_and_imports_s": first("sweep_start")["start"] - spawned,
        "engine_start_s": start["end"] - start["start"],
        "engine_start_cpu_s": start["cpu"],
        # the sweep's process's CPU from its start until the workers are forked: work that
        # only one core can do, whatever the number of workers
        "cpu_before_fork_s": start["cpu_total"],
        "plan_s": plan["end"] - plan["start"],
        "plan_cpu_s": plan["cpu"],
        "dispatch_start_s": since(run_start),
        "first_task_start_s": since(parallel_start),
        "before_first_task_s": parallel_start - spawned,
        "parallel_s": parallel,
        "idle_core_time_in_parallel_s": sum(parallel - b for b in busy),
        "tail_imbalance_s": max(last_task_ends) - min(last_task_ends),
        "after_last_task_s": exited - parallel_end,
        "merge_s": sum(e["end"] - e["start"] for e in merges),
        "table_writes": len(writes),
        "table_writes_s": sum(e["end"] - e["start"] for e in writes),
        "engine_close_s": close["end"] - close["start"] if close else None,
        "exit_s": exited - sweep_end,
        "task_s_median": statistics.median(task_walls),
        "task_cpu_s_median": statistics.median(task_cpus),
        "workers": per_worker,
        "parent_cpu_s": recorded["parent_cpu_s"],
    }


def serial_breakdown(runs, spawned, exited):
    """Figures of one instrumented serial loop: ``runs`` is a list of (start, end, cpu)."""
    later = runs[1:] or runs
    return {
        "wall_s": exited - spawned,
        "interpreter_and_imports_s": runs[0][0] - spawned,
        "first_run_s": runs[0][1] - runs[0][0],
        "first_run_cpu_s": runs[0][2],
        "run_s_median": statistics.median(end - start for start, end, _ in later),
        "run_cpu_s_median": statistics.median(cpu for _, _, cpu in later),
        "runs_s": runs[-1][1] - runs[0][0],
        "after_last_run_s": exited - runs[-1][1],
    }
