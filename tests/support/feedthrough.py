"""Measure an FMU's direct feedthrough through fmpy and compare it with its ModelStructure.

An output depends directly on an input when setting that input, with no ``fmi2DoStep`` in
between, changes what ``fmi2Get<Type>`` returns for the output. Two readings are measured:

- in step mode (after a few steps), against ``ModelStructure/Outputs``;
- at initialisation (input set in initialisation mode, outputs read after
  ``fmi2ExitInitializationMode``), against the inputs among ``ModelStructure/InitialUnknowns``.

The declared side is read from the modelDescription.xml by fmpy, independently of the slave code
that wrote it.
"""

import math
import shutil

import fmpy
from fmpy.fmi2 import FMU2Slave

__all__ = ["declared_dependencies", "measured_dependencies", "feedthrough_mismatches"]

_TYPES = ("Real", "Integer", "Boolean")


def declared_dependencies(description):
    """Declared input dependencies: ``{"outputs": {out: set}, "initial": {out: set}}``.

    An ``Unknown`` without a ``dependencies`` attribute depends on every input (FMI 2.0,
    section 2.2.8); an output not listed at all likewise.
    """
    inputs = {v.name for v in description.modelVariables if v.causality == "input"}
    outputs = [v.name for v in description.modelVariables if v.causality == "output"]

    def read(unknowns):
        listed = {}
        for unknown in unknowns:
            if unknown.dependencies is None:
                listed[unknown.variable.name] = set(inputs)
            else:
                listed[unknown.variable.name] = {d.name for d in unknown.dependencies
                                                 if d.name in inputs}
        return {name: listed.get(name, set(inputs)) for name in outputs}

    return {"outputs": read(description.outputs), "initial": read(description.initialUnknowns)}


def _perturbations(value, type_name):
    if type_name == "Real":
        return [value + 0.1, value - 0.23 if value != 0.23 else -0.5]
    if type_name == "Integer":
        return [value + 1, value + 2]
    return [not value]


class _Probe:
    """One fmpy instance of the FMU with name-based typed get/set."""

    def __init__(self, path, unzip_dir, description, name):
        self.variables = {v.name: v for v in description.modelVariables}
        self.slave = FMU2Slave(guid=description.guid, unzipDirectory=unzip_dir,
                               modelIdentifier=description.coSimulation.modelIdentifier,
                               instanceName=name)
        self.slave.instantiate()
        self.slave.setupExperiment(startTime=0.0)
        self.slave.enterInitializationMode()

    def set(self, values):
        for name, value in values.items():
            variable = self.variables[name]
            setter = getattr(self.slave, "set" + variable.type)
            setter([variable.valueReference], [value])

    def get(self, names):
        row = {}
        for name in names:
            variable = self.variables[name]
            row[name] = getattr(self.slave, "get" + variable.type)([variable.valueReference])[0]
        return row

    def close(self):
        self.slave.terminate()
        self.slave.freeInstance()


def _differs(a, b):
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return False
    return a != b


def measured_dependencies(path, drive, step_size, warmup=5):
    """Measure which outputs change when each input is set, without a step in between.

    Parameters
    ----------
    path : path-like
        The ``.fmu``.
    drive : callable
        ``drive(t)`` returns valid values for every input at time ``t``.
    step_size : float
        Communication step of the warm-up steps.
    warmup : int
        Steps taken before the step-mode measurement (so states are not at their start values).

    Returns
    -------
    dict
        ``{"outputs": {out: set of inputs}, "initial": {out: set of inputs}}``.
    """
    description = fmpy.read_model_description(str(path))
    unzip_dir = fmpy.extract(str(path))
    try:
        inputs = [v for v in description.modelVariables if v.causality == "input"]
        outputs = [v.name for v in description.modelVariables
                   if v.causality == "output" and v.type in _TYPES]
        base = drive(0.0)

        def at_initialisation(changed_input=None, value=None):
            probe = _Probe(path, unzip_dir, description, "feedthrough_init")
            try:
                probe.set(base)
                if changed_input is not None:
                    probe.set({changed_input: value})
                probe.slave.exitInitializationMode()
                return probe.get(outputs)
            finally:
                probe.close()

        initial = {name: set() for name in outputs}
        reference = at_initialisation()
        for variable in inputs:
            for value in _perturbations(base[variable.name], variable.type):
                row = at_initialisation(variable.name, value)
                for name in outputs:
                    if _differs(row[name], reference[name]):
                        initial[name].add(variable.name)

        stepped = {name: set() for name in outputs}
        probe = _Probe(path, unzip_dir, description, "feedthrough_step")
        try:
            probe.set(base)
            probe.slave.exitInitializationMode()
            for k in range(warmup):
                t = k * step_size
                probe.set(drive(t))
                probe.slave.doStep(currentCommunicationPoint=t, communicationStepSize=step_size)
            held = drive(warmup * step_size)
            probe.set(held)
            for variable in inputs:
                for value in _perturbations(held[variable.name], variable.type):
                    before = probe.get(outputs)
                    probe.set({variable.name: value})
                    after = probe.get(outputs)
                    probe.set({variable.name: held[variable.name]})
                    for name in outputs:
                        if _differs(before[name], after[name]):
                            stepped[name].add(variable.name)
        finally:
            probe.close()
        return {"outputs": stepped, "initial": initial}
    finally:
        shutil.rmtree(unzip_dir, ignore_errors=True)


def feedthrough_mismatches(declared, measured):
    """One line per output whose declared and measured input dependencies differ."""
    lines = []
    for section, title in (("outputs", "Outputs"), ("initial", "InitialUnknowns")):
        for name in sorted(measured[section]):
            want, got = declared[section].get(name, set()), measured[section][name]
            if want != got:
                lines.append(f"{title} {name}: declared {sorted(want)}, measured {sorted(got)}")
    return lines
