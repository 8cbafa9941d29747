"""Session fixtures: the FMUs are built once per test run into a temporary folder."""

import pytest

from orchestrator.builder.fmus import FMU_PACKAGES, REPO_ROOT, build_all


@pytest.fixture(scope="session", autouse=True)
def fmu_cache(tmp_path_factory):
    """Unpack FMUs into a cache of this test session, not the user's ~/.cache/sonotrack
    (child processes inherit the variable)."""
    import os

    folder = tmp_path_factory.mktemp("fmu-cache")
    previous = os.environ.get("SONOTRACK_CACHE_DIR")
    os.environ["SONOTRACK_CACHE_DIR"] = str(folder)
    yield folder
    if previous is None:
        os.environ.pop("SONOTRACK_CACHE_DIR", None)
    else:
        os.environ["SONOTRACK_CACHE_DIR"] = previous


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    """Folder holding every FMU of the project, freshly built from this checkout."""
    out = tmp_path_factory.mktemp("fmus")
    build_all(out, names=list(FMU_PACKAGES))
    return out


@pytest.fixture(scope="session")
def fmu_paths(fmu_dir):
    """Model name -> built .fmu path."""
    return {name: fmu_dir / f"{name}.fmu" for name in FMU_PACKAGES}


@pytest.fixture(scope="session")
def repo_root():
    return REPO_ROOT


@pytest.fixture(scope="session", autouse=True)
def keep_fmu_binaries_loaded():
    """Stop fmpy from unloading FMU binaries inside the test process.

    ``fmpy.simulate_fmu`` frees each FMU's shared library when it is done; unloading a
    pythonfmu binary inside a Python host leaves the interpreter liable to crash later (seen
    as segfaults in unrelated tests). :class:`orchestrator.fmu.handle.FmuInstance` never unloads; this
    keeps direct ``simulate_fmu`` calls in tests equally safe.
    """
    from fmpy.fmi1 import _FMU

    original = _FMU.freeLibrary
    _FMU.freeLibrary = lambda self: None
    yield
    _FMU.freeLibrary = original


@pytest.fixture(scope="session")
def c_host(tmp_path_factory):
    """The minimal C host of tests/support/fmi_host.c, compiled with gcc once per session."""
    import shutil
    import subprocess

    from tests.support.fmi_binary import C_HOST_SOURCE, fmi_headers

    compiler = shutil.which("gcc")
    if compiler is None:
        pytest.skip("gcc is not installed: the C host cannot be compiled")
    binary = tmp_path_factory.mktemp("c_host") / "fmi_host"
    subprocess.run([compiler, "-std=c11", "-O1", "-Wall", "-Werror", f"-I{fmi_headers()}", "-o",
                    str(binary), str(C_HOST_SOURCE), "-ldl", "-pthread"], check=True)
    return binary
