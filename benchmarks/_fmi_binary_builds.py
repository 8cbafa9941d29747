"""Helpers of benchmarks/fmi_call_cost.py: the FMI binary as it was before issue 23, FMU sizes,
and the time of fmi2Instantiate in a C host.

The reference library is compiled from the C sources of REFERENCE_COMMIT (git show) with gcc
-O2, as ``make`` compiled it then: the library whose per-call cost today's must stay within
10 % of. It reads the same binding table; it imports ``pythonfmu`` from the host's Python (the
benchmark's venv has it), which the FMU's code no longer needs.
"""

import statistics
import subprocess
import sys
import zipfile
from pathlib import Path

__all__ = ["REFERENCE_COMMIT", "reference_library", "with_library", "fmu_sizes",
           "c_host_instantiate_times"]

ROOT = Path(__file__).resolve().parent.parent
REFERENCE_COMMIT = "fc83132"  # main before issue 23 (its fmi_binary sources as of e07e903 on)
_FOLDER = "orchestrator/builder/fmi_binary"


def _headers():
    import fmpy

    return Path(fmpy.__file__).parent / "c-code"


def reference_library(out):
    """Compile REFERENCE_COMMIT's FMI binary (gcc -O2) into ``out``; return its path."""
    names = subprocess.run(["git", "ls-tree", "--name-only", f"{REFERENCE_COMMIT}:{_FOLDER}"],
                           cwd=ROOT, check=True, capture_output=True, text=True).stdout.split()
    source = Path(out) / "reference_src"
    source.mkdir(parents=True, exist_ok=True)
    for name in [n for n in names if n.endswith((".c", ".h"))]:
        (source / name).write_bytes(subprocess.run(
            ["git", "show", f"{REFERENCE_COMMIT}:{_FOLDER}/{name}"], cwd=ROOT, check=True,
            capture_output=True).stdout)
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


def c_host_instantiate_times(paths, runs, work):
    """Median wall time of the first fmi2Instantiate in a fresh C host process (the library
    starts Python and loads the model's code) and of a later one (everything loaded), per FMU,
    ``runs`` fresh processes each."""
    import fmpy

    sys.path.insert(0, str(ROOT))
    from tests.support.fmi_binary import C_HOST_SOURCE, host_env, plan

    work = Path(work)
    host = work / "fmi_host"
    subprocess.run(["gcc", "-std=c11", "-O1", f"-I{_headers()}", "-o", str(host),
                    str(C_HOST_SOURCE), "-ldl", "-pthread"], check=True)
    times = {}
    for name, path in paths.items():
        folder = work / f"x_{name}"
        fmpy.extract(str(path), str(folder))
        description = fmpy.read_model_description(str(folder))
        text, _ = plan(None, [(name, folder, description, "timed")], 1)
        first, later = [], []
        for _ in range(runs):
            completed = subprocess.run([str(host), "--timing"], input=text, capture_output=True,
                                       text=True, env=host_env(), cwd="/", timeout=300)
            if completed.returncode != 0:
                raise RuntimeError(f"{name}: C host failed: {completed.stderr[-2000:]}")
            line = next(x for x in completed.stderr.splitlines() if x.startswith("timing "))
            fields = line.split()
            first.append(float(fields[3]))
            later.append(float(fields[5]))
        times[name] = {"first_ms": statistics.median(first) * 1e3,
                       "later_ms": statistics.median(later) * 1e3, "runs": runs}
    return times
