"""Sweeps end to end: resumption, stale inputs, failed runs, warm workers, a real cluster."""

import json
import os
import pickle
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from orchestrator.builder.fmus import REPO_ROOT
from orchestrator.sweep.dask_cluster import start_cluster, stop_cluster
from orchestrator.run.runner import run_scenario
from orchestrator.scenario import load_scenario
from orchestrator.sweep import plan_runs, sweep
from orchestrator.sweep.runs import _warm_up_tasks
from orchestrator.sweep.worker import RunTask, WarmInstances, run_task, warm_up
from tests.support.process_group import pause_env, wait_for_stopped

pytestmark = pytest.mark.integration

# Figures that depend on the machine's speed or on the process that ran, not on the simulation.
_TIMING = {"wall_time_s", "realtime_factor", "run_dir", "process"}


def _short(stop_time=2.0):
    return load_scenario(REPO_ROOT / "scenarios" / "static_case1.toml").with_overrides(
        stop_time=stop_time)


def _figures(row):
    return {k: v for k, v in row.items() if k not in _TIMING}


def test_sweep_runs_each_combination_once_and_resumes(fmu_dir, tmp_path):
    base = _short()
    grid = {"planner.v_cruise": [0.2, 0.3]}
    first = sweep(base, grid, tmp_path, fmu_dir=fmu_dir, workers=2, progress=False)
    assert (first.computed, first.reused, first.engine) == (2, 0, "local")
    assert [row["status"] for row in first.rows] == ["ok", "ok"]
    assert len({row["hash"] for row in first.rows}) == 2
    # a faster cruise speed covers more ground in the same 2 s
    moved = {row["planner.v_cruise"]: row["final_distance_to_source_m"] for row in first.rows}
    assert moved[0.3] < moved[0.2]
    again = sweep(base, grid, tmp_path, fmu_dir=fmu_dir, workers=2, progress=False)
    assert (again.computed, again.reused) == (0, 2)
    assert again.rows == first.rows
    assert json.loads(first.table_json.read_text()) == first.rows

    # a summary cut short by a kill is not a finished run: it is computed again, no crash
    # each row names its run folder relative to the sweep folder, which can then be moved
    assert [r["run_dir"] for r in first.rows] == [f"runs/{r['hash']}" for r in first.rows]
    summary = tmp_path / first.rows[1]["run_dir"] / "summary.json"
    summary.write_text(summary.read_text()[:40])
    resumed = sweep(base, grid, tmp_path, fmu_dir=fmu_dir, workers=2, progress=False)
    assert (resumed.computed, resumed.reused) == (1, 1)
    assert [_figures(r) for r in resumed.rows] == [_figures(r) for r in first.rows]


def _write_waypoints(path, points):
    path.write_text("x,y\n" + "".join(f"{x},{y}\n" for x, y in points), encoding="utf-8")


def test_editing_a_waypoint_csv_invalidates_the_stored_run(fmu_dir, tmp_path):
    waypoints = tmp_path / "waypoints.csv"
    _write_waypoints(waypoints, [(0.0, 1.0), (0.0, 3.0)])
    base = _short(3.0).with_overrides(parameters={"source.path": str(waypoints)})
    first = sweep(base, {}, tmp_path / "sweep", fmu_dir=fmu_dir, workers=1, progress=False)
    assert (first.computed, first.rows[0]["status"]) == (1, "ok")

    _write_waypoints(waypoints, [(2.0, 1.0), (2.0, 3.0)])  # same name, the source moved 2 m
    second = sweep(base, {}, tmp_path / "sweep", fmu_dir=fmu_dir, workers=1, progress=False)
    assert (second.computed, second.reused) == (1, 0)
    assert second.rows[0]["hash"] != first.rows[0]["hash"]
    fresh = run_scenario(base, tmp_path / "fresh", progress=False, fmu_dir=fmu_dir, plots=False)
    assert second.rows[0]["final_distance_to_source_m"] == \
        fresh.summary["final_distance_to_source_m"]
    assert abs(second.rows[0]["final_distance_to_source_m"]
               - first.rows[0]["final_distance_to_source_m"]) > 0.5


def test_the_key_covers_ssv_files_the_ssd_binds(fmu_dir, tmp_path):
    ssd = (REPO_ROOT / "fmus" / "SystemStructure.ssd").read_text(encoding="utf-8")
    marker = ('source="CurvaturePlanner.fmu">')
    assert ssd.count(marker) == 1
    ssd = ssd.replace(marker, marker + '<ssd:ParameterBindings><ssd:ParameterBinding '
                      'source="planner.ssv"/></ssd:ParameterBindings>')
    for fmu in Path(fmu_dir).glob("*.fmu"):
        shutil.copy(fmu, tmp_path / fmu.name)
    (tmp_path / "SystemStructure.ssd").write_text(ssd, encoding="utf-8")
    ssv = tmp_path / "planner.ssv"

    def key(a_max):
        ssv.write_text(
            '<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/'
            'SystemStructureParameterValues" version="1.0" name="planner"><ssv:Parameters>'
            f'<ssv:Parameter name="a_max"><ssv:Real value="{a_max}"/></ssv:Parameter>'
            '</ssv:Parameters></ssv:ParameterSet>', encoding="utf-8")
        base = _short().with_overrides(system=str(tmp_path / "SystemStructure.ssd"))
        [run] = plan_runs(base, {}, tmp_path / "out")
        assert any(label.startswith("ssv:planner.ssv") for label in run.digests)
        return run.key

    assert key(0.4) == key(0.4)
    assert key(0.3) != key(0.4)


def test_a_failed_run_is_a_row_and_the_sweep_goes_on(fmu_dir, tmp_path):
    broken = tmp_path / "broken.csv"
    broken.write_text("x,y\n0,1\n0,banana\n", encoding="utf-8")
    base = _short(1.0)
    result = sweep(base, {"source.path": [str(broken), "static"]}, tmp_path / "sweep",
                   fmu_dir=fmu_dir, workers=2, progress=False)
    by_path = {row["source.path"]: row for row in result.rows}
    assert by_path["static"]["status"] == "ok"
    assert by_path[str(broken)]["status"] == "failed"
    # the row keeps the model's own reason: the instance, the file, the line and the value
    error = by_path[str(broken)]["error"]
    assert "instance source" in error and f"{broken}, line 3: '0,banana'" in error
    assert (result.computed, result.failed) == (2, 1)
    table = json.loads(result.table_json.read_text())
    assert [row["status"] for row in table] == [row["status"] for row in result.rows]
    # a failed run is not a finished one: the next sweep tries it again
    again = sweep(base, {"source.path": [str(broken), "static"]}, tmp_path / "sweep",
                  fmu_dir=fmu_dir, workers=2, progress=False)
    assert (again.computed, again.reused, again.failed) == (1, 1, 1)


_FRESH_RUN = """
import pickle, sys
from orchestrator.run.runner import run_scenario
scenario, out, fmu_dir = pickle.load(open(sys.argv[1], "rb"))
run_scenario(scenario, out, progress=False, fmu_dir=fmu_dir, plots=False)
"""


def test_a_warm_workers_run_is_bit_identical_to_a_fresh_process(fmu_dir, tmp_path):
    base = _short(2.0)
    other = base.with_overrides(seed=5, parameters={"planner.v_cruise": 0.35,
                                                    "planner.mode": "pure_pursuit"})
    target = base.with_overrides(seed=3, parameters={"planner.v_cruise": 0.25})
    job = tmp_path / "job.pickle"
    job.write_bytes(pickle.dumps((target, str(tmp_path / "fresh"), str(fmu_dir))))
    subprocess.run([sys.executable, "-c", _FRESH_RUN, str(job)], check=True, timeout=300)

    warm = WarmInstances()
    try:
        for name, scenario in (("first", other), ("second", target)):
            summary = run_task(RunTask(scenario, str(tmp_path / name), name, str(fmu_dir)),
                               warm=warm)
            assert summary["status"] == "ok", summary
        assert (warm.created, warm.reused) == (6, 6)  # the second run reset all six instances
    finally:
        warm.clear()
    fresh = (tmp_path / "fresh" / "results.csv").read_bytes()
    assert (tmp_path / "second" / "results.csv").read_bytes() == fresh
    assert (tmp_path / "first" / "results.csv").read_bytes() != fresh
    fresh_summary = json.loads((tmp_path / "fresh" / "summary.json").read_text())
    warm_summary = json.loads((tmp_path / "second" / "summary.json").read_text())
    assert _figures(warm_summary) == _figures(fresh_summary)

    # a pool worker's warm-up (another scenario, cut to a few steps) leaves the same six
    # instances for the first task, which is again bit-identical; its scratch folder goes
    warmed = WarmInstances()
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    try:
        warm_up(_warm_up_tasks(other, str(fmu_dir), 0.02, False), scratch, warm=warmed)
        assert (warmed.created, warmed.reused) == (6, 0)
        assert not scratch.exists()
        summary = run_task(RunTask(target, str(tmp_path / "after_warm_up"), "w", str(fmu_dir)),
                           warm=warmed)
        assert summary["status"] == "ok", summary
        assert (warmed.created, warmed.reused) == (6, 6)
    finally:
        warmed.clear()
    assert (tmp_path / "after_warm_up" / "results.csv").read_bytes() == fresh


def test_a_failed_warm_up_keeps_nothing_and_raises_nothing(fmu_dir, tmp_path):
    broken = tmp_path / "broken.csv"
    broken.write_text("x,y\n0,1\n0,banana\n", encoding="utf-8")
    scenario = _short(1.0).with_overrides(parameters={"source.path": str(broken)})
    warm = WarmInstances()
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    warm_up(_warm_up_tasks(scenario, str(fmu_dir), 0.02, False), scratch, warm=warm)
    # the source refused its path at initialisation: every instance of that run was freed
    assert warm.created >= 1 and not warm._idle
    assert not scratch.exists()


def test_a_real_scheduler_and_two_workers_give_the_local_engines_rows(fmu_dir, tmp_path):
    from distributed import Client

    base = _short(1.0)
    grid = {"planner.v_cruise": [0.2, 0.3]}
    address, processes = start_cluster(
        tmp_path, workers=2, env={**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"})
    try:
        assert address.startswith("tcp://127.0.0.1:")
        with Client(address, timeout="30s") as client:
            assert len(client.scheduler_info()["workers"]) == 2
        on_cluster = sweep(base, grid, tmp_path / "cluster", fmu_dir=fmu_dir, scheduler=address,
                           progress=False)
    finally:
        stop_cluster(processes)
    local = sweep(base, grid, tmp_path / "local", fmu_dir=fmu_dir, workers=2, progress=False)
    assert (on_cluster.engine, local.engine) == ("cluster", "local")
    assert [r["status"] for r in on_cluster.rows] == ["ok", "ok"]
    assert [_figures(r) for r in on_cluster.rows] == [_figures(r) for r in local.rows]


@pytest.mark.parametrize("arguments, fragment", [
    (["--workers", "-1"], "--workers '-1': expected a whole number of worker processes >= 1"),
    (["--workers", "two"], "--workers 'two'"),
    (["--seeds", "5..1"], "--seeds '5..1': the range is empty (5 > 1)"),
    (["--set", "planner.bogus=1"], "planner has no parameter 'bogus'; its parameters are "
                                   "track_width, v_cruise"),
    (["--set", "bogus.x=1"], "no instance 'bogus'; instances are source, localizer"),
    (["--set", "planner.v_cruise=0.2", "--set", "planner.v_cruise=0.3"], "given twice"),
    (["--scheduler", "tcp://127.0.0.1:1"], "--scheduler tcp://127.0.0.1:1: no Dask scheduler "
                                           "answers there"),
], ids=["workers-negative", "workers-word", "seeds-empty", "unknown-parameter",
        "unknown-instance", "set-twice", "no-scheduler"])
def test_bad_sweep_arguments_give_one_line_and_a_nonzero_exit(fmu_dir, tmp_path, arguments,
                                                              fragment):
    completed = subprocess.run(
        [sys.executable, "-m", "orchestrator.cli", "sweep", "scenarios/static_case1.toml",
         "--out", str(tmp_path / "sweep"), "--fmu-dir", str(fmu_dir), "--quiet", *arguments],
        cwd=REPO_ROOT, capture_output=True, text=True, timeout=120)
    assert completed.returncode != 0
    lines = completed.stderr.strip().splitlines()
    assert len(lines) == 1, completed.stderr
    assert fragment in lines[0]
    assert "Traceback" not in completed.stderr
    assert not (tmp_path / "sweep" / "runs").exists()


def test_run_many_on_an_engine_kept_across_calls(fmu_dir, tmp_path):
    from orchestrator.sweep import LocalEngine, run_many

    base = _short(0.5)
    draws = [base.with_overrides(seed=seed, parameters={"plant.mass": mass})
             for seed, mass in ((1, 4.4), (2, 4.6))]
    with LocalEngine(workers=1) as engine:
        first = run_many(draws, tmp_path / "mc", fmu_dir=fmu_dir, engine=engine, progress=False)
        second = run_many(draws + [base.with_overrides(seed=3)], tmp_path / "mc", fmu_dir=fmu_dir,
                          engine=engine, progress=False)
    # a Monte Carlo row carries the value drawn for it
    assert [(r["scenario"], r["seed"], r["plant.mass"], r["status"]) for r in first.rows] == [
        ("static_case1", 1, 4.4, "ok"), ("static_case1", 2, 4.6, "ok")]
    assert (second.computed, second.reused) == (1, 2)
    assert second.rows[:2] == first.rows


def test_run_many_sends_back_the_columns_its_runs_wrote(fmu_dir, tmp_path):
    import numpy as np

    from orchestrator.run import read_results
    from orchestrator.sweep import run_many

    base = _short(0.5)
    draws = [base.with_overrides(seed=seed) for seed in (1, 2)]
    first = run_many(draws, tmp_path / "mc", fmu_dir=fmu_dir, workers=2, progress=False,
                     keep_rows=True)
    assert sorted(first.data) == sorted(row["hash"] for row in first.rows)
    for row in first.rows:
        on_disk = read_results(first.out_dir / row["run_dir"] / "results.csv")
        sent = first.data[row["hash"]]
        assert list(sent) == list(on_disk)
        assert all(np.array_equal(sent[k], on_disk[k], equal_nan=True) for k in on_disk)
    # runs found on disk are for the caller to read; without keep_rows nothing is sent
    again = run_many(draws + [base.with_overrides(seed=3)], tmp_path / "mc", fmu_dir=fmu_dir,
                     workers=1, progress=False, keep_rows=True)
    assert (again.computed, again.reused) == (1, 2)
    assert list(again.data) == [again.rows[2]["hash"]]
    plain = run_many([base.with_overrides(seed=4)], tmp_path / "mc", fmu_dir=fmu_dir,
                     workers=1, progress=False)
    assert plain.computed == 1 and plain.data == {}


def test_runs_alike_share_one_search_for_their_files(fmu_dir, tmp_path):
    from orchestrator.sweep.inputs import input_digests
    from orchestrator.system import load_system

    first, second = tmp_path / "first.csv", tmp_path / "second.csv"
    _write_waypoints(first, [(0.0, 1.0), (0.0, 3.0)])
    _write_waypoints(second, [(2.0, 1.0), (2.0, 3.0)])
    base = _short(1.0)
    system = load_system(base.system, fmu_dir=fmu_dir)
    runs = [base.with_overrides(seed=1, parameters={"plant.mass": 4.4, "source.path": str(first)}),
            base.with_overrides(seed=2, parameters={"plant.mass": 4.6, "source.path": str(first)}),
            base.with_overrides(seed=3, parameters={"plant.mass": 4.6,
                                                    "source.path": str(second)})]
    shared = {}
    digests = [input_digests(run, system, shared) for run in runs]
    assert digests == [input_digests(run, system, {}) for run in runs]   # as found alone
    assert digests[0] == digests[1]
    data = [{k: v for k, v in d.items() if k.startswith("data:source.path")} for d in digests]
    assert len(data[0]) == 1 and data[2] != data[0]
    # a result handed out is the caller's: changing it changes nothing kept
    digests[0]["ssd"] = "changed"
    assert input_digests(runs[0], system, shared)["ssd"] != "changed"


def test_a_killed_sweep_keeps_its_finished_rows_and_resumes(fmu_dir, tmp_path):
    import signal

    out = tmp_path / "sweep"
    scenario = tmp_path / "short.toml"  # 8 runs of 3 s: the sweep is still going after one
    text = (REPO_ROOT / "scenarios" / "static_case1.toml").read_text(encoding="utf-8")
    assert "stop_time = 12.0" in text
    scenario.write_text(text.replace("stop_time = 12.0", 'stop_time = 3.0\nsystem = '
                                     '"SystemStructure.ssd"'), encoding="utf-8")
    shutil.copy(REPO_ROOT / "fmus" / "SystemStructure.ssd", tmp_path / "SystemStructure.ssd")
    command = [sys.executable, "-m", "orchestrator.cli", "sweep", str(scenario),
               "--seeds", "1..8", "--workers", "1", "--out", str(out), "--fmu-dir",
               str(fmu_dir), "--quiet"]
    # The sweep's process stops itself as it starts its third table write, when the second
    # (with at least one finished row) is whole on disk: the kill lands while the sweep runs
    # however fast the machine is (polling for a first row could miss a sweep that fast).
    process = subprocess.Popen(command, cwd=REPO_ROOT, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, start_new_session=True,
                               env=pause_env("open */.sweep.json.*.partial 3"))
    try:
        assert wait_for_stopped(process.pid, timeout=240, process=process) == [process.pid]
        os.killpg(process.pid, signal.SIGKILL)  # the sweep and its worker process
        process.wait(timeout=30)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait(timeout=30)
    kept = json.loads((out / "sweep.json").read_text())  # whole, though killed
    assert 1 <= len(kept) < 8 and all(row["status"] == "ok" for row in kept)
    resumed = sweep(load_scenario(scenario), {}, out, seeds=range(1, 9), fmu_dir=fmu_dir,
                    workers=1, progress=False)
    assert resumed.reused >= len(kept) and resumed.computed == 8 - resumed.reused
    assert [row["status"] for row in resumed.rows] == ["ok"] * 8
    by_seed = {row["seed"]: row for row in resumed.rows}
    for row in kept:
        assert _figures(by_seed[row["seed"]]) == _figures(row)


def test_a_relative_csv_in_set_names_the_file_in_the_working_folder(fmu_dir, tmp_path,
                                                                    monkeypatch):
    monkeypatch.chdir(tmp_path)
    _write_waypoints(tmp_path / "wp.csv", [(0.0, 1.0), (0.0, 3.0)])
    [run] = plan_runs(_short(), {"source.path": ["wp.csv"]}, tmp_path / "out",
                      fmu_dir=fmu_dir)
    assert run.settings["source.path"] == "wp.csv"  # the table shows what was typed
    assert run.scenario.parameters["source.path"] == str(tmp_path / "wp.csv")
    assert any(label.startswith("data:source.path@") for label in run.digests)
    before = run.key
    _write_waypoints(tmp_path / "wp.csv", [(1.0, 1.0), (1.0, 3.0)])
    [run] = plan_runs(_short(), {"source.path": ["wp.csv"]}, tmp_path / "out",
                      fmu_dir=fmu_dir)
    assert run.key != before


def _die_or_wait(task):
    """A task for the engine: -1 kills its worker process (as a crash in native code would),
    any other number waits a little and answers."""
    if task == -1:
        os._exit(70)
    time.sleep(0.3)
    return {"status": "ok", "task": task}


def test_a_task_that_kills_its_worker_fails_alone(tmp_path):
    from orchestrator.sweep import LocalEngine

    tasks = [("die", -1)] + [(f"run{n}", n) for n in range(5)]
    results = {}
    with LocalEngine(workers=2) as engine:
        engine.run(_die_or_wait, tasks, lambda key, result: results.setdefault(key, result))
    assert set(results) == {key for key, _ in tasks}
    assert results["die"]["status"] == "failed"
    assert "died" in results["die"]["error"]
    # the runs that shared the pool with it are computed, not blamed for its crash
    assert {key: r["status"] for key, r in results.items() if key != "die"} == {
        f"run{n}": "ok" for n in range(5)}


def test_a_worker_notices_an_fmu_rebuilt_in_place(fmu_dir, tmp_path):
    import zipfile

    from orchestrator.fmu.handle import extract_once

    for fmu in Path(fmu_dir).glob("*.fmu"):
        shutil.copy(fmu, tmp_path / fmu.name)
    shutil.copy(REPO_ROOT / "fmus" / "SystemStructure.ssd", tmp_path)
    ssd, fmu = tmp_path / "SystemStructure.ssd", tmp_path / "WheelController.fmu"
    warm = WarmInstances()
    first = warm.system(ssd, None)
    assert warm.system(ssd, None) is first
    _, first_folder = extract_once(fmu)
    # rebuilt at the same path: another archive (one more file), another digest
    with zipfile.ZipFile(fmu, "a") as archive:
        archive.writestr("documentation/rebuilt.txt", "rebuilt")
    assert warm.system(ssd, None) is not first  # its model descriptions are read again
    _, folder = extract_once(fmu)
    # the run uses the new build's files, unpacked under the new content's digest
    assert folder != first_folder
    assert Path(folder).name == warm.file_digest(fmu)
