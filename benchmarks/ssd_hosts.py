"""What each host applies of fmus/SystemStructure.ssd: measured from trajectories, not assumed.

The committed .ssd (with freshly built FMUs) runs for STOP seconds in fmpy's ``simulate_ssp``,
libcosim (no step size given), ecos (with and without ``--parameterSet``) and our master. Our
Jacobi master also runs eight reference variants: the file's parameter bindings applied in full,
only the String ``source.path``, only the Integer ``localizer.seed``, or none; each with the
file's per-component step hints (multi-rate) or every instance at the base step. A host's
trajectory (source, localizer and plant outputs at every 20 ms point) equal to one variant within
the comparison tolerance says what that host applied. Separate runs check whether a host runs
without a step size and whether it refuses a connection whose two connectors declare different
units. Writes benchmarks/results/ssd_hosts.json.
"""

import csv
import json
import shutil
import subprocess
import sys
import tempfile
import textwrap
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks._common import build_fresh, write_result  # noqa: E402
from orchestrator.builder.fmus import FMU_PACKAGES, REPO_ROOT, write_ssp_archive  # noqa: E402
from orchestrator.ssp import read_ssd, write_ssd  # noqa: E402

STOP = 1.0
COLUMNS = ["source.x", "source.y", "localizer.distance", "localizer.bearing", "plant.x",
           "plant.y"]
TOLERANCE = 1e-6   # ecos prints six decimals; every other host is compared at the same bar


def _ours(ssd, seed, multi_rate, out_dir, stop=STOP, base_step=0.01):
    from orchestrator.run.runner import run_scenario
    from orchestrator.scenario import scenario_from_dict

    system = read_ssd(ssd)
    data = {"name": "hosts", "system": str(ssd), "stop_time": stop, "seed": seed,
            "parameters": {}, "master": "jacobi"}
    if base_step is not None:
        data["base_step"] = base_step
    if multi_rate:
        data["steps"] = {c.name: c.step_size_hint for c in system.components}
    result = run_scenario(scenario_from_dict(data), out_dir, progress=False, plots=False,
                          record_interval=0.01)
    with open(result.results_csv) as f:
        rows = list(csv.DictReader(f))
    return {float(r["time"]): [float(r[c]) for c in COLUMNS] for r in rows}


def _variant_file(system, folder, name, keep):
    components = []
    for component in system.components:
        parameters = {k: v for k, v in component.parameters.items()
                      if f"{component.name}.{k}" in keep}
        components.append(replace(component, parameters=parameters))
    return write_ssd(folder / f"{name}.ssd", replace(system, components=components, path=None))


def _libcosim(ssd, step=None):
    from orchestrator.hosts.libcosim import run_libcosim_ssd

    base = read_ssd(ssd).base_step if step is None else step
    _, rows = run_libcosim_ssd(ssd, step, STOP, COLUMNS)
    return {round((k + 1) * base, 9): row for k, row in enumerate(rows)}


_FMPY = textwrap.dedent('''
    import json, sys
    from fmpy.ssp.simulation import simulate_ssp
    kwargs = json.loads(sys.argv[2])
    try:
        result = simulate_ssp(sys.argv[1], **kwargs)
    except Exception as error:
        print(json.dumps({"error": f"{type(error).__name__}: {error}"}))
        raise SystemExit(0)
    columns = json.loads(sys.argv[3])
    names = result.dtype.names
    rows = {}
    step = float(result["time"][1] - result["time"][0])
    for record in result:
        # simulate_ssp records the values after the step that starts at `time`
        rows[round(float(record["time"]) + step, 9)] = [float(record[c]) if c in names else None
                                                        for c in columns]
    print(json.dumps({"rows": rows, "step": step, "names": list(names)}))
''')


def _fmpy(ssp, **kwargs):
    completed = subprocess.run([sys.executable, "-c", _FMPY, str(ssp), json.dumps(kwargs),
                                json.dumps(COLUMNS)], capture_output=True, text=True)
    if completed.returncode != 0:
        return {"error": completed.stderr.strip().splitlines()[-1]}
    return json.loads(completed.stdout.strip().splitlines()[-1])


def _ecos(binary, folder, out_dir, parameter_set=None, step=0.01):
    from orchestrator.hosts.ecos import read_ecos_csv, run_ecos

    completed, csv_path = run_ecos(binary, folder, STOP, step, out_dir,
                                   parameter_set=parameter_set)
    if completed.returncode != 0 or csv_path is None:
        return {"error": f"status {completed.returncode}: "
                         f"{(completed.stderr or completed.stdout).strip()[-300:]}"}
    data = read_ecos_csv(csv_path)
    rows = {round(t, 9): [data[c][i] for c in COLUMNS] for i, t in enumerate(data["time"])}
    return {"rows": rows, "path": sorted(set(data["source.path"])),
            "seed": sorted(set(data["localizer.seed"]))}


def _match(rows, variants):
    """Best-matching variant at every 20 ms point (where all instances have just stepped)."""
    times = [round(0.02 * k, 9) for k in range(1, int(round(STOP / 0.02)))]
    distances = {}
    for name, reference in variants.items():
        common = [t for t in times if t in rows and t in reference and None not in rows[t]]
        if len(common) < len(times) // 2:
            continue
        distances[name] = float(np.max(np.abs(np.array([rows[t] for t in common])
                                              - np.array([reference[t] for t in common]))))
    best = min(distances, key=distances.get)
    return {"closest": best, "max_difference": distances[best],
            "exact": distances[best] <= TOLERANCE,
            "all": {k: round(v, 12) for k, v in sorted(distances.items(), key=lambda i: i[1])}}


def main():
    work = Path(tempfile.mkdtemp(prefix="sonotrack_hosts_"))
    fmus = build_fresh(list(FMU_PACKAGES))
    for path in fmus.values():
        shutil.copy2(path, work)
    ssd = work / "SystemStructure.ssd"
    shutil.copy2(REPO_ROOT / "fmus" / "SystemStructure.ssd", ssd)
    ssp = write_ssp_archive(ssd, work / "tracking.ssp")
    system = read_ssd(ssd)
    import fmpy
    default_seed = int(next(v.start for v in fmpy.read_model_description(
        str(work / "AcousticLocalizer.fmu")).modelVariables if v.name == "seed"))
    bound = {"path": "source.path", "seed": "localizer.seed"}
    subsets = {"both": {"source.path", "localizer.seed"}, "path only": {"source.path"},
               "seed only": {"localizer.seed"}, "none": set()}

    variants, system_files = {}, {}
    system_files["no hints"] = write_ssd(work / "no_hints.ssd",
                                         replace(system.without_step_hints(), path=None))
    for subset, keep in subsets.items():
        file = _variant_file(system, work, subset.replace(" ", "_"), keep)
        system_files[subset] = file
        seed = 1 if "localizer.seed" in keep else default_seed
        for multi_rate in (True, False):
            name = f"parameters: {subset}; steps: {'hints' if multi_rate else 'base step'}"
            variants[name] = _ours(file, seed, multi_rate, work / f"ours_{len(variants)}")

    hosts = {}
    lc = _libcosim(ssd)
    hosts["libcosim (from_ssp_file, no step size)"] = {"trajectory": _match(lc, variants)}

    fm = _fmpy(ssp, stop_time=STOP, step_size=0.01)
    hosts["fmpy simulate_ssp (.ssp, step_size=0.01)"] = (
        {"error": fm["error"]} if "error" in fm else
        {"trajectory": _match({float(k): v for k, v in fm["rows"].items()}, variants),
         "recorded_columns": [c for c in COLUMNS if c in fm["names"]]})
    if "error" not in fm:
        # fmpy matches no variant of ours (its loop starts every connector at 0.0), so what it
        # applies is measured against itself: the same run without the file's bindings, and
        # without its step hints.
        facts = hosts["fmpy simulate_ssp (.ssp, step_size=0.01)"]
        for label, variant in (("without parameter bindings", system_files["none"]),
                               ("without step hints", system_files["no hints"])):
            other = _fmpy(write_ssp_archive(variant, work / f"fmpy_{label[8:12]}.ssp"),
                          stop_time=STOP, step_size=0.01)
            same = other.get("rows") == fm["rows"]
            facts[f"same trajectory {label}"] = same
        facts["applies the file's parameter bindings"] = \
            not facts["same trajectory without parameter bindings"]
        facts["applies the step hints"] = not facts["same trajectory without step hints"]
    fm_default = _fmpy(ssp, stop_time=STOP)
    no_step = {"fmpy simulate_ssp (.ssp, step_size=0.01)": (
        fm_default.get("error") or f"runs; step = stop_time/100 = {fm_default['step']} s "
                                   f"(the file's base step is {system.base_step} s)")}

    from orchestrator.hosts.ecos import ecos_binary, run_ecos
    binary, reason = ecos_binary(work)
    if binary is None:
        hosts["ecos"] = {"error": reason}
    else:
        for label, parameter_set in (("ecos simulate --parameterSet default", "default"),
                                     ("ecos simulate (no --parameterSet)", None)):
            result = _ecos(binary, work, work / f"ecos_{parameter_set}", parameter_set)
            hosts[label] = ({"error": result["error"]} if "error" in result else
                            {"trajectory": _match(result["rows"], variants),
                             "source.path read": result["path"],
                             "localizer.seed read": result["seed"]})
        completed = subprocess.run([str(binary), "simulate", "--path", str(work),
                                    "--stopTime", "0.2"], capture_output=True, text=True,
                                   cwd=work)
        no_step["ecos simulate --parameterSet default"] = (
            f"status {completed.returncode}: "
            f"{(completed.stderr or completed.stdout).strip().splitlines()[-1]}")

    ours = _ours(ssd, 1, False, work / "ours_cli")
    hosts["our master (scenario without steps)"] = {"trajectory": _match(ours, variants)}
    no_step["libcosim (from_ssp_file, no step size)"] = (
        f"runs; base step {system.base_step} s from osp:FixedStepAlgorithm")
    no_step["our master (scenario without steps)"] = (
        "runs; a scenario's base_step defaults to 0.01 s (orchestrator/scenario/schema.py), "
        "not read from the file")

    # a connection between connectors with different declared units
    mismatched = replace(system, path=None, components=[
        replace(c, connectors=[replace(k, unit="rad") if (c.name, k.name) ==
                               ("localizer", "source_x") else k for k in c.connectors])
        for c in system.components])
    (work / "units").mkdir()
    unit_ssd = write_ssd(work / "units" / "SystemStructure.ssd", mismatched)
    for path in fmus.values():
        shutil.copy2(path, unit_ssd.parent)
    units = {}
    try:
        _libcosim(unit_ssd)
        units["libcosim (from_ssp_file, no step size)"] = "runs (no unit check)"
    except Exception as error:  # report what happened, whatever it is
        units["libcosim (from_ssp_file, no step size)"] = f"refused: {error}"
    unit_ssp = write_ssp_archive(unit_ssd, work / "units.ssp")
    result = _fmpy(unit_ssp, stop_time=0.2, step_size=0.01)
    units["fmpy simulate_ssp (.ssp, step_size=0.01)"] = (
        f"refused: {result['error']}" if "error" in result else "runs (no unit check)")
    if binary is not None:
        completed, _ = run_ecos(binary, unit_ssd.parent, 0.2, 0.01, work / "ecos_units",
                                parameter_set="default")
        units["ecos simulate --parameterSet default"] = (
            "runs (no unit check)" if completed.returncode == 0 else
            f"refused: status {completed.returncode}")
    try:
        from orchestrator.system import load_system
        load_system(unit_ssd)
        units["our master (scenario without steps)"] = "runs (no unit check)"
    except Exception as error:
        problems = getattr(error, "problems", [str(error)])
        units["our master (scenario without steps)"] = "refused: " + "; ".join(problems)

    for host in hosts:
        hosts[host]["no step size given"] = no_step.get(host, no_step.get(
            "ecos simulate --parameterSet default") if host.startswith("ecos") else None)
        hosts[host]["unit mismatch across a connection"] = units.get(host, units.get(
            "ecos simulate --parameterSet default") if host.startswith("ecos") else None)
    record = {"stop_time_s": STOP, "tolerance": TOLERANCE, "default_localizer_seed": default_seed,
              "variants": list(variants), "hosts": hosts,
              "command": "python benchmarks/ssd_hosts.py"}
    path = write_result("ssd_hosts", record)
    for host, facts in hosts.items():
        print(host)
        for key, value in facts.items():
            shown = value if key != "trajectory" else {k: value[k] for k in
                                                       ("closest", "max_difference", "exact")}
            print(f"  {key}: {shown}")
    print(path)
    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
