"""A run's summary figures, kept row by row while it steps, equal the re-read of its file.

The reference is :func:`orchestrator.run.summary.summary_figures` over
:class:`~orchestrator.run.summary.ResultRows`: the chunked re-read of ``results.csv``.
"""

import json
import math

import pytest

from orchestrator.run import summary as run_metrics
from orchestrator.builder.fmus import REPO_ROOT
from orchestrator.run.runner import run_scenario
from orchestrator.run.summary import ResultRows, summary_figures
from orchestrator.scenario import load_scenario
from tests.support.json_leaves import leaves

pytestmark = pytest.mark.integration

SCENARIOS = REPO_ROOT / "scenarios"


@pytest.mark.parametrize("path, record_interval, bound", [
    (SCENARIOS / "s_curve.toml", 0.02, None),
    (SCENARIOS / "straight.toml", 0.01, None),          # 3,001 rows: past one parsed chunk
    (SCENARIOS / "faults" / "lost_fixes.toml", 0.02, None),
    (SCENARIOS / "faults" / "low_friction.toml", 0.02, None),
    (SCENARIOS / "s_curve.toml", 0.02, 100),            # no trace kept: read back instead
], ids=["s_curve", "straight-3001-rows", "lost_fixes", "low_friction", "untraced"])
def test_summary_figures_equal_the_chunked_reread(path, record_interval, bound, fmu_dir,
                                                  tmp_path, monkeypatch):
    if bound is not None:
        monkeypatch.setattr(run_metrics, "MAX_TRACE_ROWS", bound)
    scenario = load_scenario(path)
    result = run_scenario(scenario, tmp_path / "run", progress=False, fmu_dir=fmu_dir,
                          plots=False, record_interval=record_interval)
    reference = summary_figures(ResultRows(result.results_csv), scenario.faults,
                                result.summary["stop_distance_m"])
    on_disk = json.loads(result.summary_json.read_text())
    for key, value in leaves(reference):
        ours = dict(leaves(on_disk))[key]
        if isinstance(value, float):
            assert math.isclose(ours, value, rel_tol=1e-12, abs_tol=1e-12), key
        else:
            assert ours == value, key
    assert on_disk["status"] == "ok" and on_disk["path_rmse_m"] > 0
