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


IMPERFECTIONS = ("mic_left_along", "mic_left_across", "mic_centre_along", "mic_centre_across",
                 "mic_right_along", "mic_right_across", "adc_skew_left", "adc_skew_right")


def test_room_parameters_come_after_every_published_variable():
    # Each group appended after the ones published before it: older value references hold.
    root = AcousticLocalizer(instance_name="x").to_xml()
    references = {v.get("name"): int(v.get("valueReference")) for v in root.find("ModelVariables")}
    imperfections = [references.pop(name) for name in IMPERFECTIONS]
    room = [references.pop(name) for name in ROOM_PARAMETERS]
    assert room == sorted(room) and min(room) > max(references.values())
    assert imperfections == sorted(imperfections) and min(imperfections) > max(room)


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


@pytest.fixture(scope="module")
def built_localizer(tmp_path_factory):
    from orchestrator.builder.fmus import build_fmu

    return build_fmu("AcousticLocalizer", tmp_path_factory.mktemp("localizer"))


@pytest.mark.integration
def test_built_fmu_runs_in_fmpy(built_localizer):
    from fmpy import simulate_fmu

    fmu = built_localizer
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


IMPERFECT = dict(mic_left_along=3e-3, mic_centre_across=1e-3, mic_right_across=-2e-3,
                 adc_skew_left=-3.3e-6, adc_skew_right=5e-6)


def test_imperfections_reach_the_core_and_move_the_fix_as_the_exact_geometry_says():
    from tests.support.array_geometry import nominal_fix, skewed_tdoas, true_microphones

    slave = make_slave(snr_db=120.0, adc_bits=24, **IMPERFECT)
    assert slave.do_step(0.0, 0.01) and slave.valid
    pose = (0.0, 0.0, math.pi / 2)
    delays = skewed_tdoas((-1.0, 2.0), true_microphones(pose, ((3e-3, 0.0), (0.0, 1e-3),
                                                              (0.0, -2e-3))),
                          (-3.3e-6, 0.0, 5e-6))
    # 1e-9 s: tests/unit/components/acoustics/test_imperfections.py says why.
    assert (slave.tdoa_12, slave.tdoa_23) == pytest.approx(delays, abs=1e-9)
    distance, bearing = nominal_fix(*delays, guess=(2.2, 0.46))
    assert slave.distance == pytest.approx(distance, abs=1e-4)
    assert slave.bearing == pytest.approx(bearing, abs=1e-6)
    assert abs(slave.distance - math.sqrt(5.0)) > 0.01


def test_an_imperfection_outside_its_range_is_refused_at_initialisation():
    from components.common.errors import ParameterError

    with pytest.raises(ParameterError) as caught:
        make_slave(mic_right_along=0.02, adc_skew_left=-1e-4)
    assert str(caught.value) == (
        "localizer: parameter mic_right_along = 0.02 is outside its valid range "
        "[-0.01, 0.01] m; parameter adc_skew_left = -0.0001 is outside its valid range "
        "[-2e-05, 2e-05] s")


@pytest.mark.integration
def test_built_fmu_hears_the_imperfect_array(built_localizer):
    from fmpy.fmi1 import FMICallException

    from orchestrator.fmu.handle import FmuInstance

    names = ["tdoa_12", "tdoa_23", "distance", "bearing"]

    def fix(parameters):
        instance = FmuInstance(built_localizer, "localizer")
        instance.instantiate(parameters={"snr_db": 120.0, "adc_bits": 24, **parameters})
        instance.set_values({"source_x": -1.0, "source_y": 2.0, "emitting": True})
        instance.do_step(0.0, 0.01)
        values = instance.get_values(names + ["valid"])
        instance.terminate()
        return values

    imperfect, perfect = fix(IMPERFECT), fix({})
    assert imperfect["valid"] and perfect["valid"]
    # The FMU's copy of the core gives the in-process slave's numbers, bit for bit.
    in_process = make_slave(snr_db=120.0, adc_bits=24, **IMPERFECT)
    in_process.do_step(0.0, 0.01)
    assert [imperfect[name] for name in names] == [getattr(in_process, name) for name in names]
    assert perfect["distance"] == pytest.approx(math.sqrt(5.0), abs=1e-4)
    assert abs(imperfect["distance"] - perfect["distance"]) > 0.01
    bad = FmuInstance(built_localizer, "bad")
    with pytest.raises(FMICallException):
        bad.instantiate(parameters={"mic_centre_across": 0.5})
    assert bad.last_error() == ("bad: parameter mic_centre_across = 0.5 is outside its valid "
                                "range [-0.01, 0.01] m")
    bad.terminate()
