"""A reduced paper reproduction on freshly built FMUs: Table 1 at two speeds through Dask."""

import json
import math

import pytest

from orchestrator.reproduce import reproduce

pytestmark = pytest.mark.integration


def test_reduced_reproduction_writes_both_numbers_per_row(fmu_dir, tmp_path):
    report = reproduce(tmp_path / "reproduce", fmu_dir=fmu_dir, workers=2, progress=False,
                       tables=("table1",), speeds=(0.4, 0.5))
    assert report.markdown_path.is_file() and report.json_path.is_file()
    assert [p.name for p in report.figures] == ["table1_2_trajectories.png"]
    assert all(p.stat().st_size > 0 for p in report.figures)

    data = json.loads(report.json_path.read_text())
    assert list(data["tables"]) == ["table1"]
    rows = data["tables"]["table1"]["rows"]
    assert [row["v"] for row in rows] == [0.4, 0.5]
    for row in rows:
        for key in ("distance_m", "error_m", "time_ms"):
            sim, paper = row[key]["sim"], row[key]["paper"]
            assert sim is not None and paper is not None, (key, row)
            assert math.isfinite(sim) and math.isfinite(paper)
        # physical sanity, independent of the paper: the robot ends near the source and drives
        # at least the straight-line distance to (1.5, 1.5)
        assert row["error_m"]["sim"] < 0.2
        assert row["distance_m"]["sim"] >= math.hypot(1.5, 1.5) - 0.05
    assert "| 0.4 |" in report.markdown_path.read_text()

    # the second call finds every run stored by its input hash
    again = reproduce(tmp_path / "reproduce", fmu_dir=fmu_dir, workers=1, progress=False,
                      tables=("table1",), speeds=(0.4, 0.5))
    assert again.settings["runs_computed"] == 0 and again.settings["runs_reused"] == 2
