"""The TrackingSystem slave without building it: ports routed to the inner slaves, whole base
steps, parameter problems named per inner component, complete state.

A small system (a static source heard by the localizer) keeps these fast; the whole sonotrack
loop against ``sonotrack run`` is tests/integration/orchestrator/builder/test_system_fmu.py.
"""

import json

import pytest

from components.common.errors import InputError, ParameterError
from components.system import DESCRIPTION_FILE, InstancePlan, SystemDescription
from components.system.fmu import TrackingSystem

H = 0.01


@pytest.fixture
def resources(tmp_path):
    description = SystemDescription(
        name="heard", base_step=H, algorithm="gauss-seidel", stop_time=1.0, seed=5,
        instances=(InstancePlan("source", "SoundSource", "source", 1,
                                {"path": "static", "x0": 2.0, "y0": 0.3}),
                   InstancePlan("localizer", "AcousticLocalizer", "acoustics", 2, {}, True)),
        links=(("source.x", "localizer.source_x"), ("source.y", "localizer.source_y"),
               ("source.emitting", "localizer.emitting")))
    (tmp_path / DESCRIPTION_FILE).write_text(description.to_json())
    return str(tmp_path)


def _initialized(resources, **parameters):
    system = TrackingSystem(instance_name="sys", resources=resources)
    system.setup_experiment(0.0, 1.0, None)
    system.enter_initialization_mode()
    for name, value in parameters.items():
        setattr(system, name, value)
    system.exit_initialization_mode()
    return system


def _outputs(system):
    return {v.name: getattr(system, v.name) for v in system.vars.values()
            if v.causality.name == "output"}


def test_ports_are_the_inner_ports_and_reach_the_inner_slaves(resources):
    system = TrackingSystem(instance_name="sys", resources=resources)
    source = system._handles["source"].slave
    # the description's values are the parameters' start values
    assert (system.source_path, system.source_x0, system.seed) == ("static", 2.0, 5)
    system.source_y0 = -0.4
    assert source.y0 == -0.4
    assert system._handles["localizer"].slave.seed == 5   # the seed reaches the seeded one
    names = [v.name for v in system.vars.values()]
    assert "localizer_seed" not in names and "seed" in names and "source_fault_schedule" in names
    nodes = {node.get("name"): node for node in system.to_xml().find("ModelVariables")}
    assert nodes["source_v_max"].find("Real").get("min") == "0.001"
    assert nodes["localizer_bearing"].find("Real").get("unit") == "rad"
    assert nodes["seed"].get("causality") == "parameter"


def test_a_step_of_n_base_steps_is_n_master_steps_at_the_system_time(resources):
    one = _initialized(resources)
    five = _initialized(resources)
    for k in range(10):
        assert one.do_step(k * H, H)
    assert five.do_step(0.0, 5 * H) and five.do_step(5 * H, 5 * H)
    assert _outputs(five) == _outputs(one)
    assert one.localizer_fix_attempts >= 1   # the localizer stepped and tried a fix
    # not a whole number of base steps, or not the system's time: refused and logged
    assert not one.do_step(10 * H, 0.015)
    assert not one.do_step(0.5, H)
    lines = [m.msg for m in one.log_queue]
    assert any("step_size = 0.015" in line for line in lines)
    assert any("current_time = 0.5" in line and "t = 0.1 s" in line for line in lines)


def test_every_bad_parameter_is_named_with_its_inner_component(resources):
    with pytest.raises(ParameterError) as caught:
        _initialized(resources, source_v_max=-1.0, localizer_mic_spacing=100.0, seed=-3)
    message = str(caught.value)
    assert message.startswith("sys: ")
    for words in ("inner component source: parameter v_max = -1.0", "source_v_max",
                  "inner component localizer: parameter mic_spacing = 100.0",
                  "localizer_mic_spacing", "parameter seed = -3", "FMU parameter seed"):
        assert words in message, words


def test_state_restores_and_serializes_every_inner_slave_bit_for_bit(resources):
    system = _initialized(resources)
    for k in range(30):
        system.do_step(k * H, H)
    state = system._fmu_state_from_bytes(system._fmu_state_to_bytes(system._get_fmu_state()))
    for k in range(30, 60):
        system.do_step(k * H, H)
    later = _outputs(system)
    system._set_fmu_state(state)
    assert system.localizer_fix_attempts < later["localizer_fix_attempts"]
    for k in range(30, 60):
        assert system.do_step(k * H, H)
    assert _outputs(system) == later
    # a fresh instance, never stepped, takes the state and goes on identically
    fresh = _initialized(resources)
    fresh._set_fmu_state(json.loads(json.dumps(state)))
    for k in range(30, 60):
        assert fresh.do_step(k * H, H)
    assert _outputs(fresh) == later


def test_a_state_of_something_else_is_refused_naming_what_is_wrong(resources):
    system = _initialized(resources)
    with pytest.raises(InputError, match="sys: FMU state refused: not a state of"):
        system._set_fmu_state({"x": 1.0})
    state = system._get_fmu_state()
    del state["__instances__"]["localizer"]
    with pytest.raises(InputError, match="instances source, localizer"):
        system._set_fmu_state(state)
