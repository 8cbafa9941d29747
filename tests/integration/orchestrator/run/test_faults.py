"""Every shipped fault scenario, closed loop through the built FMUs: does the robot survive?

Survived means: no NaN or inf in any recorded output; body speed never above the planner's
v_max by more than 5 %; never closer to the source than stop_distance / 2; after a fault that
ends, the final distance is within 0.3 m of stop_distance; after a permanent one, the robot
has stopped (a floor patch counts as ending: the robot can drive off it). A kind the loop
does not survive is an xfail with the measured numbers, not a looser assertion. The planner's
odometry check may stop the robot only while an encoder fault is on (or within the fixes it
needs to trip after one ends).
"""

from pathlib import Path

import numpy as np
import pytest

from components.planner.odometry_check import TRIPS_AFTER
from orchestrator.run.results import read_results
from orchestrator.run.runner import run_scenario
from orchestrator.scenario import load_scenario

pytestmark = pytest.mark.integration

SCENARIOS = Path(__file__).resolve().parents[4] / "scenarios" / "faults"
V_MAX = 0.4              # the planner's default v_max, which the scenarios keep
STOP_DISTANCE = 0.5      # the planner's default stop_distance
STOPPED_SPEED = 0.03     # m/s
FIX_PERIOD = 0.1         # the localizer's default, which the scenarios keep
ENCODER_KINDS = ("encoder_skip", "encoder_freeze")

# Kinds the loop does not survive today, with the measured numbers (seed 1).
KNOWN_FAILURES = {
    "encoder_skip": (
        "a trade-off, not a defect: an encoder losing half its counts reads as a wheel at half "
        "speed, which the loop answers as it answers a load, until the planner's odometry check "
        "stops the robot; the default form (its speed observer's disturbance recovers 20 % of "
        "stall in <= 0.98 s on the commissioned grid) reaches 0.424 m/s against the 0.42 m/s "
        "bound; before the observer, of 7 gain sets none both recovered the load within 1 s "
        "and stayed below 0.42 m/s (benchmarks/wheel_loop.py, encoder_skip: 0.472 m/s at "
        "0.90 s recovery, 0.389 m/s at 3.52 s); the paper form peaks at 0.396 m/s and never "
        "recovers the load"),
}


def _cases():
    for path in sorted(SCENARIOS.glob("*.toml")):
        marks = ([pytest.mark.xfail(reason=KNOWN_FAILURES[path.stem], strict=True)]
                 if path.stem in KNOWN_FAILURES else [])
        yield pytest.param(path, id=path.stem, marks=marks)


@pytest.mark.parametrize("path", list(_cases()))
def test_robot_survives_the_fault(path, fmu_dir, tmp_path):
    scenario = load_scenario(path)
    result = run_scenario(scenario, tmp_path / "run", progress=False, fmu_dir=fmu_dir,
                          plots=False)
    data = read_results(result.results_csv)
    for name, column in data.items():
        assert np.all(np.isfinite(column)), f"{name} has NaN or inf"
    speed = np.abs(data["plant.speed"])
    distance = np.hypot(data["plant.x"] - data["source.x"], data["plant.y"] - data["source.y"])
    assert speed.max() <= 1.05 * V_MAX, f"body speed {speed.max():.3f} m/s"
    assert distance.min() > STOP_DISTANCE / 2, f"closest {distance.min():.3f} m"
    robustness = result.summary["robustness"]
    assert robustness["faults"], "the summary lists no fault"
    # a floor patch is permanent but the robot drives off it: it must track again
    permanent = any(fault.permanent and not fault.region for _, fault in scenario.faults)
    if permanent:
        assert speed[-1] < STOPPED_SPEED, f"still moving at {speed[-1]:.3f} m/s"
        assert robustness["stopped_safely"]
    else:
        assert abs(distance[-1] - STOP_DISTANCE) <= 0.3, f"final distance {distance[-1]:.3f} m"
    assert robustness["max_body_speed_m_s"] == pytest.approx(speed.max())
    trips = data["time"][np.flatnonzero(np.diff(data["planner.odometry_faults"]) > 0) + 1]
    windows = [(fault.start, fault.end + (TRIPS_AFTER + 1) * FIX_PERIOD)
               for _, fault in scenario.faults if fault.kind in ENCODER_KINDS]
    outside = [t for t in trips if not any(start <= t <= end for start, end in windows)]
    assert not outside, f"odometry check tripped with no encoder fault at {outside} s"
    assert robustness["odometry_check_stops"] == len(trips)


def test_encoder_skip_is_lost_without_the_odometry_check(fmu_dir, tmp_path):
    """The odometry check is what saves encoder_skip: with it off, the source is lost."""
    scenario = load_scenario(SCENARIOS / "encoder_skip.toml").with_overrides(
        parameters={"planner.odometry_check": False})
    result = run_scenario(scenario, tmp_path / "run", progress=False, fmu_dir=fmu_dir,
                          plots=False)
    data = read_results(result.results_csv)
    distance = np.hypot(data["plant.x"] - data["source.x"], data["plant.y"] - data["source.y"])
    assert distance[-1] > STOP_DISTANCE + 1.0, f"final distance {distance[-1]:.3f} m"
    assert data["planner.odometry_faults"][-1] == 0
