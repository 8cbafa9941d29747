"""The whole-system FMU (TrackingSystem.fmu) in every host its tests use, and its reference.

The reference is ``sonotrack run`` of the same scenario: our master stepping the five FMUs
through fmpy (:func:`reference`). Each host runs the system FMU alone at the macro step
(20 ms) and returns ``{port: array}`` with the rows after every step; its ports are named
``<instance>_<output>`` where the run's columns are ``<instance>.<output>``
(:func:`fmu_name`).

- :func:`fmpy_run`: ``fmpy.simulate_fmu``, as an fmpy user runs it (rows from t0);
- :func:`libcosim_run`: libcosim (libcosimpy) on a one-component ``.ssd`` binding the
  parameters, in a child process (:func:`orchestrator.hosts.libcosim.run_libcosim_ssd`);
- :func:`ecos_run`: ecos through the ``ecospy`` API (its engine, values read as doubles, not
  the command line's six-decimal CSV), in a child process;
- :func:`c_host_plan` / :func:`c_host_rows`: the C host of tests/support/fmi_host.c.
"""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np

__all__ = ["STEP", "fmu_name", "reference", "fmpy_run", "libcosim_run", "ecos_run",
           "c_host_plan", "c_host_rows", "largest_difference"]

STEP = 0.02


def fmu_name(column):
    """The system FMU's port for a run column: ``plant.x`` -> ``plant_x``."""
    return column.replace(".", "_", 1)


def reference(scenario, fmu_dir, out_dir):
    """``sonotrack run`` of ``scenario`` recorded every 20 ms: ``{FMU port: array}``.

    ``distance_to_source`` is computed from the recorded true positions (the run's summary
    measures the distance the same way).
    """
    from orchestrator.run import read_results, run_scenario

    result = run_scenario(scenario, out_dir, progress=False, fmu_dir=fmu_dir, plots=False,
                          record_interval=STEP)
    columns = read_results(result.results_csv)
    rows = {fmu_name(name): np.asarray(values, dtype=float) for name, values in columns.items()}
    rows["distance_to_source"] = np.hypot(rows["plant_x"] - rows["source_x"],
                                          rows["plant_y"] - rows["source_y"])
    return rows


def largest_difference(ours, theirs, names, first_row=0):
    """``(largest |ours - theirs|, port)`` over ``names``; ``theirs`` from ``first_row`` on."""
    worst, where = 0.0, None
    for name in names:
        mine = np.asarray(ours[name], dtype=float)
        other = np.asarray(theirs[name], dtype=float)[first_row:first_row + len(mine)]
        assert len(mine) == len(other), f"{name}: {len(mine)} rows against {len(other)}"
        difference = float(np.max(np.abs(mine - other))) if len(mine) else 0.0
        if not difference <= worst:   # NaN counts as the worst
            worst, where = difference, name
    return worst, where


def fmpy_run(fmu_path, stop_time, parameters=None):
    """``fmpy.simulate_fmu`` at 20 ms with ``parameters`` as start values: every output."""
    import fmpy

    result = fmpy.simulate_fmu(str(fmu_path), stop_time=stop_time, step_size=STEP,
                               output_interval=STEP, start_values=dict(parameters or {}))
    return {name: np.asarray(result[name], dtype=float) for name in result.dtype.names}


def _one_component_ssd(fmu_path, parameters, folder):
    """A ``.ssd`` holding only the system FMU, binding ``parameters``, beside a copy of it."""
    import shutil

    from orchestrator.ssp import write_ssd
    from orchestrator.ssp.model import ComponentDescription, ParameterValue, SystemDescription

    kinds = {bool: "Boolean", int: "Integer", float: "Real", str: "String"}
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy2(fmu_path, folder / Path(fmu_path).name)
    bound = {name: ParameterValue(kinds[type(value)], value)
             for name, value in (parameters or {}).items()}
    system = SystemDescription(
        name="one", components=[ComponentDescription(
            name="system", source=Path(fmu_path).name, parameters=bound,
            step_size_hint=STEP)],
        base_step=STEP, parameter_set_name="overrides" if bound else None)
    path = folder / "SystemStructure.ssd"
    write_ssd(path, system)
    return path


def libcosim_run(fmu_path, stop_time, ports, folder, parameters=None):
    """libcosim on the system FMU alone: the Real ``ports`` after every 20 ms step."""
    from orchestrator.hosts.libcosim import run_libcosim_ssd

    ssd = _one_component_ssd(fmu_path, parameters, folder)
    _, rows = run_libcosim_ssd(ssd, STEP, stop_time, [f"system.{p}" for p in ports])
    table = np.asarray(rows, dtype=float)
    return {port: table[:, i] for i, port in enumerate(ports)}


_ECOS_CHILD = textwrap.dedent('''
    import json, sys
    from ecospy.EcosSimulation import EcosSimulation
    from ecospy.EcosSimulationStructure import EcosSimulationStructure

    job = json.loads(sys.stdin.read())
    rows = []
    with EcosSimulationStructure() as structure:
        structure.add_model("system", job["fmu"], job["step"])
        parameters = {f"system::{k}": v for k, v in job["parameters"].items()}
        if parameters:
            structure.add_parameter_set("overrides", parameters)
        with EcosSimulation(structure=structure, step_size=job["step"]) as simulation:
            if not simulation.init(parameter_set="overrides" if parameters else None):
                raise SystemExit("ecos: init failed")
            for _ in range(job["steps"]):
                simulation.step(1)
                rows.append([simulation.get_real(f"system::{p}") for p in job["ports"]])
            simulation.terminate()
    print(json.dumps(rows))
''')


def ecos_run(fmu_path, stop_time, ports, parameters=None):
    """ecos (the ecospy engine) on the system FMU: the Real ``ports`` after every step."""
    job = {"fmu": str(fmu_path), "step": STEP, "steps": int(round(stop_time / STEP)),
           "ports": list(ports), "parameters": dict(parameters or {})}
    completed = subprocess.run([sys.executable, "-c", _ECOS_CHILD], input=json.dumps(job),
                               capture_output=True, text=True, timeout=600)
    assert completed.returncode == 0, completed.stderr[-3000:]
    table = np.asarray(json.loads(completed.stdout.strip().splitlines()[-1]), dtype=float)
    return {port: table[:, i] for i, port in enumerate(ports)}


def c_host_plan(folder, description, stop_time, ports):
    """The C host's plan: the unzipped system FMU, no inputs, the Real ``ports`` read."""
    variables = {v.name: v for v in description.modelVariables}
    binary = folder / "binaries" / "linux64" / f"{description.coSimulation.modelIdentifier}.so"
    fields = [str(binary), description.guid, (folder / "resources").as_uri(), "c_system",
              repr(STEP), "0", "0", "0", str(len(ports))]
    fields += [str(variables[p].valueReference) for p in ports] + ["0", "0"]
    steps = int(round(stop_time / STEP))
    return f"1 {steps}\n" + " ".join(fields) + "\n" + "\n" * steps


def c_host_rows(stdout, ports):
    """The C host's output lines as ``{port: array}`` (rows after every step)."""
    table = np.asarray([[float(v) for v in line.split()[2:]] for line in stdout.splitlines()
                        if line.strip()], dtype=float)
    return {port: table[:, i] for i, port in enumerate(ports)}
