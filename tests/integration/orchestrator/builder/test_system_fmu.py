"""The whole-system FMU (``sonotrack build --system``) against ``sonotrack run`` of the same
settings, in fmpy, libcosim, ecos and a C host; its parameters, state, refusals and checks.

The reference of every trajectory is ``sonotrack run`` (our master stepping the five FMUs
through fmpy, :func:`tests.support.system_fmu.reference`); the system FMU must equal it to
1e-9 on every output both record (it runs the same slave code under the same master, so it
is expected to be equal bit for bit).
"""

import json

import fmpy
import numpy as np
import pytest

from orchestrator.builder.fmus import REPO_ROOT
from orchestrator.scenario import load_scenario

from tests.support.fmi_binary import Host, run_host
from tests.support.system_fmu import (STEP, c_host_plan, c_host_rows, ecos_run, fmpy_run,
                                      fmu_name, largest_difference, libcosim_run, reference)

pytestmark = pytest.mark.integration

STOP = 6.0          # s: the first arcs, fixes and turns of the default S-curve
TOLERANCE = 1e-9


@pytest.fixture(scope="module")
def scenario():
    return load_scenario(REPO_ROOT / "scenarios" / "s_curve.toml").with_overrides(stop_time=STOP)


@pytest.fixture(scope="module")
def system_fmu(fmu_dir, scenario, tmp_path_factory):
    """TrackingSystem.fmu of the default scenario, built from this checkout's components."""
    from orchestrator.run.as_fmu import build_scenario_fmu

    return build_scenario_fmu(scenario, tmp_path_factory.mktemp("system_fmu"), fmu_dir=fmu_dir)


@pytest.fixture(scope="module")
def default_run(fmu_dir, scenario, tmp_path_factory):
    return reference(scenario, fmu_dir, tmp_path_factory.mktemp("reference"))


@pytest.fixture(scope="module")
def real_outputs(system_fmu):
    """Every Real output of the system FMU (what the non-Python hosts read here)."""
    return [v.name for v in fmpy.read_model_description(str(system_fmu)).modelVariables
            if v.causality == "output" and v.type == "Real"]


def _recorded(run):
    return [name for name in run if name != "time"]


# ----- the same trajectory in every host --------------------------------------------------

def test_fmpy_runs_it_like_sonotrack_run(system_fmu, default_run):
    ours = fmpy_run(system_fmu, STOP)
    names = _recorded(default_run)
    assert len(names) > 70 and set(names) <= set(ours), sorted(set(names) - set(ours))
    np.testing.assert_allclose(ours["time"], default_run["time"], rtol=0, atol=1e-12)
    worst, where = largest_difference(ours, default_run, names)
    assert worst <= TOLERANCE, f"{where}: {worst}"
    assert np.ptp(ours["plant_y"]) > 0.5 and ours["localizer_measurement_id"][-1] > 30


def test_libcosim_runs_it_like_sonotrack_run(system_fmu, default_run, real_outputs, tmp_path):
    ours = libcosim_run(system_fmu, STOP, real_outputs, tmp_path)
    worst, where = largest_difference(ours, default_run, real_outputs, first_row=1)
    assert worst <= TOLERANCE, f"{where}: {worst}"


@pytest.fixture(scope="module")
def ecos_ready(tmp_path_factory):
    from orchestrator.hosts.ecos import ecos_binary

    binary, reason = ecos_binary(tmp_path_factory.mktemp("ecos"))
    if binary is None:
        print(f"ecos skipped: {reason}")
        pytest.skip(f"ecos cannot run here: {reason}")
    return binary


def test_ecos_runs_it_like_sonotrack_run(ecos_ready, system_fmu, default_run, real_outputs):
    ours = ecos_run(system_fmu, STOP, real_outputs)
    worst, where = largest_difference(ours, default_run, real_outputs, first_row=1)
    assert worst <= TOLERANCE, f"{where}: {worst}"


def test_ecos_command_line_runs_it_to_its_csv_resolution(ecos_ready, system_fmu, default_run,
                                                         tmp_path):
    """``ecos simulate`` (no Python in the host) prints six decimals: equal to that."""
    from orchestrator.hosts.ecos import read_ecos_csv, run_ecos

    completed, csv_path = run_ecos(ecos_ready, system_fmu, STOP, STEP, tmp_path)
    assert completed.returncode == 0, completed.stderr[-2000:] + completed.stdout[-2000:]
    theirs = read_ecos_csv(csv_path)
    rows = len(theirs["time"])
    assert rows >= int(STOP / STEP) - 1
    for name in ("plant_x", "plant_y", "source_x", "localizer_bearing", "distance_to_source"):
        other = np.asarray(theirs[f"instance.{name}"], dtype=float)
        assert np.max(np.abs(other - default_run[name][:rows])) <= 1e-6, name


def test_c_host_runs_it_like_sonotrack_run(c_host, system_fmu, default_run, real_outputs,
                                           tmp_path):
    folder = tmp_path / "unzipped"
    fmpy.extract(str(system_fmu), str(folder))
    description = fmpy.read_model_description(str(folder))
    ports = real_outputs[:64]   # the host reads at most 64 ports of a type
    completed = run_host(c_host, c_host_plan(folder, description, STOP, ports))
    assert completed.returncode == 0, completed.stderr[-3000:]
    ours = c_host_rows(completed.stdout, ports)
    worst, where = largest_difference(ours, default_run, ports, first_row=1)
    assert worst <= TOLERANCE, f"{where}: {worst}"


# ----- parameters act as the run's overrides ------------------------------------------------

# Each case: the scenario's overrides (its `parameters`, `seed`, `[[faults]]`) and the system
# FMU's parameters a user sets for the same thing, written independently.
CASES = {
    "source_path": ({"parameters": {"source.path": "straight"}}, {"source_path": "straight"}),
    "v_cruise": ({"parameters": {"planner.v_cruise": 0.22}}, {"planner_v_cruise": 0.22}),
    "friction": ({"parameters": {"plant.mu": 0.05}}, {"plant_mu": 0.05}),
    "controller_mode": ({"parameters": {"controller_left.mode": "pid",
                                        "controller_right.mode": "pid"}},
                        {"controller_left_mode": "pid", "controller_right_mode": "pid"}),
    "planner_mode": ({"parameters": {"planner.mode": "pure_pursuit"}},
                     {"planner_mode": "pure_pursuit"}),
    "seed": ({"seed": 7}, {"seed": 7}),
    "fault_schedule": ({"faults": [{"kind": "mic_dead", "target": "localizer", "channel": "M2",
                                    "start": 1.0, "end": 4.0}]},
                       {"localizer_fault_schedule": json.dumps(
                           [{"kind": "mic_dead", "channel": "M2", "start": 1.0, "end": 4.0}])}),
}


@pytest.mark.parametrize("case", list(CASES), ids=list(CASES))
def test_parameters_change_it_as_run_overrides_do(case, system_fmu, scenario, default_run,
                                                  fmu_dir, tmp_path):
    overrides, parameters = CASES[case]
    changed = reference(scenario.with_overrides(**overrides), fmu_dir, tmp_path / "run")
    moved = max(float(np.max(np.abs(changed[n] - default_run[n])))
                for n in ("plant_x", "plant_y", "source_x", "localizer_bearing",
                          "planner_v_ref_left", "controller_left_voltage"))
    assert moved > 1e-3, "the override must change the run"
    ours = fmpy_run(system_fmu, STOP, parameters)
    worst, where = largest_difference(ours, changed, _recorded(changed))
    assert worst <= TOLERANCE, f"{where}: {worst}"


# ----- state, refusals, checks ---------------------------------------------------------------

def _outputs(slave, description):
    groups = {}
    for v in description.modelVariables:
        if v.causality == "output":
            groups.setdefault(v.type, []).append(v.valueReference)
    return (list(slave.getReal(groups["Real"])) + list(slave.getInteger(groups["Integer"]))
            + list(slave.getBoolean(groups["Boolean"])))


def _steps(slave, first, last):
    for k in range(first, last):
        slave.doStep(currentCommunicationPoint=k * STEP, communicationStepSize=STEP)


def test_state_is_saved_restored_and_serialized_bit_for_bit(system_fmu, tmp_path):
    folder = tmp_path / "unzipped"
    fmpy.extract(str(system_fmu), str(folder))
    description = fmpy.read_model_description(str(folder))
    first, second = (Host(folder, description, name=name) for name in ("first", "second"))
    for host in (first, second):
        host.initialize()
    slave = first.slave
    _steps(slave, 0, 100)
    state = slave.getFMUstate()
    serialized = slave.serializeFMUstate(state)
    _steps(slave, 100, 200)
    straight_on = _outputs(slave, description)
    slave.setFMUstate(state)
    _steps(slave, 100, 200)
    assert _outputs(slave, description) == straight_on
    # another instance, at t = 0, takes the serialized state and goes on identically
    other = second.slave
    other.setFMUstate(other.deSerializeFMUstate(serialized))
    _steps(other, 100, 200)
    assert _outputs(other, description) == straight_on
    slave.freeFMUstate(state)
    for host in (first, second):
        host.free()


@pytest.mark.parametrize("port, value, words", [
    ("planner_v_cruise", -1.0, ("inner component planner", "v_cruise = -1.0", "planner_v_cruise")),
    ("source_path", "zigzag", ("inner component source", "path = 'zigzag'", "source_path")),
    ("seed", -5, ("inner component localizer", "seed = -5", "FMU parameter seed")),
], ids=["real", "string", "seed"])
def test_bad_parameter_is_error_naming_inner_component_port_and_value(system_fmu, tmp_path,
                                                                     port, value, words):
    from fmpy.fmi1 import FMICallException

    folder = tmp_path / "unzipped"
    fmpy.extract(str(system_fmu), str(folder))
    description = fmpy.read_model_description(str(folder))
    host = Host(folder, description, name="bad")
    slave = host.slave
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    setter = {str: slave.setString, int: slave.setInteger, float: slave.setReal}[type(value)]
    setter([host.refs[port]], [value])
    with pytest.raises(FMICallException) as caught:
        slave.exitInitializationMode()
    assert caught.value.status == 3  # fmi2Error, never fmi2Fatal
    errors = [text for status, text in host.messages if status == 3]
    assert errors and all(word in errors[-1] for word in words), host.messages
    host.free()


def test_a_step_that_is_not_whole_base_steps_is_discarded_and_logged(system_fmu, tmp_path):
    from fmpy.fmi1 import FMICallException

    folder = tmp_path / "unzipped"
    fmpy.extract(str(system_fmu), str(folder))
    host = Host(folder, fmpy.read_model_description(str(folder)), name="odd")
    host.initialize()
    with pytest.raises(FMICallException) as caught:
        host.slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.015)
    assert caught.value.status == 2  # fmi2Discard
    assert any("step_size = 0.015" in text for _, text in host.messages), host.messages
    host.free()


def test_validators_and_documentation_report_no_problem(system_fmu):
    from orchestrator.builder.documentation import documentation_problems
    from orchestrator.builder.validation import validate_fmu

    report = validate_fmu(system_fmu)
    assert report.problems == []
    assert documentation_problems(system_fmu) == []
