"""A run's summary figures, kept row by row while it steps, equal the re-read of its file.

The reference is :func:`orchestrator.run.summary.summary_figures` over
:class:`~orchestrator.run.summary.ResultRows`: the chunked re-read of ``results.csv``.
"""

import json
import math

import numpy as np
import pytest

from orchestrator.run import summary as run_metrics
from orchestrator.builder.fmus import REPO_ROOT
from orchestrator.run.runner import run_scenario
from orchestrator.run.results import read_results
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


@pytest.mark.parametrize("path, bound", [
    (SCENARIOS / "s_curve.toml", None),
    (SCENARIOS / "faults" / "lost_fixes.toml", None),   # fault flags and fix statuses
    (SCENARIOS / "s_curve.toml", 100),                   # more rows than kept: no data
], ids=["s_curve", "lost_fixes", "untraced"])
def test_kept_rows_are_the_values_read_back_from_the_file(path, bound, fmu_dir, tmp_path,
                                                          monkeypatch):
    if bound is not None:
        monkeypatch.setattr(run_metrics, "MAX_TRACE_ROWS", bound)
    kept = run_scenario(load_scenario(path), tmp_path / "kept", progress=False,
                        fmu_dir=fmu_dir, plots=False, keep_rows=True)
    if bound is not None:
        assert kept.data is None
        return
    reference = read_results(kept.results_csv)
    assert list(kept.data) == list(reference)
    for name, values in reference.items():
        ours = kept.data[name]
        assert ours.dtype == values.dtype and ours.flags.c_contiguous, name
        assert np.array_equal(ours, values, equal_nan=True), name      # bit for bit
        assert np.array_equal(np.signbit(ours), np.signbit(values)), name
    # the summary is the one written without keeping the rows
    plain = run_scenario(load_scenario(path), tmp_path / "plain", progress=False,
                         fmu_dir=fmu_dir, plots=False)
    assert plain.data is None
    assert (tmp_path / "plain" / "results.csv").read_bytes() == kept.results_csv.read_bytes()
    drop = {"wall_time_s", "realtime_factor", "process"}
    assert ({k: v for k, v in plain.summary.items() if k not in drop}
            == {k: v for k, v in kept.summary.items() if k not in drop})
