"""The WheelController slave: model description, a manual loop, refusals, state round trip."""

import json
import math

import pytest

pytest.importorskip("pythonfmu")

from components.control import WheelSpeedController  # noqa: E402
from components.control.fmu import WheelController  # noqa: E402


def _slave(**parameters):
    slave = WheelController(instance_name="t")
    for name, value in parameters.items():
        setattr(slave, name, value)
    slave.enter_initialization_mode()
    slave.exit_initialization_mode()
    return slave


def test_model_description_ports_units_and_no_feedthrough():
    root = WheelController(instance_name="t").to_xml()
    variables = {v.get("name"): v for v in root.find("ModelVariables")}
    units = {name: v.find("Real").get("unit") for name, v in variables.items()
             if v.find("Real") is not None}
    assert units["v_ref"] == units["v_meas"] == "m/s"
    assert units["voltage"] == "V" and units["kp"] == units["kd"] == "1"
    assert units["error"] == "m/s" and units["error_rate"] == "m/s2"
    assert units["e_range"] == "m/s" and units["de_range"] == "m/s2" and units["kp_min"] == "1"
    assert variables["mode"].get("causality") == "parameter"
    index = {v.get("name"): str(i + 1) for i, v in enumerate(root.find("ModelVariables"))}
    outputs = {u.get("index"): u.get("dependencies").split()
               for u in root.find("ModelStructure").find("Outputs")}
    # outputs change only in do_step: no direct feedthrough from v_ref or v_meas
    assert all(outputs[index[name]] == [] for name in ("voltage", "kp", "kd", "error",
                                                         "error_rate"))
    assert root.find("UnitDefinitions") is not None


@pytest.mark.parametrize("mode", ["fgs_pd", "pid", "pd"], ids=["fgs_pd", "pid", "pd"])
def test_manual_loop_matches_core(mode):
    slave = _slave(mode=mode)
    core = WheelSpeedController(mode=mode)
    for k in range(50):
        slave.v_ref, slave.v_meas = 0.3, 0.3 * (1 - math.exp(-0.1 * k))
        assert slave.do_step(k * 0.02, 0.02) is True
        assert slave.voltage == core.step(slave.v_ref, slave.v_meas, 0.02)
        assert (slave.kp, slave.kd, slave.error) == (core.kp, core.kd, core.error)


@pytest.mark.parametrize("port", ["v_ref", "v_meas"], ids=["v_ref", "v_meas"])
def test_nan_input_refused_naming_port(port):
    slave = _slave()
    logged = []
    slave.log = lambda message, status=None, *a, **k: logged.append((message, status))
    setattr(slave, "v_ref", 0.2)
    setattr(slave, "v_meas", 0.1)
    setattr(slave, port, float("nan"))
    assert slave.do_step(0.0, 0.02) is False
    assert any(port in message and "nan" in message for message, _ in logged)


def test_bad_mode_refused_at_initialisation():
    slave = WheelController(instance_name="t")
    slave.log = lambda *a, **k: None
    slave.mode = "fuzzy"
    with pytest.raises(ValueError, match="mode = 'fuzzy' .* one of 'fgs_pd', 'pid', 'pd'"):
        slave.exit_initialization_mode()


@pytest.mark.parametrize("mode", ["fgs_pd", "pid"], ids=["fgs_pd", "pid"])
def test_state_round_trip_includes_filter_and_integrator(mode):
    slave = _slave(mode=mode)
    for k in range(30):
        slave.v_ref, slave.v_meas = 0.342, 0.01 * k
        slave.do_step(k * 0.02, 0.02)
    saved = json.loads(json.dumps(slave._get_fmu_state()))

    def continue_run():
        out = []
        for k in range(30, 60):
            slave.v_ref, slave.v_meas = 0.342, 0.3 + 0.001 * k
            slave.do_step(k * 0.02, 0.02)
            out.append((slave.voltage, slave.kp, slave.kd, slave.error, slave.error_rate,
                        slave.core.pid.integral, slave.core.derivative.value))
        return out

    first = continue_run()
    slave._set_fmu_state(saved)
    second = continue_run()
    assert first == second
    if mode == "pid":
        assert first[-1][5] != 0.0  # the integrator was part of what was restored
