"""Fixtures of the FMI binary tests (test_fmi_binary_*.py), built once per test session."""

import shutil
import subprocess

import pytest

from orchestrator.build import REPO_ROOT, build_fmu

from .fmi_binary_support import C_HOST_SOURCE, NAMES, PROBE_RANGES, PROBE_SOURCE, fmi_headers


@pytest.fixture(scope="session")
def c_host(tmp_path_factory):
    """The minimal C host (fmi_host.c) compiled with gcc."""
    compiler = shutil.which("gcc")
    if compiler is None:
        pytest.skip("gcc is not installed: the C host cannot be compiled")
    binary = tmp_path_factory.mktemp("c_host") / "fmi_host"
    subprocess.run([compiler, "-std=c11", "-O1", "-Wall", "-Werror", f"-I{fmi_headers()}", "-o",
                    str(binary), str(C_HOST_SOURCE), "-ldl"], check=True)
    return binary


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
