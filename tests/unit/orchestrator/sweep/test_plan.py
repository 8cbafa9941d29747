"""Sweep plans, ``--set`` / ``--seeds`` parsing and the sweep's files (no runs)."""

import json

import pytest

from components.common.errors import ConfigError
from orchestrator.sweep import expand_grid, parse_assignment, parse_seeds
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
    ("planner.v_cruise", "expected instance.parameter=value"),
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
