"""What the tests of sonotrack's own FMI binary share: the C host's plans and checks, an fmpy
host with a logger that keeps every message, and the probe slave whose do_step does what an
input says. The fixtures built from these live in tests/integration/orchestrator/builder/fmi_binary/conftest.py;
running FMUs from many threads is tests/support/fmi_threads.py, reading a library's glibc needs
tests/support/elf_versions.py.

The test modules in tests/integration/orchestrator/builder/fmi_binary/, one concept each
(docs/fmi_binary.md states the contract they check): ``test_c_host`` (a compiled C host, also
under AddressSanitizer), ``test_refusals`` (every refusal class and status mapping),
``test_calls`` (string and FMU-state round trips), ``test_lifetime`` (instantiate/free cycles,
unload and reload), ``test_builds`` (two builds of one model in one process), ``test_time_checks``,
``test_threads``, ``test_isolation``, ``test_finding_python`` and ``test_old_glibc``;
tests/unit/orchestrator/builder/test_fmi_binary.py checks which C sources a library was compiled
from and which glibc it needs.
"""

import os
import subprocess
import textwrap
from pathlib import Path

import pytest

from orchestrator.builder.fmus import FMU_PACKAGES

from tests.support.fmu_checks import DRIVES

__all__ = ["NAMES", "STEPS", "ABORT_SIGNS", "C_HOST_SOURCE", "LEAK_SUPPRESSIONS", "SANITIZER_FINDINGS",
           "PROBE_SOURCE", "PROBE_RANGES", "Host",
           "fmi_headers", "host_env", "plan", "fmpy_reference", "run_host", "check_host_run", "expect_error",
           "wheel_reference_voltage"]

NAMES = list(FMU_PACKAGES)
STEPS = 200
ABORT_SIGNS = ("abort", "corrupted", "Fatal Python error", "Segmentation", "double free")
C_HOST_SOURCE = Path(__file__).with_name("fmi_host.c")


# The interpreter is never finalized (docs/fmi_binary.md, "Never aborting at exit"), so what
# Python, its extension modules and the libraries they load allocated is still held at exit and
# LeakSanitizer lists it. Those allocations are suppressed by the module that made them; the
# library's own (instances, binding tables, states, log buffers) are made by its code called
# straight from the host's main, with none of these modules on the stack, so a leak of them is
# reported (seen: dropping one free() in free_instance fails test_fmi_binary_c_host).
LEAK_SUPPRESSIONS = """\
leak:libpython
leak:.cpython-
leak:libcrypto
leak:libssl
leak:libffi
leak:libz.so
leak:libexpat
leak:liblzma
leak:libbz2
leak:openblas
"""
SANITIZER_FINDINGS = ("ERROR: AddressSanitizer", "ERROR: LeakSanitizer", "runtime error:",
                       "SUMMARY: ")


def fmi_headers():
    """The FMI 2.0 headers fmpy ships (what the binary is compiled against)."""
    import fmpy

    return Path(fmpy.__file__).parent / "c-code"


def host_env():
    """The caller's environment minus anything that would help the FMU find Python."""
    return {k: v for k, v in os.environ.items()
            if k not in ("LD_PRELOAD", "PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV",
                         "SONOTRACK_PYTHON", "SONOTRACK_LIBPYTHON")}


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


def plan(extracted, names, steps=STEPS):
    """The C host's plan text and, per FMU, (step, drive, typed input and output names).

    ``names`` are model names, each run from its folder in ``extracted``; an entry may also be
    a tuple (model name, folder, description, instance name), to run one model several times
    in one plan, from one folder or from several copies.
    """
    entries = [entry if isinstance(entry, tuple) else (entry, *extracted[entry], f"c_{entry}")
               for entry in names]
    header = [f"{len(entries)} {steps}"]
    layouts = []
    for name, folder, description, instance in entries:
        h, drive = DRIVES[name]
        variables, groups = _ports(description, drive(0.0))
        binary = folder / "binaries" / "linux64" / f"{description.coSimulation.modelIdentifier}.so"
        fields = [str(binary), description.guid, (folder / "resources").as_uri(), instance,
                  repr(h)]
        for group in groups:
            fields += [str(len(group))] + [str(variables[n].valueReference) for n in group]
        header.append(" ".join(fields))
        layouts.append((h, drive, groups))
    rows = []
    for k in range(steps):
        for h, drive, groups in layouts:
            values = drive(k * h)
            rows.append(" ".join([repr(float(values[n])) for n in groups[0]] +
                                 [str(int(values[n])) for n in groups[1]] +
                                 [str(int(bool(values[n]))) for n in groups[2]]))
    return "\n".join(header + rows) + "\n", layouts


def fmpy_reference(extracted, name, steps=STEPS):
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
    for k in range(steps):
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


def run_host(c_host, plan_text, *flags, env=None):
    """Run the C host on a plan, with no LD_PRELOAD and no PYTHONPATH (unless ``env`` says)."""
    return subprocess.run([str(c_host), *flags], input=plan_text, capture_output=True, text=True,
                          env=host_env() if env is None else env, cwd="/", timeout=600)


def check_host_run(completed, names, extracted):
    """Exit status 0, no abort text, and every FMU's outputs equal fmpy's to 1e-12."""
    assert completed.returncode == 0, completed.stderr[-3000:]
    assert not any(sign in completed.stderr for sign in ABORT_SIGNS), completed.stderr[-3000:]
    ours = {name: [] for name in names}
    for line in completed.stdout.splitlines():
        k, f, *values = line.split()
        ours[names[int(f)]].append([float(v) for v in values])
    for name in names:
        reference = fmpy_reference(extracted, name)
        assert len(ours[name]) == len(reference) == STEPS
        for k, (a, b) in enumerate(zip(ours[name], reference)):
            assert a == pytest.approx(b, rel=0, abs=1e-12), f"{name} step {k}"
        assert ours[name][0] != ours[name][-1] or name == "SoundSource", "nothing moved"


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


def expect_error(host, call, *words):
    """``call()`` fails with fmi2Error (never fmi2Fatal); the last error message has ``words``."""
    from fmpy.fmi1 import FMICallException

    with pytest.raises(FMICallException) as caught:
        call()
    assert caught.value.status == 3  # fmi2Error, never fmi2Fatal
    errors = [text for status, text in host.messages if status == 3]
    assert errors and all(word in errors[-1] for word in words), host.messages


def wheel_reference_voltage():
    """Voltage after one step from rest at v_ref 0.3, v_meas 0.1, from the core itself."""
    from components.control.controller import WheelSpeedController

    return WheelSpeedController().step(0.3, 0.1, 0.005)


PROBE_SOURCE = textwrap.dedent('''
    """A probe slave: do_step does what the ``action`` input says."""

    from ..common.errors import InputError, StepRejectedError
    from ..common.slave import Fmi2Status, SonotrackSlave, load_ranges


    class Probe(SonotrackSlave):
        description = "status-mapping probe"
        valid_ranges = load_ranges("probe")

        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.count = 0
            self.elapsed = 0.0
            self.declare_inputs()
            self.declare_parameters()
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


# Every SonotrackSlave declares its parameters and inputs from its port table.
PROBE_RANGES = textwrap.dedent('''
    [step]
    step_size = { type = "Real", unit = "s", min = 1e-6, max = 1.0 }
    [inputs.action]
    description = "0 ok, 1 InputError, 2 StepRejectedError, 3 ZeroDivisionError, 4 return None, 5 return False, 6 log sys.prefix"
    type = "Integer"
    start = 0
    min = 0
    max = 6
    [parameters.refuse_init]
    description = "exit_initialization_mode returns False"
    type = "Boolean"
    start = false
''')
