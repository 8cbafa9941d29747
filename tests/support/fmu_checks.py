"""Shared checks on a built FMU: isolation from the repo, state round trip, libcosim parity,
instantiate/free cycles (sys.path, sys.modules, RSS)."""

import json
import math
import subprocess
import sys
import textwrap

from orchestrator.fmu.handle import FmuInstance

# Runs an FMU in a child Python that can import numpy and fmpy but not this repository:
# an import hook refuses `components` and `orchestrator`, so the FMU must use its own copy.
_ISOLATED = textwrap.dedent('''
    import sys, importlib.abc
    class Refuse(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in ("components", "orchestrator"):
                raise ImportError("repository package " + name + " must not be imported")
    sys.meta_path.insert(0, Refuse())
    import fmpy
    result = fmpy.simulate_fmu(sys.argv[1], stop_time=float(sys.argv[2]))
    assert not any(m.split(".")[0] in ("components", "orchestrator") for m in sys.modules)
    import json
    last = {n: result[n][-1].item() for n in result.dtype.names}
    print(json.dumps({"rows": len(result), "last": last}))
''')


def run_isolated(path, stop_time):
    """Simulate ``path`` in a child process that cannot import the repo.

    Returns ``{"rows": int, "last": {variable: value}}`` of fmpy's result.
    """
    completed = subprocess.run([sys.executable, "-c", _ISOLATED, str(path), str(stop_time)],
                               capture_output=True, text=True, cwd="/", timeout=300)
    assert completed.returncode == 0, completed.stderr[-2000:]
    return json.loads(completed.stdout.strip().splitlines()[-1])


def outputs_of(description):
    """Names of the output variables of a model description, by type."""
    groups = {"Real": [], "Integer": [], "Boolean": []}
    for variable in description.modelVariables:
        if variable.causality == "output" and variable.type in groups:
            groups[variable.type].append(variable.name)
    return groups


def step_and_record(instance, groups, drive, t0, h, steps):
    """Step ``steps`` times feeding ``drive(t)`` and return every output after each step."""
    rows = []
    for k in range(steps):
        t = t0 + k * h
        instance.set_values(drive(t))
        instance.do_step(t, h)
        row = []
        for type_name in ("Real", "Integer", "Boolean"):
            row += list(instance.get_values(groups[type_name]).values())
        rows.append(tuple(row))
    return rows


def state_round_trip(path, drive, h, warmup=100, steps=500, parameters=None):
    """Save after ``warmup`` steps, run ``steps``, restore (from serialized bytes), run again.

    Returns the two recorded runs, which must be identical bit for bit.
    """
    instance = FmuInstance(path, "round_trip")
    instance.instantiate(parameters=parameters)
    try:
        groups = outputs_of(instance.description)
        step_and_record(instance, groups, drive, 0.0, h, warmup)
        state = instance.get_state()
        data = instance.serialize_state(state)
        instance.free_state(state)
        first = step_and_record(instance, groups, drive, warmup * h, h, steps)
        restored = instance.deserialize_state(data)
        instance.set_state(restored)
        instance.free_state(restored)
        second = step_and_record(instance, groups, drive, warmup * h, h, steps)
    finally:
        instance.terminate()
    return first, second


def same_bits(a, b):
    """True when two rows of floats/ints/bools are identical (NaN equal to NaN)."""
    return all((x == y) or (isinstance(x, float) and math.isnan(x) and math.isnan(y))
               for x, y in zip(a, b)) and len(a) == len(b)


_LIBCOSIM = textwrap.dedent('''
    import json, sys
    from libcosimpy.CosimEnums import CosimVariableCausality, CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    job = json.loads(sys.stdin.read())
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_step_size(step_size=int(round(job["h"] * 1e9)))
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=job["path"], instance_name="fmu"))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    manipulator = CosimManipulator.create_override()
    execution.add_manipulator(manipulator)
    variables = {v.name.decode(): v for v in execution.slave_variables(index)}
    kind = {CosimVariableType.REAL.value: "Real", CosimVariableType.INTEGER.value: "Integer",
            CosimVariableType.BOOLEAN.value: "Boolean", CosimVariableType.STRING.value: "String"}
    for name, value in job["parameters"].items():
        variable = variables[name]
        setter = {"Real": execution.real_initial_value, "Integer": execution.integer_initial_value,
                  "Boolean": execution.boolean_initial_value,
                  "String": execution.string_initial_value}[kind[variable.type]]
        setter(index, variable.reference, value)
    outputs = {"Real": [], "Integer": [], "Boolean": []}
    for name, variable in variables.items():
        if variable.causality == CosimVariableCausality.OUTPUT.value and \\
                kind[variable.type] in outputs:
            outputs[kind[variable.type]].append(variable.reference)
    readers = {"Real": observer.last_real_values, "Integer": observer.last_integer_values,
               "Boolean": observer.last_boolean_values}
    writers = {"Real": manipulator.slave_real_values, "Integer": manipulator.slave_integer_values,
               "Boolean": manipulator.slave_boolean_values}
    rows = []
    for inputs in job["inputs"]:
        for name, value in inputs.items():
            variable = variables[name]
            writers[kind[variable.type]](index, [variable.reference], [value])
        execution.step(1)
        row = []
        for type_name in ("Real", "Integer", "Boolean"):
            if outputs[type_name]:
                row += list(readers[type_name](index, outputs[type_name]))
        rows.append(row)
    print(json.dumps(rows))
''')


def run_libcosim(path, drive, h, steps, parameters=None):
    """Step one FMU in libcosim feeding ``drive(t)``; return its outputs after each step.

    Rows have the same layout as :func:`step_and_record` (Real, Integer, Boolean outputs).
    libcosim runs in a child process: when it releases an execution it unloads the FMU's
    binary, and unloading a pythonfmu binary inside a Python host leaves that interpreter
    liable to crash later (seen as segfaults in unrelated tests).
    """
    job = {"path": str(path), "h": h, "parameters": parameters or {},
           "inputs": [drive(k * h) for k in range(steps)]}
    completed = subprocess.run([sys.executable, "-c", _LIBCOSIM], input=json.dumps(job),
                               capture_output=True, text=True, timeout=600)
    assert completed.returncode == 0, completed.stderr[-2000:]
    return [tuple(row) for row in json.loads(completed.stdout.strip().splitlines()[-1])]


_CYCLES = textwrap.dedent('''
    import json, resource, sys
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    path, cycles = sys.argv[1], int(sys.argv[2])
    description = fmpy.read_model_description(path)
    slave = FMU2Slave(guid=description.guid, unzipDirectory=fmpy.extract(path),
                      modelIdentifier=description.coSimulation.modelIdentifier, instanceName="c")

    def cycle():
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.005)
        slave.terminate()
        slave.fmi2FreeInstance(slave.component)

    def rss_kib():
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * resource.getpagesize() // 1024

    for _ in range(20):  # first load of the code and warm-up of the allocator
        cycle()
    path_before, modules_before, rss_before = list(sys.path), set(sys.modules), rss_kib()
    for _ in range(cycles):
        cycle()
    print(json.dumps({"path_unchanged": sys.path == path_before,
                      "modules_added": sorted(set(sys.modules) - modules_before),
                      "modules_removed": sorted(modules_before - set(sys.modules)),
                      "rss_growth_kib": rss_kib() - rss_before, "cycles": cycles}))
''')


def instantiate_free_cycles(path, cycles=500):
    """Run ``cycles`` instantiate/step/free cycles of one FMU in a fresh Python; return facts."""
    completed = subprocess.run([sys.executable, "-c", _CYCLES, str(path), str(cycles)],
                               capture_output=True, text=True, cwd="/", timeout=600)
    assert completed.returncode == 0, completed.stderr[-2000:]
    return json.loads(completed.stdout.splitlines()[-1])


# Inputs that exercise each FMU (time-varying where the FMU has inputs), and its step.
DRIVES = {
    "RobotPlant": (0.005, lambda t: {"voltage_left": 6.0 + 2.0 * math.sin(3.0 * t),
                                      "voltage_right": 5.0}),
    "WheelController": (0.005, lambda t: {"v_ref": min(0.3, 0.3 * t),
                                           "v_meas": 0.2 + 0.05 * math.sin(3.0 * t),
                                           "supply_voltage": 11.1}),
    "CurvaturePlanner": (0.02, lambda t: {"distance": 2.0, "bearing": -math.pi / 4,
                                           "valid": True, "measurement_id": 1,
                                           "wheel_speed_left": min(0.3, 0.3 * t),
                                           "wheel_speed_right": min(0.25, 0.25 * t)}),
    "SoundSource": (0.01, lambda t: {}),
    "AcousticLocalizer": (0.01, lambda t: {"source_x": 0.5 + 0.05 * t, "source_y": 2.0,
                                            "emitting": True, "robot_x": 0.0, "robot_y": 0.0,
                                            "robot_heading": math.pi / 2}),
}
