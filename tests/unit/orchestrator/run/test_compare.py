"""``sonotrack compare``: two run folders in, overlaid figures and a table of figures out."""

import json

import numpy as np
import pytest

from components.common.errors import ConfigError
from orchestrator.run.compare import compare_runs
from orchestrator.run.recorder import Recorder

COLUMNS = ["source.x", "source.y", "plant.x", "plant.y", "plant.rim_speed_left",
           "plant.rim_speed_right"]


def _run_folder(path, speed, status="ok"):
    """A finished run: the robot drives +y at ``speed`` for 2 s; its summary says so."""
    path.mkdir(parents=True)
    with Recorder(path / "results.csv", COLUMNS) as recorder:
        for k in range(101):
            t = 0.02 * k
            recorder.record(t, [0.0, 3.0, 0.0, speed * t, speed, speed])
    summary = {"scenario": "straight", "controller": "fgs_pd", "status": status, "seed": 1,
               "stop_distance_m": 0.5, "final_distance_to_source_m": 3.0 - 2 * speed,
               "path_rmse_m": 0.0, "robustness": {"faults": []}}
    (path / "summary.json").write_text(json.dumps(summary), encoding="utf-8")
    return path


def test_two_runs_give_two_figures_and_a_table_of_their_figures(tmp_path):
    slow = _run_folder(tmp_path / "slow", 0.2)
    fast = _run_folder(tmp_path / "fast", 0.3)
    result = compare_runs([slow, fast], tmp_path / "out")
    assert result.labels == ["slow", "fast"]
    rows = {row[0]: row[1:] for row in result.rows}
    assert rows["final_distance_to_source_m"] == [pytest.approx(2.6), pytest.approx(2.4)]
    assert rows["controller"] == ["fgs_pd", "fgs_pd"] and "robustness" not in rows
    assert "wall_time_s" not in rows   # no run has it: no empty row
    for path in result.figures:
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    text = result.markdown.read_text(encoding="utf-8")
    assert "| figure | slow | fast |" in text
    assert "| final_distance_to_source_m | 2.6 | 2.4 |" in text
    assert "![" in text and "comparison_trajectories.png" in text


@pytest.mark.parametrize("make, fragment", [
    (lambda tmp: [_run_folder(tmp / "a", 0.2)], "compare needs two or more run folders, got 1"),
    (lambda tmp: [_run_folder(tmp / "a", 0.2), tmp / "missing"], "missing: no such run folder"),
    (lambda tmp: [_run_folder(tmp / "a", 0.2), _run_folder(tmp / "b", 0.2, "failed")],
     "summary.json status is 'failed', not 'ok'"),
    (lambda tmp: [_run_folder(tmp / "a", 0.2), tmp / "a"], "a: given twice"),
    (lambda tmp: [_run_folder(tmp / "a", 0.2), tmp], "no readable summary.json"),
], ids=["one", "missing", "unfinished", "twice", "not-a-run"])
def test_bad_folders_are_one_line_and_nothing_is_written(tmp_path, make, fragment):
    with pytest.raises(ConfigError) as caught:
        compare_runs(make(tmp_path), tmp_path / "out")
    assert fragment in str(caught.value) and "\n" not in str(caught.value)
    assert not (tmp_path / "out").exists()
