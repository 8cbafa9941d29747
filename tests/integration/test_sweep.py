"""A small sweep on a Dask LocalCluster, and its resumption from stored runs."""

import json

import pytest

from orchestrator.build import REPO_ROOT
from orchestrator.scenario import load_scenario
from orchestrator.sweep import sweep

pytestmark = pytest.mark.integration


def test_sweep_runs_each_combination_once_and_resumes(fmu_dir, tmp_path):
    base = load_scenario(REPO_ROOT / "scenarios" / "static_case1.toml").with_overrides(
        stop_time=2.0)
    grid = {"planner.v_cruise": [0.2, 0.3]}
    first = sweep(base, grid, tmp_path, fmu_dir=fmu_dir, workers=2, progress=False)
    assert (first.computed, first.reused) == (2, 0)
    assert [row["status"] for row in first.rows] == ["ok", "ok"]
    assert len({row["hash"] for row in first.rows}) == 2
    # a faster cruise speed covers more ground in the same 2 s
    moved = {row["planner.v_cruise"]: row["final_distance_to_source_m"] for row in first.rows}
    assert moved[0.3] < moved[0.2]
    again = sweep(base, grid, tmp_path, fmu_dir=fmu_dir, workers=2, progress=False)
    assert (again.computed, again.reused) == (0, 2)
    assert again.rows == first.rows
    assert json.loads(first.table_json.read_text()) == first.rows
