"""Every built FMU: both checkers, a run without the repository, state round trip, libcosim."""


import pytest

from orchestrator.builder.fmus import FMU_PACKAGES
from orchestrator.builder.validation import validate_fmu

from tests.support.fmu_checks import DRIVES, run_isolated, run_libcosim, same_bits, state_round_trip, step_and_record

pytestmark = pytest.mark.integration


NAMES = list(FMU_PACKAGES)


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_both_checkers_find_no_problem(fmu_paths, name):
    assert validate_fmu(fmu_paths[name]).problems == []


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_runs_in_a_python_without_the_repository(fmu_paths, name):
    result = run_isolated(fmu_paths[name], 0.5)
    assert result["rows"] > 1
    assert all(isinstance(v, (int, float, bool)) for v in result["last"].values())


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_state_round_trip_is_bit_identical(fmu_paths, name):
    h, drive = DRIVES[name]
    first, second = state_round_trip(fmu_paths[name], drive, h, warmup=100, steps=500)
    assert len(first) == len(second) == 500
    mismatches = [k for k, (a, b) in enumerate(zip(first, second)) if not same_bits(a, b)]
    assert mismatches == []
    # the run after the save point must actually change something, or the test proves nothing
    assert first[0] != first[-1]


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_libcosim_gives_the_same_outputs_as_fmpy(fmu_paths, name):
    from orchestrator.fmu.handle import FmuInstance

    from tests.support.fmu_checks import outputs_of

    h, drive = DRIVES[name]
    steps = 60
    theirs = run_libcosim(fmu_paths[name], drive, h, steps)
    instance = FmuInstance(fmu_paths[name], "fmpy")
    instance.instantiate()
    groups = outputs_of(instance.description)
    ours = step_and_record(instance, groups, drive, 0.0, h, steps)
    instance.terminate()
    assert len(theirs) == len(ours)
    for k, (a, b) in enumerate(zip(ours, theirs)):
        # booleans arrive as bool from libcosim and as 0/1 from fmpy: compare as numbers
        assert [float(x) for x in a] == pytest.approx([float(x) for x in b], rel=0, abs=1e-12), \
            f"step {k}"


WITH_INPUTS = [name for name in NAMES if name != "SoundSource"]


@pytest.mark.parametrize("name", WITH_INPUTS, ids=WITH_INPUTS)
@pytest.mark.parametrize("bad", [float("nan"), float("inf")], ids=["nan", "inf"])
def test_a_non_finite_input_gives_an_error_status_naming_port_and_value(fmu_paths, name, bad):
    from fmpy.fmi1 import FMICallException

    from orchestrator.fmu.handle import FmuInstance

    h, drive = DRIVES[name]
    inputs = drive(0.0)
    port = next(p for p, v in inputs.items() if isinstance(v, float))
    instance = FmuInstance(fmu_paths[name], "bad_input")
    instance.instantiate()
    before = instance.get_state()
    instance.set_values({**inputs, port: bad})
    with pytest.raises(FMICallException) as caught:
        instance.do_step(0.0, h)
    assert caught.value.status in (2, 3)  # fmi2Discard or fmi2Error, never a crash
    assert port in instance.last_error() and repr(bad) in instance.last_error()
    # the host keeps running: as FMI 2.0 asks after a refused step, it restores the state saved
    # before the step (which leaves stepFailed) and the same instance takes good input again
    instance.set_state(before)
    instance.free_state(before)
    instance.set_values(inputs)
    instance.do_step(0.0, h)
    instance.terminate()


def test_plant_clamps_a_voltage_beyond_the_supply_and_logs_it_once(fmu_paths):
    from orchestrator.fmu.handle import FmuInstance

    instance = FmuInstance(fmu_paths["RobotPlant"], "clamp")
    instance.instantiate()
    for k in range(5):
        instance.set_values({"voltage_left": 30.0, "voltage_right": 11.1})
        instance.do_step(k * 0.01, 0.01)
    clamped = instance.get_values(["rim_speed_left", "rim_speed_right"])
    warnings = [text for status, text in instance.messages if "voltage_left" in text]
    instance.terminate()
    assert len(warnings) == 1 and "30" in warnings[0]
    # clamped to the 11.1 V supply: both wheels driven alike
    assert clamped["rim_speed_left"] == pytest.approx(clamped["rim_speed_right"], rel=1e-9)
