"""Cost of FMI calls through sonotrack's FMU binary against pythonfmu's, against our library
before issue 23 and before portable FMUs, on the same slave; FMU sizes (plain and portable);
fmi2Instantiate times in a C host (plain and portable).

WheelController is built from this checkout as ``sonotrack build`` ships it (our binary), then
copied with pythonfmu 0.7.0's linux64 binary put back, with our library as it was at
benchmarks/_fmi_binary_builds.REFERENCE_COMMIT (gcc -O2, as ``make`` built it then) and as it
was at BEFORE_PORTABLE_COMMIT (zig, as ``make`` builds it now), and built with ``--portable``
(the same library; in a Python host the carried runtime is not used). All five are loaded in
one Python process and called through their raw ctypes functions (as the master's hot path
calls them):

* ``getReal`` of 1 and of 20 values, ``setReal`` of the 2 inputs, ``doStep`` (which includes the
  controller's own computation, the same in both);
* each measured as a batch of calls, the binaries alternating batch by batch (their order
  rotated every repetition); medians of the per-call times and of the per-pair ratios. Times are
  the calling thread's CPU time (``time.thread_time``): on a shared machine, wall time also
  counts the time the process waits for a core, which made single batches 10x slower here;
* ``doStep`` also split into the model's own ``do_step`` (the slave class called directly in
  Python, same inputs) and the binary's overhead (the rest), since the model's share is common
  to both binaries and bounds the ratio of the totals.

Also: the default scenario's stepping time (scenarios/s_curve.toml, summary ``wall_time_s``) with
all five FMUs built each way, one fresh process per run, runs alternating; and the RSS growth
over 500 instantiate/free cycles of WheelController with our binary (with sys.path and
sys.modules unchanged). Targets: ours <= 0.7x pythonfmu's per call; ours within +-10 % of the
reference library and of the library before portable FMUs per call (issue 23: thread safety,
the Python search, the glibc 2.17 build and the carried runtime must not cost per call). Also
the size of every FMU, plain and portable (and what it unpacks to), and the wall time of the
first fmi2Instantiate in a fresh C host process (the library starts Python and loads the
model: the build's Python for a plain FMU, its own runtime for a portable one) and of a later
one, per FMU: medians of --instantiate-runs processes, plain and portable alternating.

The machine is shared: the load average is read before and after measuring and recorded.

Writes benchmarks/results/fmi_call_cost.json.

    python benchmarks/fmi_call_cost.py [--repeats 21] [--calls 5000] [--scenario-runs 3]
                                       [--instantiate-runs 11]
"""

import argparse
import ctypes
import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import median, write_result  # noqa: E402
from _fmi_binary_builds import (BEFORE_PORTABLE_COMMIT, REFERENCE_COMMIT,  # noqa: E402
                                before_portable_library, c_host_instantiate_times, fmu_sizes,
                                reference_library, with_library)

ROOT = Path(__file__).resolve().parent.parent
NAMES = ("RobotPlant", "SoundSource", "AcousticLocalizer", "CurvaturePlanner", "WheelController")
TARGET_RATIO = 0.7
REFERENCE_TOLERANCE = 0.10


def build_both(names, out):
    """Build ``names`` into out/ours, out/pythonfmu and out/portable (same code, different linux64
    binary or runtime) and WheelController with the two earlier libraries."""
    from orchestrator.builder.fmus import build_fmu
    from orchestrator.builder.fmi_binary import restore_pythonfmu_binary

    paths = {"ours": {}, "pythonfmu": {}, "portable": {}}
    for name in names:
        paths["ours"][name] = build_fmu(name, out / "ours")
        paths["pythonfmu"][name] = restore_pythonfmu_binary(build_fmu(name, out / "pythonfmu"))
        paths["portable"][name] = build_fmu(name, out / "portable", portable=True)
    paths["reference"] = {"WheelController": with_library(
        paths["ours"]["WheelController"], reference_library(out),
        out / "reference" / "WheelController.fmu")}
    paths["before_portable"] = {"WheelController": with_library(
        paths["ours"]["WheelController"], before_portable_library(out),
        out / "before_portable" / "WheelController.fmu")}
    return paths


class Raw:
    """One initialised WheelController instance behind raw ctypes FMI functions."""

    def __init__(self, path, label):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave, fmi2ValueReference

        description = read_model_description(str(path))
        self.slave = FMU2Slave(guid=description.guid, unzipDirectory=extract(str(path)),
                               modelIdentifier="WheelController", instanceName=label)
        self.slave.instantiate(loggingOn=False)
        self.slave.setupExperiment(startTime=0.0)
        self.slave.enterInitializationMode()
        self.slave.exitInitializationMode()
        refs = {v.name: v.valueReference for v in description.modelVariables}
        reals = [v.valueReference for v in description.modelVariables if v.type == "Real"][:20]
        assert len(reals) == 20
        self.component = self.slave.component
        f = self.slave._functions
        self.get, self.set, self.step = f["fmi2GetReal"], f["fmi2SetReal"], f["fmi2DoStep"]
        self.one = (fmi2ValueReference * 1)(refs["voltage"])
        self.twenty = (fmi2ValueReference * 20)(*reals)
        self.inputs = (fmi2ValueReference * 2)(refs["v_ref"], refs["v_meas"])
        self.out1 = (ctypes.c_double * 1)()
        self.out20 = (ctypes.c_double * 20)()
        self.in2 = (ctypes.c_double * 2)(0.3, 0.1)
        self.k = 0

    def operations(self):
        c, get, set_, step = self.component, self.get, self.set, self.step
        one, twenty, inputs, out1, out20, in2 = (self.one, self.twenty, self.inputs, self.out1,
                                                 self.out20, self.in2)

        def get_real_1(n):
            for _ in range(n):
                get(c, one, 1, out1)

        def get_real_20(n):
            for _ in range(n):
                get(c, twenty, 20, out20)

        def set_real_2(n):
            for _ in range(n):
                set_(c, inputs, 2, in2)

        def do_step(n):
            k = self.k
            for i in range(k, k + n):
                if step(c, i * 0.005, 0.005, 1) != 0:
                    raise RuntimeError("fmi2DoStep failed")
            self.k = k + n

        return {"getReal_1": get_real_1, "getReal_20": get_real_20, "setReal_2": set_real_2,
                "doStep": do_step}


def call_costs(paths, repeats, calls):
    """Per-call CPU time of each binary's WheelController ("ours" first) and the ratios of ours
    to each other, medians over interleaved batches."""
    labels = list(paths)
    raws = {label: Raw(paths[label]["WheelController"], label) for label in labels}
    ops = {label: raws[label].operations() for label in labels}
    for label in labels:  # all return the same numbers before anything is timed
        ops[label]["setReal_2"](1)
        ops[label]["doStep"](1)
        ops[label]["getReal_20"](1)
    assert all(list(raws[label].out20) == list(raws["ours"].out20) for label in labels), \
        "the builds disagree"
    result = {}
    for name in ops["ours"]:
        batch = calls if name != "doStep" else max(1, calls // 10)
        per_call = {label: [] for label in labels}
        ratios = {label: [] for label in labels if label != "ours"}
        for r in range(repeats):
            timings = {}
            for label in labels[r % len(labels):] + labels[:r % len(labels)]:
                started = time.thread_time()
                ops[label][name](batch)
                timings[label] = (time.thread_time() - started) / batch
            for label in labels:
                per_call[label].append(timings[label])
            for label in ratios:
                ratios[label].append(timings["ours"] / timings[label])
        row = {f"{label}_us": median(per_call[label]) * 1e6 for label in labels}
        row.update({f"ratio_to_{label}": median(ratios[label]) for label in ratios})
        row.update({"calls_per_batch": batch, "rounds": repeats,
                    "target_met": row["ratio_to_pythonfmu"] <= TARGET_RATIO})
        for label in ("reference", "before_portable", "portable"):
            if label in ratios:
                row[f"within_tolerance_of_{label}"] = \
                    abs(row[f"ratio_to_{label}"] - 1.0) <= REFERENCE_TOLERANCE
        result[name] = row
    return result


def ctypes_floor_us(calls):
    """Per-call time of a trivial C function through ctypes: what no binary can go below."""
    libc = ctypes.CDLL(None)
    function = libc.labs
    function.argtypes, function.restype = [ctypes.c_long], ctypes.c_long
    started = time.thread_time()
    for _ in range(calls):
        function(1)
    return (time.thread_time() - started) / calls * 1e6


def model_do_step_us(repeats, calls):
    """CPU time of WheelController's own ``do_step`` called in Python (no FMI), per call."""
    module = next(m for name, m in sys.modules.items()
                  if name.startswith("_sonotrack_wheelcontroller_") and name.endswith("._fmu_entry"))
    slave = module.WheelController(instance_name="direct", resources=None)
    slave.exit_initialization_mode()
    slave.v_ref, slave.v_meas = 0.3, 0.1
    times = []
    k = 0
    for _ in range(repeats):
        started = time.thread_time()
        for i in range(k, k + calls):
            slave.do_step(i * 0.005, 0.005)
        times.append((time.thread_time() - started) / calls)
        k += calls
    return median(times) * 1e6


_SCENARIO = textwrap.dedent('''
    import json, sys
    from orchestrator.run.runner import run_scenario
    import time
    started = time.process_time()
    result = run_scenario(sys.argv[1], sys.argv[2], progress=False, fmu_dir=sys.argv[3],
                          plots=False)
    print(json.dumps({"wall_time_s": result.summary["wall_time_s"],
                      "cpu_s": time.process_time() - started,
                      "steps": result.summary["steps"]}), flush=True)
''')


def scenario_times(paths, runs, out):
    """Stepping time of the default scenario with each binary, fresh process per run."""
    import shutil

    scenario = ROOT / "scenarios" / "s_curve.toml"
    dirs = {}
    for label in ("ours", "pythonfmu"):
        folder = Path(paths[label]["WheelController"]).parent
        shutil.copy(ROOT / "fmus" / "SystemStructure.ssd", folder / "SystemStructure.ssd")
        dirs[label] = folder
    times = {"ours": [], "pythonfmu": []}
    cpu = {"ours": [], "pythonfmu": []}
    ratios, cpu_ratios = [], []
    exits = {"ours": [], "pythonfmu": []}
    for r in range(runs):
        order = ("ours", "pythonfmu") if r % 2 == 0 else ("pythonfmu", "ours")
        pair = {}
        for label in order:
            completed = subprocess.run(
                [sys.executable, "-c", _SCENARIO, str(scenario), str(out / f"{label}_{r}"),
                 str(dirs[label])], capture_output=True, text=True, cwd=str(ROOT), timeout=1800)
            lines = [line for line in completed.stdout.splitlines() if line.startswith("{")]
            if not lines:
                raise RuntimeError(f"{label} run failed: {completed.stderr[-2000:]}")
            exits[label].append(completed.returncode)
            record = json.loads(lines[-1])
            pair[label] = record
            times[label].append(record["wall_time_s"])
            cpu[label].append(record["cpu_s"])
        ratios.append(pair["ours"]["wall_time_s"] / pair["pythonfmu"]["wall_time_s"])
        cpu_ratios.append(pair["ours"]["cpu_s"] / pair["pythonfmu"]["cpu_s"])
    return {"stepping_wall_ours_s": median(times["ours"]),
            "stepping_wall_pythonfmu_s": median(times["pythonfmu"]),
            "wall_ratio_median_of_pairs": median(ratios),
            "run_cpu_ours_s": median(cpu["ours"]), "run_cpu_pythonfmu_s": median(cpu["pythonfmu"]),
            "cpu_ratio_median_of_pairs": median(cpu_ratios), "runs": runs,
            "process_exit_status": exits}


def portable_glibc_floor(fmu_path, out):
    """The newest GLIBC version the ELF files a portable FMU carries need (by part)."""
    import zipfile

    sys.path.insert(0, str(ROOT))
    from tests.support.elf_versions import glibc_floor

    folder = Path(out) / "glibc_floor"
    with zipfile.ZipFile(fmu_path) as archive:
        archive.extractall(folder)
    lib = folder / "binaries" / "linux64" / "python" / "lib"
    parts = {"libpython": "libpython*", "numpy": "python3.*/site-packages/numpy*/**/*.so*",
             "lib_dynload": "python3.*/lib-dynload/*.so"}
    floors = {}
    for part, pattern in parts.items():
        floors[part] = ".".join(map(str, max(glibc_floor(p) for p in lib.glob(pattern))))
    floors["floor"] = max(floors.values(), key=lambda v: tuple(map(int, v.split("."))))
    return floors


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=21)
    parser.add_argument("--calls", type=int, default=5000)
    parser.add_argument("--scenario-runs", type=int, default=3)
    parser.add_argument("--instantiate-runs", type=int, default=11)
    args = parser.parse_args(argv)

    sys.path.insert(0, str(ROOT))
    from tests.support.fmu_checks import instantiate_free_cycles

    load_before = os.getloadavg()
    print(f"load average before: {load_before[0]:.2f} {load_before[1]:.2f} "
          f"{load_before[2]:.2f} ({os.cpu_count()} cores)")
    out = Path(tempfile.mkdtemp(prefix="sonotrack_fmi_cost_"))
    paths = build_both(NAMES, out)
    costs = call_costs({label: paths[label] for label in
                        ("ours", "pythonfmu", "reference", "before_portable", "portable")},
                       args.repeats, args.calls)
    floor = ctypes_floor_us(args.calls)
    model_us = model_do_step_us(args.repeats, max(1, args.calls // 10))
    step = costs["doStep"]
    step["model_do_step_us"] = model_us
    step["overhead_ours_us"] = step["ours_us"] - model_us
    step["overhead_pythonfmu_us"] = step["pythonfmu_us"] - model_us
    step["overhead_ratio"] = step["overhead_ours_us"] / step["overhead_pythonfmu_us"]
    for name, row in costs.items():
        print(f"{name:11s} ours {row['ours_us']:7.2f} us  pythonfmu {row['pythonfmu_us']:7.2f} us"
              f"  ratio {row['ratio_to_pythonfmu']:.3f}"
              f"  ({'met' if row['target_met'] else 'NOT met'}: <= {TARGET_RATIO});"
              f"  reference ({REFERENCE_COMMIT}) {row['reference_us']:7.2f} us  ratio "
              f"{row['ratio_to_reference']:.3f} ("
              f"{'met' if row['within_tolerance_of_reference'] else 'NOT met'}: within "
              f"+-{REFERENCE_TOLERANCE:.0%}); before portable ({BEFORE_PORTABLE_COMMIT}) "
              f"{row['before_portable_us']:7.2f} us ratio {row['ratio_to_before_portable']:.3f} "
              f"({'met' if row['within_tolerance_of_before_portable'] else 'NOT met'}); "
              f"portable FMU {row['portable_us']:7.2f} us ratio {row['ratio_to_portable']:.3f}")
    print(f"doStep: the model's own do_step {model_us:.2f} us; binary overhead ours "
          f"{step['overhead_ours_us']:.2f} us, pythonfmu {step['overhead_pythonfmu_us']:.2f} us, "
          f"ratio {step['overhead_ratio']:.3f}")
    print(f"ctypes floor (a trivial C call from Python): {floor:.2f} us")
    scenario = scenario_times(paths, args.scenario_runs, out)
    print(f"default scenario stepping (wall): ours {scenario['stepping_wall_ours_s']:.2f} s, "
          f"pythonfmu {scenario['stepping_wall_pythonfmu_s']:.2f} s, ratio "
          f"{scenario['wall_ratio_median_of_pairs']:.3f}; run CPU: ours "
          f"{scenario['run_cpu_ours_s']:.2f} s, pythonfmu {scenario['run_cpu_pythonfmu_s']:.2f} s, "
          f"ratio {scenario['cpu_ratio_median_of_pairs']:.3f}; exit statuses "
          f"{scenario['process_exit_status']}")
    cycles = instantiate_free_cycles(paths["ours"]["WheelController"], 500)
    print(f"500 instantiate/free cycles: RSS +{cycles['rss_growth_kib']} KiB, sys.path unchanged "
          f"{cycles['path_unchanged']}, modules added {cycles['modules_added']}")
    sizes = {"plain": fmu_sizes(paths["ours"]), "portable": fmu_sizes(paths["portable"])}
    for name in NAMES:
        plain, portable = sizes["plain"][name], sizes["portable"][name]
        print(f"{name}.fmu: plain {plain['fmu_bytes'] / 1e3:.1f} kB ({plain['unpacked_bytes'] / 1e3:.1f} "
              f"kB unpacked), portable {portable['fmu_bytes'] / 1e6:.2f} MB "
              f"({portable['unpacked_bytes'] / 1e6:.1f} MB unpacked)")
    glibc = portable_glibc_floor(paths["portable"]["WheelController"], out)
    print(f"portable runtime needs glibc {glibc['floor']} (libpython {glibc['libpython']}, "
          f"numpy {glibc['numpy']}, standard extension modules {glibc['lib_dynload']})")
    instantiate = c_host_instantiate_times(
        {"plain": paths["ours"], "portable": paths["portable"]}, args.instantiate_runs, out)
    for name in NAMES:
        plain, portable = instantiate["plain"][name], instantiate["portable"][name]
        print(f"C host fmi2Instantiate {name}: first plain {plain['first_ms']:.1f} ms, portable "
              f"{portable['first_ms']:.1f} ms (ratio {portable['first_ratio_to_plain']:.2f}); "
              f"later plain {plain['later_ms']:.2f} ms, portable {portable['later_ms']:.2f} ms")
    load_after = os.getloadavg()
    print(f"load average after: {load_after[0]:.2f} {load_after[1]:.2f} {load_after[2]:.2f}")
    path = write_result("fmi_call_cost", {
        "description": "FMI call cost through sonotrack's binary vs pythonfmu 0.7.0's on "
                       "WheelController, raw ctypes calls from one Python process, interleaved "
                       "batches; default scenario stepping time with each binary",
        "target_ratio": TARGET_RATIO,
        "reference_commit": REFERENCE_COMMIT,
        "reference_tolerance": REFERENCE_TOLERANCE,
        "before_portable_commit": BEFORE_PORTABLE_COMMIT,
        "load_average": {"before": load_before, "after": load_after, "cores": os.cpu_count()},
        "fmu_sizes": sizes,
        "portable_glibc_floor": glibc,
        "c_host_instantiate": instantiate,
        "calls": costs,
        "ctypes_floor_us": floor,
        "default_scenario": scenario,
        "instantiate_free_500": cycles,
        "command": "python benchmarks/fmi_call_cost.py " + " ".join(argv or sys.argv[1:]),
    })
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
