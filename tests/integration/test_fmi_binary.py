"""sonotrack's own FMI binary in real hosts: a C host, fmpy, refusals, isolation of builds.

The C host (fmi_host.c, compiled here with gcc) runs with no LD_PRELOAD and no PYTHONPATH and
must give fmpy's outputs; two builds of one model run their own code in one process; every
refusal is an fmi2Error with a message naming the call and the variable, after which the
instance is freed and a new one runs; 500 instantiate/free cycles leave sys.path and
sys.modules alone. docs/fmi_binary.md states the contract these tests check.
"""

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from orchestrator.build import FMU_PACKAGES, REPO_ROOT, build_fmu

from .fmu_checks import instantiate_free_cycles
from .test_fmus import DRIVES

pytestmark = pytest.mark.integration

NAMES = list(FMU_PACKAGES)
STEPS = 200
ABORT_SIGNS = ("abort", "corrupted", "Fatal Python error", "Segmentation", "double free")


def _host_env():
    """The caller's environment minus anything that would help the FMU find Python."""
    return {k: v for k, v in os.environ.items()
            if k not in ("LD_PRELOAD", "PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}


@pytest.fixture(scope="module")
def c_host(tmp_path_factory):
    import fmpy

    compiler = shutil.which("gcc")
    if compiler is None:
        pytest.skip("gcc is not installed: the C host cannot be compiled")
    headers = Path(fmpy.__file__).parent / "c-code"
    binary = tmp_path_factory.mktemp("c_host") / "fmi_host"
    subprocess.run([compiler, "-std=c11", "-O1", "-Wall", "-Werror", f"-I{headers}", "-o",
                    str(binary), str(Path(__file__).with_name("fmi_host.c")), "-ldl"],
                   check=True)
    return binary


@pytest.fixture(scope="module")
def extracted(fmu_paths, tmp_path_factory):
    """Model name -> (unzip folder, model description), each FMU extracted once."""
    import fmpy

    out = {}
    for name in NAMES:
        folder = tmp_path_factory.mktemp(f"x_{name}")
        fmpy.extract(str(fmu_paths[name]), str(folder))
        out[name] = (folder, fmpy.read_model_description(str(fmu_paths[name])))
    return out


def _ports(description, inputs):
    """Value references of the driven inputs and of every output, grouped by type."""
    variables = {v.name: v for v in description.modelVariables}
    groups = []
    for type_name in ("Real", "Integer", "Boolean"):
        groups.append([n for n in inputs if variables[n].type == type_name])
    for type_name in ("Real", "Integer", "Boolean"):
        groups.append([v.name for v in description.modelVariables
                       if v.causality == "output" and v.type == type_name])
    return variables, groups


def _plan(extracted, names):
    """The C host's plan text and, per FMU, (step, typed input names, output names)."""
    header = [f"{len(names)} {STEPS}"]
    layouts = []
    for name in names:
        folder, description = extracted[name]
        h, drive = DRIVES[name]
        variables, groups = _ports(description, drive(0.0))
        binary = folder / "binaries" / "linux64" / f"{description.coSimulation.modelIdentifier}.so"
        fields = [str(binary), description.guid, (folder / "resources").as_uri(), f"c_{name}",
                  repr(h)]
        for group in groups:
            fields += [str(len(group))] + [str(variables[n].valueReference) for n in group]
        header.append(" ".join(fields))
        layouts.append((h, drive, groups))
    rows = []
    for k in range(STEPS):
        for h, drive, groups in layouts:
            values = drive(k * h)
            rows.append(" ".join([repr(float(values[n])) for n in groups[0]] +
                                 [str(int(values[n])) for n in groups[1]] +
                                 [str(int(bool(values[n]))) for n in groups[2]]))
    return "\n".join(header + rows) + "\n", layouts


def _fmpy_reference(extracted, name):
    """The same inputs and steps through fmpy (in this process): outputs after every step."""
    from fmpy.fmi2 import FMU2Slave

    folder, description = extracted[name]
    h, drive = DRIVES[name]
    variables, groups = _ports(description, drive(0.0))
    slave = FMU2Slave(guid=description.guid, unzipDirectory=str(folder),
                      modelIdentifier=description.coSimulation.modelIdentifier,
                      instanceName=f"py_{name}")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    vr = [[variables[n].valueReference for n in group] for group in groups]
    rows = []
    for k in range(STEPS):
        values = drive(k * h)
        if vr[0]:
            slave.setReal(vr[0], [float(values[n]) for n in groups[0]])
        if vr[1]:
            slave.setInteger(vr[1], [int(values[n]) for n in groups[1]])
        if vr[2]:
            slave.setBoolean(vr[2], [bool(values[n]) for n in groups[2]])
        slave.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
        row = list(slave.getReal(vr[3])) if vr[3] else []
        row += list(slave.getInteger(vr[4])) if vr[4] else []
        row += [int(b) for b in slave.getBoolean(vr[5])] if vr[5] else []
        rows.append([float(x) for x in row])
    slave.terminate()
    slave.fmi2FreeInstance(slave.component)
    return rows


def _run_host(c_host, plan, *flags):
    return subprocess.run([str(c_host), *flags], input=plan, capture_output=True, text=True,
                          env=_host_env(), cwd="/", timeout=600)


def _check_host_run(completed, names, extracted):
    assert completed.returncode == 0, completed.stderr[-3000:]
    assert not any(sign in completed.stderr for sign in ABORT_SIGNS), completed.stderr[-3000:]
    ours = {name: [] for name in names}
    for line in completed.stdout.splitlines():
        k, f, *values = line.split()
        ours[names[int(f)]].append([float(v) for v in values])
    for name in names:
        reference = _fmpy_reference(extracted, name)
        assert len(ours[name]) == len(reference) == STEPS
        for k, (a, b) in enumerate(zip(ours[name], reference)):
            assert a == pytest.approx(b, rel=0, abs=1e-12), f"{name} step {k}"
        assert ours[name][0] != ours[name][-1] or name == "SoundSource", "nothing moved"


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_c_host_without_preload_gives_fmpys_outputs_and_exits_cleanly(c_host, extracted, name):
    plan, _ = _plan(extracted, [name])
    _check_host_run(_run_host(c_host, plan), [name], extracted)


@pytest.mark.parametrize("flags", [(), ("--keep-loaded",)], ids=["dlclose", "no_dlclose"])
def test_c_host_runs_all_five_fmus_in_one_process(c_host, extracted, flags):
    plan, _ = _plan(extracted, NAMES)
    _check_host_run(_run_host(c_host, plan, *flags), NAMES, extracted)


# ----- two builds of one model in one process --------------------------------------------------

_TWO_BUILDS = textwrap.dedent('''
    import json, sys
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    instances = []
    for index, path in enumerate(sys.argv[1:]):
        description = fmpy.read_model_description(path)
        slave = FMU2Slave(guid=description.guid, unzipDirectory=fmpy.extract(path),
                          modelIdentifier="WheelController", instanceName=f"build{index}")
        refs = {v.name: v.valueReference for v in description.modelVariables}
        start = next(v.start for v in description.modelVariables if v.name == "v_supply")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        instances.append((path, slave, refs, float(start)))
    result = {}
    for path, slave, refs, start in instances:  # step both only after both are loaded
        slave.setReal([refs["v_ref"], refs["v_meas"]], [1.0, 0.0])
        slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.005)
        voltage, v_supply = slave.getReal([refs["voltage"], refs["v_supply"]])
        result[path] = {"voltage": voltage, "v_supply": v_supply, "declared": start}
    print(json.dumps(result))
''')


def test_two_builds_of_one_model_each_run_their_own_code(fmu_paths, tmp_path):
    components = tmp_path / "components"
    shutil.copytree(REPO_ROOT / "components", components,
                    ignore=shutil.ignore_patterns("__pycache__"))
    controller = components / "control" / "controller.py"
    source = controller.read_text()
    assert '"v_supply": 11.1,' in source
    controller.write_text(source.replace('"v_supply": 11.1,', '"v_supply": 7.5,'))
    changed = build_fmu("WheelController", tmp_path / "b", components_dir=components)
    original = fmu_paths["WheelController"]
    for order in ([original, changed], [changed, original]):
        completed = subprocess.run([sys.executable, "-c", _TWO_BUILDS, *map(str, order)],
                                   capture_output=True, text=True, cwd="/", timeout=300)
        assert completed.returncode == 0, completed.stderr[-2000:]
        result = json.loads(completed.stdout.splitlines()[-1])
        # v_ref = 1 m/s from standstill saturates the output at +v_supply of each build's code
        assert result[str(original)] == {"voltage": 11.1, "v_supply": 11.1, "declared": 11.1}
        assert result[str(changed)] == {"voltage": 7.5, "v_supply": 7.5, "declared": 7.5}


# ----- refusals ------------------------------------------------------------------------------

class Host:
    """One fmpy FMU2Slave of an extracted FMU with a logger that keeps every message."""

    def __init__(self, folder, description, name="probe", guid=None):
        from fmpy import calloc, free
        from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE,
                               fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                               fmi2CallbackLoggerTYPE)

        self.description = description
        self.refs = {v.name: v.valueReference for v in description.modelVariables}
        self.messages = []
        self.slave = FMU2Slave(guid=guid or description.guid, unzipDirectory=str(folder),
                               modelIdentifier=description.coSimulation.modelIdentifier,
                               instanceName=name)
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.slave.instantiate(callbacks=self._callbacks, loggingOn=True)

    def _log(self, environment, instance, status, category, message):
        self.messages.append((status, message.decode()))

    def initialize(self, **parameters):
        self.slave.setupExperiment(startTime=0.0)
        self.slave.enterInitializationMode()
        for name, value in parameters.items():
            setter = self.slave.setString if isinstance(value, str) else self.slave.setReal
            setter([self.refs[name]], [value])
        self.slave.exitInitializationMode()

    def step(self, k=0, h=0.005):
        self.slave.setReal([self.refs["v_ref"], self.refs["v_meas"]], [0.3, 0.1])
        self.slave.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
        return self.slave.getReal([self.refs["voltage"]])[0]

    def free(self):
        self.slave.fmi2FreeInstance(self.slave.component)


def _expect_error(host, call, *words):
    from fmpy.fmi1 import FMICallException

    with pytest.raises(FMICallException) as caught:
        call()
    assert caught.value.status == 3  # fmi2Error, never fmi2Fatal
    errors = [text for status, text in host.messages if status == 3]
    assert errors and all(word in errors[-1] for word in words), host.messages


REFUSALS = {
    "doStep_before_initialization": (
        lambda h: None, lambda h: h.slave.doStep(0.0, 0.005),
        ("fmi2DoStep", "instantiated")),
    "getReal_before_initialization": (
        lambda h: None, lambda h: h.slave.getReal([h.refs["voltage"]]),
        ("fmi2GetReal", "instantiated")),
    "doStep_after_terminate": (
        lambda h: (h.initialize(), h.slave.terminate()), lambda h: h.slave.doStep(0.0, 0.005),
        ("fmi2DoStep", "terminated")),
    "setReal_of_an_output": (
        lambda h: h.initialize(), lambda h: h.slave.setReal([h.refs["voltage"]], [1.0]),
        ("fmi2SetReal", "voltage", "output")),
    "setReal_of_a_fixed_parameter_after_initialization": (
        lambda h: h.initialize(), lambda h: h.slave.setReal([h.refs["kp_min"]], [0.5]),
        ("fmi2SetReal", "kp_min", "fixed parameter")),
    "unknown_value_reference": (
        lambda h: h.initialize(), lambda h: h.slave.getReal([9999]),
        ("fmi2GetReal", "unknown value reference 9999")),
    "value_reference_of_another_type": (
        lambda h: h.initialize(), lambda h: h.slave.getReal([h.refs["mode"]]),
        ("fmi2GetReal", "mode", "String")),
    "bad_parameter_at_initialization": (
        lambda h: None, lambda h: h.initialize(mode="spiral"),
        ("fmi2ExitInitializationMode", "spiral")),
    "corrupted_serialized_state": (
        lambda h: h.initialize(),
        lambda h: h.slave.deSerializeFMUstate(_corrupt(h.slave)),
        ("fmi2DeSerializeFMUstate", "corrupted state")),
    "unsupported_directional_derivative": (
        lambda h: h.initialize(),
        lambda h: h.slave.getDirectionalDerivative([h.refs["voltage"]], [h.refs["v_ref"]], [1.0]),
        ("fmi2GetDirectionalDerivative", "not supported")),
}


def _corrupt(slave):
    state = slave.getFMUstate()
    data = bytearray(slave.serializeFMUstate(state))
    slave.freeFMUstate(state)
    data[40:48] = b"\xff" * 8  # inside the JSON payload, after the 32-byte header
    return bytes(data)


@pytest.mark.parametrize("refusal", list(REFUSALS), ids=list(REFUSALS))
def test_refusal_is_an_error_with_a_message_then_free_and_a_new_instance_runs(extracted,
                                                                             refusal):
    folder, description = extracted["WheelController"]
    prepare, call, words = REFUSALS[refusal]
    host = Host(folder, description, name=refusal)
    prepare(host)
    _expect_error(host, lambda: call(host), *words)
    host.free()
    fresh = Host(folder, description, name="fresh")
    fresh.initialize()
    assert fresh.step() == pytest.approx(_wheel_reference_voltage(), abs=1e-12)
    fresh.slave.terminate()
    fresh.free()


def _wheel_reference_voltage():
    """Voltage after one step from rest at v_ref 0.3, v_meas 0.1, from the core itself."""
    from components.control.controller import WheelSpeedController

    return WheelSpeedController().step(0.3, 0.1, 0.005)


def test_after_an_error_reset_gives_a_working_instance(extracted):
    folder, description = extracted["WheelController"]
    host = Host(folder, description)
    _expect_error(host, lambda: host.initialize(mode="spiral"), "spiral")
    host.slave.reset()
    host.initialize()
    assert host.step() == pytest.approx(_wheel_reference_voltage(), abs=1e-12)
    host.free()


def test_guid_refusal_message_names_both_guids(extracted):
    folder, description = extracted["WheelController"]
    messages = []

    class Recording(Host):
        def _log(self, environment, instance, status, category, message):
            messages.append((status, message.decode()))

    with pytest.raises(Exception):
        Recording(folder, description, guid="{00000000-0000-0000-0000-000000000000}")
    assert any(status == 3 and "00000000-0000" in text and description.guid in text
               for status, text in messages), messages


# ----- status mapping of model exceptions ------------------------------------------------------

_PROBE = textwrap.dedent('''
    """A probe slave: do_step does what the ``action`` input says."""

    from ..common.errors import InputError, StepRejectedError
    from ..common.slave import Fmi2Status, SonotrackSlave, load_ranges


    class Probe(SonotrackSlave):
        description = "status-mapping probe"
        valid_ranges = load_ranges("probe")

        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.action = 0
            self.refuse_init = False
            self.count = 0
            self.elapsed = 0.0
            self.input_integer("action", "0 ok, 1 InputError, 2 StepRejectedError, "
                               "3 ZeroDivisionError, 4 return None, 5 return False, "
                               "6 log sys.prefix")
            self.parameter_boolean("refuse_init", "exit_initialization_mode returns False")
            self.output_integer("count", "steps taken")
            self.output_real("elapsed", "s", "time stepped")

        def exit_initialization_mode(self):
            return not self.refuse_init

        def do_step(self, current_time, step_size):
            if self.action == 1:
                raise InputError(f"{self.instance_name}: input action = 1 refused: probe")
            if self.action == 2:
                raise StepRejectedError(f"{self.instance_name}: step {step_size} too long")
            if self.action == 3:
                return 1 / 0
            if self.action == 4:
                return None
            if self.action == 6:
                import sys
                self.log(f"sys.prefix={sys.prefix}", Fmi2Status.warning)
                self.count += 1
                return True
            if self.action == 5:
                self.log("refused by returning False", Fmi2Status.discard)
                return False
            self.count += 1
            self.elapsed += step_size
            return True
''')


# Every SonotrackSlave declares the valid range of each parameter and input.
_PROBE_RANGES = textwrap.dedent('''
    [step]
    step_size = { type = "Real", unit = "s", min = 1e-6, max = 1.0 }
    [inputs]
    action = { type = "Integer", min = 0, max = 6 }
    [parameters]
    refuse_init = { type = "Boolean" }
''')


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    import fmpy

    root = tmp_path_factory.mktemp("probe")
    components = root / "components"
    shutil.copytree(REPO_ROOT / "components" / "common", components / "common",
                    ignore=shutil.ignore_patterns("__pycache__"))
    (components / "probe").mkdir()
    (components / "probe" / "__init__.py").write_text("")
    (components / "probe" / "fmu.py").write_text(_PROBE)
    (components / "probe" / "ranges.toml").write_text(_PROBE_RANGES)
    path = build_fmu("Probe", root / "out", components_dir=components, packages={"Probe": "probe"})
    folder = root / "unzipped"
    fmpy.extract(str(path), str(folder))
    return folder, fmpy.read_model_description(str(path))


@pytest.mark.parametrize("action, status, words", [
    (1, 3, ("fmi2DoStep", "input action = 1 refused")),
    (2, 2, ("fmi2DoStep", "too long")),
    (3, 3, ("fmi2DoStep", "unexpected ZeroDivisionError")),
    (4, 3, ("fmi2DoStep", "returned None")),
    (5, 2, ("refused by returning False",)),
], ids=["InputError", "StepRejectedError", "other_exception", "returns_None", "returns_False"])
def test_model_exceptions_map_to_fmi_statuses(probe, action, status, words):
    from fmpy.fmi1 import FMICallException

    folder, description = probe
    host = Host(folder, description)
    host.initialize()
    host.slave.setInteger([host.refs["action"]], [action])
    with pytest.raises(FMICallException) as caught:
        host.slave.doStep(0.0, 0.01)
    assert caught.value.status == status
    assert any(s == status and all(w in text for w in words) for s, text in host.messages), \
        host.messages
    if status == 2:  # a refused step: terminate is allowed, the instance stays usable
        host.slave.terminate()
    host.free()


def test_an_initialization_call_returning_false_is_an_error(probe):
    folder, description = probe
    host = Host(folder, description)
    host.slave.setupExperiment(startTime=0.0)
    host.slave.enterInitializationMode()
    host.slave.setBoolean([host.refs["refuse_init"]], [True])
    _expect_error(host, host.slave.exitInitializationMode, "exit_initialization_mode",
                  "returned False")
    host.free()


# ----- no trace in sys.path / sys.modules per instance -------------------------------------------

def test_500_instantiations_leave_sys_path_and_sys_modules_unchanged(fmu_paths):
    facts = instantiate_free_cycles(fmu_paths["WheelController"], 500)
    print(f"RSS growth over 500 instantiate/free cycles: {facts['rss_growth_kib']} KiB")
    assert facts["path_unchanged"]
    assert facts["modules_added"] == [] and facts["modules_removed"] == []
    # a leak of one slave per cycle (its core, fuzzy tables, ports) is far above this
    assert facts["rss_growth_kib"] < 4096, facts


def test_instance_state_round_trip_restores_the_step_that_was_refused(probe):
    folder, description = probe
    host = Host(folder, description)
    host.initialize()
    host.slave.doStep(0.0, 0.01)
    saved = host.slave.getFMUstate()
    host.slave.setInteger([host.refs["action"]], [5])
    from fmpy.fmi1 import FMICallException

    with pytest.raises(FMICallException):
        host.slave.doStep(0.01, 0.01)
    host.slave.setFMUstate(saved)  # back to stepComplete with count 1
    host.slave.freeFMUstate(saved)
    host.slave.setInteger([host.refs["action"]], [0])
    host.slave.doStep(0.01, 0.01)
    assert host.slave.getInteger([host.refs["count"]]) == [2]
    host.slave.terminate()
    host.free()


def test_string_parameter_reads_back_what_was_set(extracted):
    folder, description = extracted["WheelController"]
    host = Host(folder, description)
    host.slave.setupExperiment(startTime=0.0)
    host.slave.enterInitializationMode()
    host.slave.setString([host.refs["mode"]], ["pid"])
    assert host.slave.getString([host.refs["mode"]]) == [b"pid"]
    host.slave.exitInitializationMode()
    assert host.slave.getString([host.refs["mode"]]) == [b"pid"]
    assert host.slave.getTypesPlatform() == "default"
    assert host.slave.getVersion() == "2.0"
    host.slave.terminate()
    host.free()


@pytest.mark.parametrize("variable, words", [
    ("SONOTRACK_PYTHON", ("Python executable /nonexistent/python (from SONOTRACK_PYTHON)",)),
    ("SONOTRACK_LIBPYTHON", ("libpython could not be loaded from /nonexistent/",
                             "from SONOTRACK_LIBPYTHON")),
], ids=["python", "libpython"])
def test_c_host_override_pointing_nowhere_is_refused_with_a_message(c_host, extracted, variable,
                                                                     words):
    plan, _ = _plan(extracted, ["WheelController"])
    env = _host_env()
    env[variable] = "/nonexistent/python" if variable == "SONOTRACK_PYTHON" else \
        "/nonexistent/libpython3.11.so"
    completed = subprocess.run([str(c_host)], input=plan, capture_output=True, text=True, env=env,
                               cwd="/", timeout=120)
    assert completed.returncode == 4  # fmi2Instantiate returned NULL; no crash
    assert "returned NULL" in completed.stderr
    assert all(word in completed.stderr for word in words), completed.stderr


def test_c_host_runs_the_builds_python_environment(c_host, probe):
    """Without PYTHONPATH, the interpreter the FMU starts is the build's venv (its numpy)."""
    folder, description = probe
    refs = {v.name: v.valueReference for v in description.modelVariables}
    binary = folder / "binaries" / "linux64" / "Probe.so"
    plan = (f"1 1\n{binary} {description.guid} {(folder / 'resources').as_uri()} c_probe 0.01 "
            f"0 1 {refs['action']} 0 1 {refs['elapsed']} 1 {refs['count']} 0\n6\n")
    completed = _run_host(c_host, plan)
    assert completed.returncode == 0, completed.stderr[-2000:]
    assert completed.stdout.split() == ["0", "0", "0", "1"]  # step 0, FMU 0, elapsed, count
    assert f"sys.prefix={sys.prefix}" in completed.stderr, completed.stderr


_UNLOAD_RELOAD = textwrap.dedent('''
    import sys
    import fmpy
    for round_ in range(2):  # fmpy unloads (dlclose) each binary when simulate_fmu returns
        for path in sys.argv[1:]:
            result = fmpy.simulate_fmu(path, stop_time=0.1)
            assert len(result) > 1
    print("done", flush=True)
''')


def test_python_host_unloading_and_reloading_every_fmu_exits_cleanly(fmu_paths):
    completed = subprocess.run([sys.executable, "-c", _UNLOAD_RELOAD,
                                *[str(fmu_paths[name]) for name in NAMES]],
                               capture_output=True, text=True, cwd="/", timeout=600)
    assert completed.returncode == 0, completed.stderr[-3000:]
    assert completed.stdout.strip() == "done"
    assert not any(sign in completed.stderr for sign in ABORT_SIGNS), completed.stderr[-3000:]
