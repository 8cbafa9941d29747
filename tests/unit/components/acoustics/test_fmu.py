"""The AcousticLocalizer slave: model description, a manual co-simulation loop, state, refusals."""

import json
import math
import zipfile
from xml.etree import ElementTree

import numpy as np
import pytest

from components.acoustics.fmu import AcousticLocalizer


def make_slave(**parameters):
    slave = AcousticLocalizer(instance_name="localizer")
    for name, value in parameters.items():
        setattr(slave, name, value)
    slave.exit_initialization_mode()
    slave.emitting = True
    slave.source_x, slave.source_y = -1.0, 2.0          # sqrt(5) m at atan(1/2) to the left
    return slave


def outputs(slave):
    return (slave.distance, slave.bearing, slave.valid, slave.tdoa_12, slave.tdoa_23,
            slave.measurement_id, slave.peak_quality, slave.fix_status)


def test_model_description_ports_units_and_no_feedthrough():
    root = AcousticLocalizer(instance_name="x").to_xml()
    variables = {v.get("name"): v for v in root.find("ModelVariables")}
    for name in ("source_x", "source_y", "emitting", "robot_x", "robot_y", "robot_heading"):
        assert variables[name].get("causality") == "input"
    units = {"distance": "m", "bearing": "rad", "tdoa_12": "s", "tdoa_23": "s"}
    for name, unit in units.items():
        assert variables[name].find("Real").get("unit") == unit
    assert variables["measurement_id"].get("variability") == "discrete"
    assert variables["method"].get("causality") == "parameter"
    # Sample-and-hold: every output's dependency list is empty (no algebraic loop via the robot).
    for unknown in root.find("ModelStructure/Outputs"):
        assert unknown.get("dependencies") == ""


def test_manual_loop_fixes_at_fix_period_and_tracks_truth():
    slave = make_slave(snr_db=30.0, seed=1)
    ids = []
    for k in range(50):                                   # 0.5 s at 10 ms: instants 0..0.4
        assert slave.do_step(k * 0.01, 0.01) is True
        ids.append(slave.measurement_id)
    assert ids[0] == 1 and ids[-1] == 5 and ids[10] == 2 and ids[9] == 1
    assert slave.valid
    assert slave.distance == pytest.approx(math.sqrt(5.0), abs=0.03)
    assert slave.bearing == pytest.approx(math.atan2(1.0, 2.0), abs=math.radians(0.2))


def test_state_round_trip_through_json_gives_identical_outputs():
    slave = make_slave(snr_db=10.0, seed=4)
    for k in range(13):
        slave.do_step(k * 0.01, 0.01)
    state = json.loads(json.dumps(slave._get_fmu_state()))
    trace = []
    for k in range(13, 45):
        slave.do_step(k * 0.01, 0.01)
        trace.append(outputs(slave))
    slave._set_fmu_state(state)
    again = []
    for k in range(13, 45):
        slave.do_step(k * 0.01, 0.01)
        again.append(outputs(slave))
    assert again == trace
    assert trace[-1][5] == 5           # instants 0, 0.1 before the save; 0.2, 0.3, 0.4 after


@pytest.mark.parametrize("port", ["source_x", "robot_y", "robot_heading"])
@pytest.mark.parametrize("value", [float("nan"), float("inf")], ids=["nan", "inf"])
def test_non_finite_input_is_refused_with_port_and_value(port, value):
    slave = make_slave()
    setattr(slave, port, value)
    assert slave.do_step(0.0, 0.01) is False
    message = slave.log_queue[-1].msg
    assert port in message and repr(value) in message


@pytest.mark.parametrize("source", [(0.0, 0.0), (0.0, -2.0), (0.0, 40.0)],
                         ids=["array_centre", "behind", "beyond_range"])
def test_unhearable_source_is_invalid_not_an_error(source):
    slave = make_slave()
    slave.source_x, slave.source_y = source
    assert slave.do_step(0.0, 0.01) is True
    assert slave.valid is False and slave.measurement_id == 0


ROOM_PARAMETERS = ("room", "room_origin_x", "room_origin_y", "room_length_x", "room_length_y",
                   "room_height", "absorption_walls", "absorption_floor", "absorption_ceiling",
                   "rt60", "source_height", "mic_height", "reverb_cut_db", "image_order",
                   "burst_period")


def test_room_parameters_come_after_every_published_variable():
    root = AcousticLocalizer(instance_name="x").to_xml()
    references = {v.get("name"): int(v.get("valueReference")) for v in root.find("ModelVariables")}
    room = [references.pop(name) for name in ROOM_PARAMETERS]
    assert room == sorted(room) and min(room) > max(references.values())


def room_slave(**parameters):
    return make_slave(room=True, rt60=0.3, reverb_cut_db=20.0, **parameters)


def test_room_state_round_trip_through_json_gives_identical_outputs():
    # Saved from one instance, restored into a fresh one: the inputs of past steps (the
    # source's positions at earlier emissions) must travel with the state.
    slave = room_slave(seed=4)
    for k in range(23):
        slave.source_y = 2.0 + 0.002 * k
        slave.do_step(k * 0.01, 0.01)
    state = json.loads(json.dumps(slave._get_fmu_state()))
    trace = []
    for k in range(23, 55):
        slave.source_y = 2.0 + 0.002 * k
        assert slave.do_step(k * 0.01, 0.01)
        trace.append(outputs(slave))
    fresh = room_slave(seed=4)
    fresh._set_fmu_state(state)
    again = []
    for k in range(23, 55):
        fresh.source_y = 2.0 + 0.002 * k
        fresh.do_step(k * 0.01, 0.01)
        again.append(outputs(fresh))
    assert again == trace
    assert trace[-1][5] >= 5 and trace[-1][2]


def test_leaving_the_room_refuses_the_step_with_one_line():
    slave = room_slave()
    assert slave.do_step(0.0, 0.01)
    slave.source_y = 6.75
    assert slave.do_step(0.01, 0.01) is False
    message = slave.log_queue[-1].msg
    assert message == ("localizer: at t = 0.01 s the source is at (-1, 6.75, 0.3) m, outside "
                       "the room (x in [-3.5, 3.5], y in [-0.5, 6.5], z in [0, 2.7] m)")


def test_room_relations_refused_at_initialisation():
    from components.common.errors import ParameterError

    with pytest.raises(ParameterError, match=r"^localizer: AcousticLocalizer: mic_height = 3\.0 "
                                             r"m puts the microphones outside the room"):
        room_slave(mic_height=3.0)


@pytest.mark.integration
def test_built_fmu_runs_in_fmpy(tmp_path):
    from fmpy import simulate_fmu

    from orchestrator.builder.fmus import build_fmu

    fmu = build_fmu("AcousticLocalizer", tmp_path)
    with zipfile.ZipFile(fmu) as archive:
        root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    assert root.get("modelName") == "AcousticLocalizer"
    signals = np.array([(0.0, -1.0, 2.0, True), (1.0, -1.0, 2.0, True)],
                       dtype=[("time", float), ("source_x", float), ("source_y", float),
                              ("emitting", bool)])
    result = simulate_fmu(str(fmu), stop_time=0.5, output_interval=0.01, step_size=0.01,
                          input=signals, start_values={"snr_db": 30.0, "seed": 2},
                          output=["distance", "bearing", "valid", "measurement_id"])
    assert result["measurement_id"][-1] == 5
    assert bool(result["valid"][-1])
    assert result["distance"][-1] == pytest.approx(math.sqrt(5.0), abs=0.03)
    assert result["bearing"][-1] == pytest.approx(math.atan2(1.0, 2.0), abs=math.radians(0.2))
