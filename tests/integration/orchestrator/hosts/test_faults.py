"""The FMUs apply their own fault schedule: fmpy's own master, no sonotrack orchestrator."""

import numpy as np
import pytest
from fmpy import simulate_fmu

from components.common.faults import Fault, encode_schedule

pytestmark = pytest.mark.integration


def test_localizer_fmu_applies_its_schedule_in_fmpy(fmu_paths):
    schedule = encode_schedule([Fault("mic_dead", 0.3, 0.6, channel="M3")])
    heading = np.pi / 2
    signals = np.array([(0.0, 0.5, 2.0, True, 0.0, 0.0, heading),
                        (2.0, 0.5, 2.0, True, 0.0, 0.0, heading)],
                       dtype=[("time", float), ("source_x", float), ("source_y", float),
                              ("emitting", bool), ("robot_x", float), ("robot_y", float),
                              ("robot_heading", float)])
    result = simulate_fmu(str(fmu_paths["AcousticLocalizer"]), stop_time=1.0,
                          output_interval=0.1, step_size=0.01, input=signals,
                          start_values={"fault_schedule": schedule},
                          output=["fix_status", "valid", "faults_active", "measurement_id"])
    by_time = {round(float(row["time"]), 2): (int(row["fix_status"]), bool(row["valid"]),
                                               int(row["faults_active"])) for row in result}
    # the fix of instant k*0.1 shows after that step: t = 0.31 .. 0.61 for instants 0.3 .. 0.5
    assert [by_time[t][0] for t in (0.2, 0.4, 0.5, 0.6, 0.7, 0.8)] == [0, 10, 10, 10, 0, 0]
    assert [bool(by_time[t][1]) for t in (0.2, 0.4, 0.7)] == [True, False, True]
    assert by_time[0.5][2] == 1 and by_time[0.8][2] == 0


def test_bad_schedule_is_refused_at_initialisation_with_its_field(fmu_paths):
    from fmpy.fmi1 import FMICallException

    bad = '[{"kind":"mic_dead","start":0,"channel":"M4"}]'
    messages = []
    with pytest.raises(FMICallException):
        simulate_fmu(str(fmu_paths["AcousticLocalizer"]), stop_time=0.1, step_size=0.01,
                     start_values={"fault_schedule": bad},
                     logger=lambda *args: messages.append(args[-1]))
    text = " ".join(m.decode() if isinstance(m, bytes) else str(m) for m in messages)
    assert "fault_schedule[0].channel" in text and "M1, M2, M3" in text, text


def test_libcosim_applies_a_fault_from_the_ssd_like_our_master(fmu_dir, tmp_path):
    """A fault set as a parameter in the .ssd: libcosim and our Jacobi master agree to 1e-12."""
    import csv
    import shutil

    from orchestrator.builder.fmus import FMU_PACKAGES, REPO_ROOT
    from orchestrator.hosts.libcosim import run_libcosim_ssd
    from orchestrator.run.runner import run_scenario
    from orchestrator.scenario import scenario_from_dict
    from orchestrator.ssp import ParameterValue, read_ssd, ssd_to_string

    for name in FMU_PACKAGES:
        shutil.copy2(fmu_dir / f"{name}.fmu", tmp_path)
    system = read_ssd(REPO_ROOT / "fmus" / "SystemStructure.ssd")
    system.component("localizer").parameters["fault_schedule"] = ParameterValue(
        "String", encode_schedule([Fault("mic_dead", 1.0, 3.0, channel="M2")]))
    ssd = tmp_path / "SystemStructure.ssd"
    ssd.write_text(ssd_to_string(system))

    stop = 4.0
    columns = ["plant.x", "plant.y", "localizer.distance", "localizer.bearing",
               "planner.v_ref_left", "controller_left.voltage"]
    _, rows = run_libcosim_ssd(ssd, None, stop, columns)
    theirs = np.array(rows)
    scenario = scenario_from_dict({
        "system": str(ssd), "stop_time": stop, "base_step": system.base_step,
        "steps": {c.name: c.step_size_hint for c in system.components}, "master": "jacobi"})
    result = run_scenario(scenario, tmp_path / "ours", progress=False, plots=False,
                          record_interval=system.base_step)
    with open(result.results_csv) as stream:
        ours_rows = list(csv.DictReader(stream))[1:]      # libcosim: after each step
    ours = np.array([[float(r[c]) for c in columns] for r in ours_rows])
    time = np.array([float(r["time"]) for r in ours_rows])
    assert theirs.shape == ours.shape
    slowest = max(c.step_size_hint for c in system.components)
    ratio = round(slowest / system.base_step)
    common = np.arange(ratio - 1, len(ours), ratio)
    assert float(np.max(np.abs(ours[common] - theirs[common]))) <= 1e-12
    # the fault did act: no new fix while M2 is dead, fixes before and after
    distance = ours[:, columns.index("localizer.distance")]
    during = (time > 1.05) & (time < 3.0)
    assert np.ptp(distance[during]) == 0.0
    assert np.ptp(distance[time < 1.0]) > 0.01 and np.ptp(distance[time > 3.05]) > 0.01
