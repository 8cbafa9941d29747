"""The fuzzy schedule's median operating point: the gains of the study's fixed-PD arm.

The fixed PD of Tables 8-9 has every element of the default-form CFGS-PD except the schedule;
its gains are the median of the scheduled kp and kd over both wheels while the planner's
reference is not zero, in the paper's two manoeuvres (Cases 1 and 2, nominal parameters, no
draws). Measured by every ``reproduce()`` call that runs Tables 8-9 (two 12 s runs, before
the study's own), from the FMUs the study uses, so the arm follows the default form wherever
it changes; the gains are inputs of the cells, so a changed form gives new cells, never a mix.
"""

import tempfile
from pathlib import Path

import numpy as np

__all__ = ["CASE_SCENARIOS", "median_operating_point"]

CASE_SCENARIOS = ("static_case1.toml", "dynamic_case2.toml")
_GAINS = [f"controller_{side}.{gain}" for side in ("left", "right") for gain in ("kp", "kd")]


def median_operating_point(fmu_dir=None, scenario_dir=None):
    """Median scheduled ``(kp, kd)`` of the default-form CFGS-PD in Cases 1 and 2.

    Parameters
    ----------
    fmu_dir : path-like, optional
        Folder of the FMUs, if not beside ``fmus/SystemStructure.ssd``.
    scenario_dir : path-like, optional
        Folder of the case scenarios (default: the repository's ``scenarios/``).

    Returns
    -------
    (float, float)
        The medians of kp and kd over every sample of both wheels while that wheel's
        reference is not zero.
    """
    from orchestrator.run import run_scenario
    from orchestrator.scenario import load_scenario

    from .experiments import SCENARIO_DIR, STOP_DISTANCE
    from orchestrator.run import read_results

    scenario_dir = Path(scenario_dir or SCENARIO_DIR)
    kp, kd = [], []
    with tempfile.TemporaryDirectory(prefix="sonotrack-operating-point-") as scratch:
        for number, name in enumerate(CASE_SCENARIOS):
            references = [f"planner.v_ref_{side}" for side in ("left", "right")]
            scenario = load_scenario(scenario_dir / name).with_overrides(
                outputs=_GAINS + references,
                parameters={"planner.stop_distance": STOP_DISTANCE,
                            **{f"controller_{side}.{key}": value
                               for side in ("left", "right")
                               for key, value in (("mode", "fgs_pd"), ("form", "default"))}})
            out = Path(scratch) / str(number)
            run_scenario(scenario, out, progress=False, plots=False, fmu_dir=fmu_dir)
            data = read_results(out / "results.csv")
            for side in ("left", "right"):
                moving = np.abs(data[f"planner.v_ref_{side}"]) > 0.0
                kp.append(data[f"controller_{side}.kp"][moving])
                kd.append(data[f"controller_{side}.kd"][moving])
    return float(np.median(np.concatenate(kp))), float(np.median(np.concatenate(kd)))
