"""Helpers of benchmarks/fmi_call_cost.py: the FMI binary as it was before issue 23 and before
portable FMUs, FMU sizes, and the time of fmi2Instantiate in a C host.

The reference library is compiled from the C sources of REFERENCE_COMMIT (git show) with gcc
-O2, as ``make`` compiled it then: the library whose per-call cost today's must stay within
10 % of. It reads the same binding table; it imports ``pythonfmu`` from the host's Python (the
benchmark's venv has it), which the FMU's code no longer needs. The library before portable FMUs
(BEFORE_PORTABLE_COMMIT) is compiled as ``make`` compiles today's (zig, glibc 2.17).
"""

import statistics
import subprocess
import sys
import zipfile
from pathlib import Path

__all__ = ["REFERENCE_COMMIT", "BEFORE_PORTABLE_COMMIT", "reference_library",
           "before_portable_library", "with_library", "fmu_sizes", "c_host_instantiate_times"]

ROOT = Path(__file__).resolve().parent.parent
REFERENCE_COMMIT = "fc83132"  # main before issue 23 (its fmi_binary sources as of e07e903 on)
BEFORE_PORTABLE_COMMIT = "121d66b"  # issue 23 items 1-5: the library before portable FMUs
_FOLDER = "orchestrator/builder/fmi_binary"


def _headers():
    import fmpy

    return Path(fmpy.__file__).parent / "c-code"


def _sources_at(commit, folder):
    """The FMI binary's C sources and headers as of ``commit``, written into ``folder``."""
    names = subprocess.run(["git", "ls-tree", "--name-only", f"{commit}:{_FOLDER}"],
                           cwd=ROOT, check=True, capture_output=True, text=True).stdout.split()
    folder.mkdir(parents=True, exist_ok=True)
    for name in [n for n in names if n.endswith((".c", ".h"))]:
        (folder / name).write_bytes(subprocess.run(
            ["git", "show", f"{commit}:{_FOLDER}/{name}"], cwd=ROOT, check=True,
            capture_output=True).stdout)
    return folder


def before_portable_library(out):
    """Compile BEFORE_PORTABLE_COMMIT's library as ``make`` compiles today's (zig for glibc
    2.17, -O2) into ``out``; it needs the lock library of the FMU it is put into (one frozen
    interface, process_lock.c). Return its path."""
    from orchestrator.builder.fmi_binary import LOCK_LIBRARY

    source = _sources_at(BEFORE_PORTABLE_COMMIT, Path(out) / "before_portable_src")
    library = Path(out) / "before_portable.so"
    subprocess.run([str(Path(sys.executable).parent / "python-zig"), "cc", "-target",
                    "x86_64-linux-gnu.2.17", "-g0", "-std=c11", "-fPIC", "-shared",
                    "-fvisibility=hidden", "-O2", '-DSONOTRACK_SOURCE_SHA256="before"',
                    f"-I{_headers()}", "-o", str(library),
                    *sorted(str(p) for p in source.glob("*.c") if p.name != "process_lock.c"),
                    f"-L{LOCK_LIBRARY.parent}", f"-l:{LOCK_LIBRARY.name}", "-Wl,-rpath,$ORIGIN",
                    "-ldl", "-lpthread"], check=True)
    return library


def reference_library(out):
    """Compile REFERENCE_COMMIT's FMI binary (gcc -O2) into ``out``; return its path."""
    source = _sources_at(REFERENCE_COMMIT, Path(out) / "reference_src")
    library = Path(out) / "reference.so"
    subprocess.run(["gcc", "-std=c11", "-fPIC", "-shared", "-fvisibility=hidden", "-O2",
                    '-DSONOTRACK_SOURCE_SHA256="reference"', f"-I{_headers()}", "-o",
                    str(library), *sorted(str(p) for p in source.glob("*.c")), "-ldl",
                    "-lpthread"], check=True)
    return library


def with_library(fmu_path, library, out_path):
    """A copy of an FMU whose linux64 model binary is ``library``."""
    out_path = Path(out_path)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(fmu_path) as source, \
            zipfile.ZipFile(out_path, "w", zipfile.ZIP_DEFLATED) as target:
        identifier = Path(out_path).stem
        for info in source.infolist():
            data = source.read(info)
            if info.filename == f"binaries/linux64/{identifier}.so":
                data = Path(library).read_bytes()
            target.writestr(info, data)
    return out_path


def fmu_sizes(paths):
    """Size in bytes of each .fmu and of what it unpacks to."""
    sizes = {}
    for name, path in paths.items():
        with zipfile.ZipFile(path) as archive:
            unpacked = sum(info.file_size for info in archive.infolist())
        sizes[name] = {"fmu_bytes": Path(path).stat().st_size, "unpacked_bytes": unpacked}
    return sizes


def c_host_instantiate_times(builds, runs, work):
    """Median wall time of the first fmi2Instantiate in a fresh C host process (the library
    starts Python and loads the model's code) and of a later one (everything loaded), per build
    label (``builds``: label -> {model name: .fmu path}) and FMU, ``runs`` fresh processes each;
    for each run and FMU the builds run one after the other (their order alternating), and the
    ratio of each build's first instantiation to the first label's is the median of those
    pairs. No Python is named to the host: a plain FMU finds the build's, a portable one its own.
    """
    import fmpy

    sys.path.insert(0, str(ROOT))
    from tests.support.fmi_binary import C_HOST_SOURCE, host_env, plan

    work = Path(work)
    host = work / "fmi_host"
    subprocess.run(["gcc", "-std=c11", "-O1", f"-I{_headers()}", "-o", str(host),
                    str(C_HOST_SOURCE), "-ldl", "-pthread"], check=True)
    labels = list(builds)
    plans = {}
    for label, paths in builds.items():
        for name, path in paths.items():
            folder = work / f"x_{label}_{name}"
            fmpy.extract(str(path), str(folder))
            description = fmpy.read_model_description(str(folder))
            plans[label, name] = plan(None, [(name, folder, description, "timed")], 1)[0]
    first = {key: [] for key in plans}
    later = {key: [] for key in plans}
    ratios = {key: [] for key in plans}
    names = list(builds[labels[0]])
    for r in range(runs):
        for name in names:
            pair = {}
            for label in labels[r % len(labels):] + labels[:r % len(labels)]:
                completed = subprocess.run([str(host), "--timing"], input=plans[label, name],
                                           capture_output=True, text=True, env=host_env(),
                                           cwd="/", timeout=300)
                if completed.returncode != 0:
                    raise RuntimeError(f"{label} {name}: C host failed: "
                                       f"{completed.stderr[-2000:]}")
                line = next(x for x in completed.stderr.splitlines() if x.startswith("timing "))
                fields = line.split()
                pair[label] = float(fields[3])
                first[label, name].append(float(fields[3]))
                later[label, name].append(float(fields[5]))
            for label in labels:
                ratios[label, name].append(pair[label] / pair[labels[0]])
    return {label: {name: {"first_ms": statistics.median(first[label, name]) * 1e3,
                           "later_ms": statistics.median(later[label, name]) * 1e3,
                           f"first_ratio_to_{labels[0]}": statistics.median(ratios[label, name]),
                           "runs": runs}
                    for name in names} for label in labels}
