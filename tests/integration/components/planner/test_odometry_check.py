"""The odometry check on the paper's scenarios: no trip without an encoder fault.

Each shipped ``scenarios/*.toml`` runs with every planner rule of the fault scenarios on (gate
at the source's top speed, fix timeout, wheel check, odometry check), cut to 15 s of
simulated time to keep the suite fast (the S-curve's first bend and both of the dynamic case's
source positions fall inside). The fault scenarios themselves, encoder_freeze among them, are
checked for trips outside their encoder faults in ``test_faults_closed_loop.py``.
"""

from pathlib import Path

import numpy as np
import pytest

from orchestrator.run.results import read_results
from orchestrator.run.runner import run_scenario
from orchestrator.scenario import load_scenario

pytestmark = pytest.mark.integration

SCENARIOS = sorted((Path(__file__).resolve().parents[4] / "scenarios").glob("*.toml"))
RULES = {"planner.max_target_speed": 0.2,     # SoundSource's v_max
         "planner.target_jump_margin": 0.3, "planner.fix_timeout": 1.0,
         "planner.wheel_check_time": 0.04, "planner.odometry_check": True}
STOP_TIME = 15.0


@pytest.mark.parametrize("path", SCENARIOS, ids=[p.stem for p in SCENARIOS])
def test_no_odometry_trip_without_an_encoder_fault(path, fmu_dir, tmp_path):
    scenario = load_scenario(path)
    assert not scenario.faults
    scenario = scenario.with_overrides(parameters=RULES, outputs=[],
                                       stop_time=min(STOP_TIME, scenario.stop_time))
    result = run_scenario(scenario, tmp_path / "run", progress=False, fmu_dir=fmu_dir,
                          plots=False)
    data = read_results(result.results_csv)
    assert data["planner.odometry_faults"][-1] == 0
    assert result.summary["robustness"]["odometry_check_stops"] == 0
    # the robot did drive (the check had fixes and motion to compare)
    assert np.hypot(data["plant.x"][-1], data["plant.y"][-1]) > 0.3
