"""scenarios/room.toml through the built FMUs: the robot follows in the room; leaving it stops."""

import csv
import math
import re

import pytest

from components.common.errors import SimulationError

pytestmark = pytest.mark.integration


def test_closed_loop_in_the_room_is_finite_and_the_robot_arrives(fmu_dir, repo_root, tmp_path):
    from orchestrator.run import run_scenario

    result = run_scenario(repo_root / "scenarios" / "room.toml", tmp_path / "room",
                          progress=False, fmu_dir=fmu_dir, plots=False)
    summary = result.summary
    assert summary["status"] == "ok" and summary["sim_time_s"] == pytest.approx(30.0)
    with open(result.results_csv, newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 1501
    for row in rows:
        for name, value in row.items():
            assert math.isfinite(float(value)), (row["time"], name)
    # The robot arrives: it stops at the planner's stop distance from the source, which
    # halted 0.5 m short of the far wall.
    assert summary["final_distance_to_source_m"] == pytest.approx(summary["stop_distance_m"],
                                                                  abs=0.1)
    final = rows[-1]
    assert float(final["source.y"]) == pytest.approx(6.0, abs=1e-6)
    assert float(final["plant.y"]) > 5.3
    # It heard the room: most fixes valid, each within the localizer's few centimetres.
    attempts = [row for row in rows if row["localizer.fix_status"] != "1"]
    valid = [row for row in attempts if row["localizer.valid"] == "1"]
    assert len(valid) >= 0.8 * len(attempts)


def test_a_source_driving_out_of_the_room_stops_the_run_and_keeps_its_rows(fmu_dir, repo_root,
                                                                          tmp_path):
    from orchestrator.run import run_scenario
    from orchestrator.run.folder import read_summary
    from orchestrator.scenario import load_scenario

    scenario = load_scenario(repo_root / "scenarios" / "room.toml").with_overrides(
        stop_time=12.0, parameters={"source.path": "straight", "source.length": 6.0,
                                    "source.v_max": 1.0, "source.a_max": 1.0})
    with pytest.raises(SimulationError) as caught:
        run_scenario(scenario, tmp_path / "out", progress=False, fmu_dir=fmu_dir, plots=False)
    message = str(caught.value)
    assert "\n" not in message
    assert "instance localizer returned fmi2Discard in doStep at t = " in message
    assert re.search(r"at t = [0-9.]+ s the source is at \([-0-9.e]+, 6\.5[0-9]*, 0\.3\) m, "
                     r"outside the room \(x in \[-3\.5, 3\.5\], y in \[-0\.5, 6\.5\], "
                     r"z in \[0, 2\.7\] m\)", message)
    summary = read_summary(tmp_path / "out")
    assert summary["status"] == "failed"
    with open(tmp_path / "out" / "results.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    # Every step before the source reached the wall, at 0.02 s.
    stopped = float(message.split("doStep at t = ")[1].split(" s")[0])
    assert len(rows) == pytest.approx(stopped / 0.02 + 1, abs=1)
    assert max(float(row["source.y"]) for row in rows) < 6.5


def test_the_built_fmu_serialises_the_room_state_bit_for_bit(fmu_paths):
    from orchestrator.fmu.handle import FmuInstance

    parameters = {"room": True, "rt60": 0.4, "reverb_cut_db": 20.0, "seed": 3}
    names = ["distance", "bearing", "tdoa_12", "tdoa_23", "peak_quality", "true_distance"]

    def drive(instance, k):
        instance.set_values({"source_x": -0.3, "source_y": 2.0 + 0.002 * k, "emitting": True,
                             "robot_x": 0.0, "robot_y": 0.001 * k, "robot_heading": math.pi / 2})
        instance.do_step(k * 0.01, 0.01)
        return instance.get_values(names + ["measurement_id"])

    first = FmuInstance(fmu_paths["AcousticLocalizer"], "first")
    first.instantiate(parameters=parameters)
    # Saved just before a fix whose earlier bursts were emitted before the save.
    for k in range(39):
        drive(first, k)
    state = first.get_state()
    data = first.serialize_state(state)
    first.free_state(state)
    trace = [drive(first, k) for k in range(39, 70)]
    second = FmuInstance(fmu_paths["AcousticLocalizer"], "second")
    second.instantiate(parameters=parameters)
    restored = second.deserialize_state(data)
    second.set_state(restored)
    second.free_state(restored)
    again = [drive(second, k) for k in range(39, 70)]
    assert again == trace
    assert trace[1]["measurement_id"] == trace[0]["measurement_id"] + 1   # the fix at 0.4 s
    assert trace[-1]["measurement_id"] >= 6
    first.terminate()
    second.terminate()
