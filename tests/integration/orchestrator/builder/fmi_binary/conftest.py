"""Fixtures of the FMI binary tests (this folder), built once per test session."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from orchestrator.builder.fmus import REPO_ROOT, build_fmu

from tests.support.fmi_binary import (C_HOST_SOURCE, LEAK_SUPPRESSIONS, NAMES, PROBE_RANGES, PROBE_SOURCE,
                                 fmi_headers)


@pytest.fixture(scope="session")
def extracted(fmu_paths, tmp_path_factory):
    """Model name -> (unzip folder, model description), each FMU extracted once."""
    import fmpy

    out = {}
    for name in NAMES:
        folder = tmp_path_factory.mktemp(f"x_{name}")
        fmpy.extract(str(fmu_paths[name]), str(folder))
        out[name] = (folder, fmpy.read_model_description(str(fmu_paths[name])))
    return out


@pytest.fixture(scope="session")
def probe(tmp_path_factory):
    """The probe FMU (fmi_binary_support.PROBE_SOURCE), built and extracted: (folder, description)."""
    import fmpy

    root = tmp_path_factory.mktemp("probe")
    components = root / "components"
    shutil.copytree(REPO_ROOT / "components" / "common", components / "common",
                    ignore=shutil.ignore_patterns("__pycache__"))
    (components / "probe").mkdir()
    (components / "probe" / "__init__.py").write_text("")
    (components / "probe" / "fmu.py").write_text(PROBE_SOURCE)
    (components / "probe" / "ranges.toml").write_text(PROBE_RANGES)
    path = build_fmu("Probe", root / "out", components_dir=components, packages={"Probe": "probe"})
    folder = root / "unzipped"
    fmpy.extract(str(path), str(folder))
    return folder, fmpy.read_model_description(str(path))


@pytest.fixture(scope="session")
def sanitized(tmp_path_factory):
    """The library and the C host built with -fsanitize=address,undefined (test only).

    Returns (host, library, LeakSanitizer suppressions file, runtime): ``runtime`` is what a
    host not built with the sanitizers (Python) must LD_PRELOAD to load the library. Skipped,
    saying why, where gcc cannot link the sanitizers.
    """
    compiler, make = shutil.which("gcc"), shutil.which("make")
    if compiler is None or make is None:
        pytest.skip("gcc or make is not installed: no sanitizer build")
    folder = tmp_path_factory.mktemp("sanitized")
    probe = folder / "probe.c"
    probe.write_text("int main(void) { return 0; }\n")
    trial = subprocess.run([compiler, "-fsanitize=address,undefined", "-o", str(folder / "probe"),
                            str(probe)], capture_output=True, text=True)
    if trial.returncode != 0:
        pytest.skip(f"gcc cannot link AddressSanitizer/UBSan here: {trial.stderr.strip()[-300:]}")
    library = folder / "sonotrack_fmi2_sanitized.so"
    # BIN: this Python's environment computes the source hash; -o: never reinstall the venv
    subprocess.run([make, "-s", "-o", ".venv/.installed", "fmi-binary-sanitized",
                    f"FMI_SANITIZED_OUT={library}", f"BIN={Path(sys.executable).parent}"],
                   cwd=REPO_ROOT, check=True, capture_output=True, text=True, timeout=600)
    host = folder / "fmi_host_sanitized"
    subprocess.run([compiler, "-std=c11", "-O1", "-g", "-fno-omit-frame-pointer",
                    "-fsanitize=address,undefined", "-Wall", "-Werror", f"-I{fmi_headers()}",
                    "-o", str(host), str(C_HOST_SOURCE), "-ldl", "-pthread"], check=True)
    suppressions = folder / "lsan_suppressions.txt"
    suppressions.write_text(LEAK_SUPPRESSIONS)
    runtime = " ".join(subprocess.run([compiler, f"-print-file-name={name}"], check=True,
                                      capture_output=True, text=True).stdout.strip()
                       for name in ("libasan.so", "libubsan.so"))
    return host, library, suppressions, runtime


@pytest.fixture(scope="session")
def thread_sanitized(tmp_path_factory):
    """The library and the C host built with -fsanitize=thread (test only): (host, folder holding
    the library and the lock library). Skipped, saying why, where gcc cannot link ThreadSanitizer."""
    from orchestrator.builder.fmi_binary import LOCK_LIBRARY, SOURCES

    compiler = shutil.which("gcc")
    if compiler is None:
        pytest.skip("gcc is not installed: no ThreadSanitizer build")
    folder = tmp_path_factory.mktemp("tsan")
    flags = ["-std=c11", "-O1", "-g", "-fsanitize=thread", f"-I{fmi_headers()}",
             '-DSONOTRACK_SOURCE_SHA256="tsan"']
    host = folder / "fmi_host_tsan"
    trial = subprocess.run([compiler, *flags, "-o", str(host), str(C_HOST_SOURCE), "-ldl",
                            "-pthread"], capture_output=True, text=True)
    if trial.returncode != 0:
        pytest.skip(f"gcc cannot link ThreadSanitizer here: {trial.stderr.strip()[-300:]}")
    lock = folder / LOCK_LIBRARY.name
    sources = [str(p) for p in SOURCES if p.suffix == ".c"]
    lock_source = [s for s in sources if s.endswith("process_lock.c")]
    subprocess.run([compiler, *flags, "-fPIC", "-shared", "-fvisibility=hidden",
                    f"-Wl,-soname,{lock.name}", "-o", str(lock), *lock_source, "-lpthread"],
                   check=True)
    subprocess.run([compiler, *flags, "-fPIC", "-shared", "-fvisibility=hidden", "-o",
                    str(folder / "sonotrack_fmi2_tsan.so"),
                    *[s for s in sources if s not in lock_source], f"-L{folder}",
                    f"-l:{lock.name}", "-Wl,-rpath,$ORIGIN", "-ldl", "-lpthread"], check=True)
    return host, folder
