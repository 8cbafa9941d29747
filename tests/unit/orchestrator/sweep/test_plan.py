"""Sweep plans, ``--set`` / ``--seeds`` parsing and the sweep's files (no runs, no FMUs)."""

import json
from pathlib import Path
from types import SimpleNamespace

import pytest

from components.common.errors import ConfigError
from orchestrator.scenario import scenario_from_dict
from orchestrator.sweep import (expand_grid, parse_assignment, parse_seeds, plan_runs,
                                plan_scenarios)
from orchestrator.sweep.store import finished_summary, read_summary, write_table


@pytest.mark.parametrize("text, expected", [
    ("planner.v_cruise=0.2,0.3", ("planner.v_cruise", [0.2, 0.3])),
    ("planner.mode=curvature,pure_pursuit", ("planner.mode", ["curvature", "pure_pursuit"])),
    ("localizer.seed=3", ("localizer.seed", [3])),
    ("source.mute_at_end=false,true", ("source.mute_at_end", [False, True])),
    ("controller_left.kp_min=1,1.0", ("controller_left.kp_min", [1, 1.0])),
], ids=["floats", "strings", "int", "bools", "int-and-float-differ"])
def test_assignments_parse_to_typed_values(text, expected):
    assert parse_assignment(text) == expected


@pytest.mark.parametrize("text, message", [
    ("v_cruise=0.2", "expected instance.parameter=value"),
    ("planner.v_cruise", "no '='; write it as one word: --set planner.v_cruise=0.2,0.3"),
    ("planner.v_cruise=", "expected instance.parameter=value"),
    (".v_cruise=1", "expected instance.parameter=value"),
    ("planner.v_cruise=0.2,0.3,0.2", "value 0.2 is given twice"),
], ids=["no-instance", "no-equals", "no-values", "empty-instance", "twice"])
def test_bad_assignments_say_what_is_expected(text, message):
    with pytest.raises(ConfigError, match=message):
        parse_assignment(text)


@pytest.mark.parametrize("text, expected", [
    ("1..4", [1, 2, 3, 4]), ("7", [7]), ("3,1,2", [3, 1, 2]), ("0..0", [0]),
], ids=["range", "one", "list", "zero"])
def test_seeds_parse(text, expected):
    assert parse_seeds(text) == expected


@pytest.mark.parametrize("text, message", [
    ("5..1", r"the range is empty \(5 > 1\)"),
    ("1,1", "seed 1 is given twice"),
    ("-1..2", "seed -1 is outside 0..2147483647"),
    ("2147483648", "outside"),
    ("a..b", "expected a list such as 1,2,3 or an inclusive range"),
    ("", "expected a list"),
    ("1,,2", "expected a list"),
], ids=["empty-range", "twice", "negative", "too-big", "words", "empty", "hole"])
def test_bad_seeds_are_refused_with_the_reason(text, message):
    with pytest.raises(ConfigError, match=message):
        parse_seeds(text)


def test_grid_is_the_full_product_times_seeds():
    runs = expand_grid({"a.x": [1, 2], "b.y": ["p", "q", "r"]}, seeds=[7, 8])
    assert len(runs) == 2 * 3 * 2
    assert ({"a.x": 2, "b.y": "q"}, 8) in runs
    assert expand_grid({}, seeds=[1]) == [({}, 1)]


class _System:
    """A loaded system as the planner reads it: instances, their parameters, files to hash.

    Only the planner's ``v_cruise`` is a parameter, so that any other override is refused by
    the parameter check (the scenario layer accepts every parameter of the range tables).
    """

    def __init__(self, folder):
        ssd = Path(__file__).resolve().parents[4] / "fmus" / "SystemStructure.ssd"
        self.description = SimpleNamespace(path=ssd)
        self.parameter_values = {}
        fmu = Path(folder) / "CurvaturePlanner.fmu"
        fmu.write_bytes(b"not an FMU: only hashed")
        v_cruise = SimpleNamespace(name="v_cruise", causality="parameter", type="Real",
                                   start=0.3)
        self.components = [SimpleNamespace(
            name="planner", fmu_path=fmu,
            model_description=SimpleNamespace(modelVariables=[v_cruise]))]

    def component(self, name):
        return next(c for c in self.components if c.name == name)


def test_plan_runs_keys_each_combination_once_in_its_folder(tmp_path):
    base = scenario_from_dict({"stop_time": 1.0})
    runs = plan_runs(base, {"planner.v_cruise": [0.2, 0.4]}, tmp_path / "out", seeds=[1, 2],
                     system=_System(tmp_path))
    assert [r.settings for r in runs] == [{"planner.v_cruise": v, "seed": s}
                                          for v in (0.2, 0.4) for s in (1, 2)]
    assert [(r.scenario.parameters, r.scenario.seed) for r in runs] == [
        ({"planner.v_cruise": v}, s) for v in (0.2, 0.4) for s in (1, 2)]
    assert len({r.key for r in runs}) == 4
    for run in runs:
        assert len(run.key) == 16 and int(run.key, 16) >= 0
        assert run.run_dir == (tmp_path / "out" / "runs" / run.key).resolve()
        assert set(run.digests) == {"ssd", "fmu:planner"}


def test_plan_runs_reports_every_refused_combination_at_once(tmp_path):
    base = scenario_from_dict({"stop_time": 1.0})
    with pytest.raises(ConfigError) as caught:
        plan_runs(base, {"planner.v_cruise": [0.2, -1.0, 99.0]}, tmp_path / "out",
                  system=_System(tmp_path))
    lines = str(caught.value).splitlines()
    assert lines[0] == "2 problems:"
    assert "-1.0" in lines[1] and "99.0" in lines[2]
    with pytest.raises(ConfigError, match=r"no parameter 'a_max'.*v_cruise"):
        plan_runs(base, {"planner.a_max": [0.5]}, tmp_path / "out", system=_System(tmp_path))


def test_plan_scenarios_keeps_the_first_of_equal_runs_and_reports_all_problems(tmp_path):
    system = _System(tmp_path)
    first = scenario_from_dict({"stop_time": 1.0, "seed": 3})
    again = scenario_from_dict({"stop_time": 1.0, "seed": 3, "name": "same run"})
    other = scenario_from_dict({"stop_time": 1.0, "seed": 4})
    runs = plan_scenarios([first, again, other], tmp_path / "mc",
                          systems={first.system: system})
    assert [r.settings for r in runs] == [{"scenario": "scenario", "seed": 3},
                                          {"scenario": "scenario", "seed": 4}]
    assert runs[0].scenario is first
    assert runs[0].run_dir.parent == (tmp_path / "mc" / "runs").resolve()
    bad = [scenario_from_dict({"stop_time": 1.0, "parameters": {f"planner.{name}": value}})
           for name, value in (("a_max", 0.5), ("mode", "curvature"))]
    with pytest.raises(ConfigError) as caught:
        plan_scenarios([first, *bad], tmp_path / "mc", settings=[{"i": 0}, {"i": 1}, {"i": 2}],
                       systems={first.system: system})
    message = str(caught.value)
    assert message.startswith("2 problems:")
    assert "no parameter 'a_max'" in message and "no parameter 'mode'" in message
    with pytest.raises(ConfigError, match="2 settings for 3 scenarios"):
        plan_scenarios([first, *bad], tmp_path / "mc", settings=[{}, {}])


def test_monte_carlo_rows_carry_every_parameter_that_differs(tmp_path):
    system = _System(tmp_path)
    draws = [scenario_from_dict({"stop_time": 1.0, "seed": seed, "parameters": parameters})
             for seed, parameters in ((1, {"planner.v_cruise": 0.25}),
                                      (2, {"planner.v_cruise": 0.35}), (3, {}))]
    runs = plan_scenarios(draws, tmp_path / "mc", systems={draws[0].system: system})
    # v_cruise is drawn (or left out by one draw): a column; a value all share is not
    same = plan_scenarios(draws[:1] + [draws[0].with_overrides(seed=5)], tmp_path / "mc",
                          systems={draws[0].system: system})
    assert [r.settings for r in same] == [{"scenario": "scenario", "seed": 1},
                                          {"scenario": "scenario", "seed": 5}]
    assert [r.settings for r in runs] == [
        {"scenario": "scenario", "seed": 1, "planner.v_cruise": 0.25},
        {"scenario": "scenario", "seed": 2, "planner.v_cruise": 0.35},
        {"scenario": "scenario", "seed": 3, "planner.v_cruise": None}]


@pytest.mark.parametrize("content", [
    None, "", '{"status": "ok", "final_dist', "[1, 2]", '"ok"', b"\xff\xfe{", "{\"status\": 1}",
    '{"status": "failed", "error": "x"}', '{"status": "interrupted"}',
], ids=["missing", "empty", "truncated", "list", "string", "not-utf8", "odd-status",
        "failed", "interrupted"])
def test_a_run_without_a_finished_summary_is_not_done(tmp_path, content):
    if content is not None:
        path = tmp_path / "summary.json"
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
    assert finished_summary(tmp_path) is None


def test_a_finished_summary_is_read_back(tmp_path):
    (tmp_path / "summary.json").write_text('{"status": "ok", "path_rmse_m": 0.25}')
    assert finished_summary(tmp_path) == {"status": "ok", "path_rmse_m": 0.25}
    assert read_summary(tmp_path / "nothing.json") is None


def test_the_table_is_replaced_whole_and_leaves_no_temporary_file(tmp_path):
    rows = [{"a.x": 1, "seed": 2, "status": "ok", "hash": "h1", "run_dir": "r1", "f": 0.5},
            {"a.x": 2, "seed": 2, "status": "failed", "error": "boom, at t = 1",
             "hash": "h2", "run_dir": "r2"}]
    table_csv, table_json = write_table(rows, tmp_path, settings=["a.x"])
    assert json.loads(table_json.read_text()) == rows
    lines = table_csv.read_text().splitlines()
    assert lines[0] == "a.x,seed,status,error,hash,run_dir,f"
    assert lines[2] == '2,2,failed,"boom, at t = 1",h2,r2,'
    write_table(rows[:1], tmp_path)
    assert json.loads(table_json.read_text()) == rows[:1]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sweep.csv", "sweep.json"]
