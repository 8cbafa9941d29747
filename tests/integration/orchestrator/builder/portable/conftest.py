"""Fixtures of the portable-FMU tests (this folder): the five FMUs built with ``--portable``
into a temporary folder once per test session, and extracted."""

import pytest

from components.common.errors import BuildError

from orchestrator.builder.fmus import FMU_PACKAGES, build_all


@pytest.fixture(scope="session")
def portable_paths(tmp_path_factory):
    """Model name -> portable .fmu path, freshly built from this checkout."""
    from orchestrator.builder.portable.runtime import libpython

    try:
        libpython()
    except BuildError as exc:  # the one thing a portable build needs beyond the venv
        pytest.skip(str(exc))
    out = tmp_path_factory.mktemp("portable_fmus")
    build_all(out, names=list(FMU_PACKAGES), portable=True)
    return {name: out / f"{name}.fmu" for name in FMU_PACKAGES}


@pytest.fixture(scope="session")
def portable_extracted(portable_paths, tmp_path_factory):
    """Model name -> (unzip folder, model description) of each portable FMU."""
    import fmpy

    out = {}
    for name, path in portable_paths.items():
        folder = tmp_path_factory.mktemp(f"p_{name}")
        fmpy.extract(str(path), str(folder))
        out[name] = (folder, fmpy.read_model_description(str(path)))
    return out
