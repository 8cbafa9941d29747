"""Refusals by sonotrack's FMI binary, and how model exceptions map to FMI statuses.

Every refusal class (wrong state, set of an output or of a fixed parameter after initialisation,
unknown or mistyped value reference, bad parameter, corrupted state, unsupported call, GUID of
another build) is an fmi2Error with a message naming the call and the variable, after which the
instance is freed and a new one runs, or reset gives a working instance. A model's exceptions
and return values map to fmi2Error / fmi2Discard as docs/fmi_binary.md ("Statuses") says. The
refusals, a '%' in names and messages, and String and FMU-state round trips run again through
the library built with AddressSanitizer and UBSan: no finding, the same statuses and messages.
"""

import json
import os
import shutil
import subprocess
import sys
import textwrap

import pytest

from tests.support.fmi_binary import SANITIZER_FINDINGS, Host, expect_error, wheel_reference_voltage

pytestmark = pytest.mark.integration


def _corrupt(slave):
    state = slave.getFMUstate()
    data = bytearray(slave.serializeFMUstate(state))
    slave.freeFMUstate(state)
    data[40:48] = b"\xff" * 8  # inside the JSON payload, after the 32-byte header
    return bytes(data)


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


@pytest.mark.parametrize("refusal", list(REFUSALS), ids=list(REFUSALS))
def test_refusal_is_an_error_with_a_message_then_free_and_a_new_instance_runs(extracted,
                                                                             refusal):
    folder, description = extracted["WheelController"]
    prepare, call, words = REFUSALS[refusal]
    host = Host(folder, description, name=refusal)
    prepare(host)
    expect_error(host, lambda: call(host), *words)
    host.free()
    fresh = Host(folder, description, name="fresh")
    fresh.initialize()
    assert fresh.step() == pytest.approx(wheel_reference_voltage(), abs=1e-12)
    fresh.slave.terminate()
    fresh.free()


def test_after_an_error_reset_gives_a_working_instance(extracted):
    folder, description = extracted["WheelController"]
    host = Host(folder, description)
    expect_error(host, lambda: host.initialize(mode="spiral"), "spiral")
    host.slave.reset()
    host.initialize()
    assert host.step() == pytest.approx(wheel_reference_voltage(), abs=1e-12)
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
    expect_error(host, host.slave.exitInitializationMode, "exit_initialization_mode",
                 "returned False")
    host.free()


# ----- the same refusals under AddressSanitizer and UBSan, in a Python host --------------------

_UNDER_SANITIZERS = textwrap.dedent('''
    import json, sys
    sys.path.insert(0, sys.argv[1])
    import fmpy
    from tests.support.fmi_binary import Host
    from tests.integration.orchestrator.builder.fmi_binary.test_refusals import REFUSALS

    folder = sys.argv[2]
    description = fmpy.read_model_description(folder)
    log = []
    for name, (prepare, call, words) in REFUSALS.items():
        host = Host(folder, description, name=f"{name} 100%")  # '%' reaches the host's printf
        prepare(host)
        try:
            call(host)
        except Exception as exc:
            log.append([name, "raised", getattr(exc, "status", None)])
        log += [[name, status, text] for status, text in host.messages]
        host.free()
    host = Host(folder, description, name="round trips")
    try:  # a refused value with '%' in the message: the escaping path
        host.initialize(mode="50%-spiral")
    except Exception as exc:
        log.append(["percent", "raised", getattr(exc, "status", None)])
    host.slave.reset()
    host.slave.setupExperiment(startTime=0.0)
    host.slave.enterInitializationMode()
    host.slave.setString([host.refs["mode"]], ["pid"])
    log.append(["string", host.slave.getString([host.refs["mode"]])[0].decode()])
    host.slave.exitInitializationMode()
    log.append(["steps", [host.step(k) for k in range(20)]])
    state = host.slave.getFMUstate()
    blob = host.slave.serializeFMUstate(state)
    copy = host.slave.deSerializeFMUstate(blob)
    host.slave.setFMUstate(copy)
    host.slave.freeFMUstate(state)
    host.slave.freeFMUstate(copy)
    log.append(["restored", [host.step(k) for k in range(20, 25)], len(blob)])
    log += [["round trips", status, text] for status, text in host.messages]
    host.slave.terminate()
    host.free()
    print(json.dumps(log))
''')


def test_refusals_and_round_trips_under_address_and_undefined_behaviour_sanitizers(
        extracted, sanitized, tmp_path):
    """Every refusal class, a '%' in names and messages, strings and FMU states, through the
    sanitized library in a Python host (the ASan runtime preloaded): no finding, and the same
    statuses, messages and numbers as the shipped library gives."""
    from orchestrator.builder.fmus import REPO_ROOT

    _, library, _, runtime = sanitized
    folder, description = extracted["WheelController"]
    copy = tmp_path / "WheelController"
    shutil.copytree(folder, copy)
    shutil.copy(library, copy / "binaries" / "linux64" / "WheelController.so")
    env = dict(os.environ, LD_PRELOAD=runtime,
               ASAN_OPTIONS="detect_leaks=0:halt_on_error=1",  # leaks: the C host test
               UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1")
    runs = {}
    for label, unzipped, environment in (("sanitized", copy, env), ("shipped", folder, None)):
        completed = subprocess.run([sys.executable, "-c", _UNDER_SANITIZERS, str(REPO_ROOT),
                                    str(unzipped)], capture_output=True, text=True, cwd="/",
                                   env=environment, timeout=600)
        assert completed.returncode == 0, completed.stderr[-6000:]
        assert not any(sign in completed.stderr for sign in SANITIZER_FINDINGS), \
            completed.stderr[-6000:]
        runs[label] = json.loads(completed.stdout.splitlines()[-1])
    assert runs["sanitized"] == runs["shipped"]
    refused = [entry for entry in runs["shipped"] if entry[1] == "raised"]
    assert len(refused) == len(REFUSALS) + 1 and all(entry[2] == 3 for entry in refused)
    # the logger gets a printf format: the model's "%" arrives escaped as "%%"
    assert any("'50%%-spiral'" in str(entry[-1]) for entry in runs["shipped"]), runs["shipped"]
