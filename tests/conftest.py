"""Session fixtures: the FMUs are built once per test run into a temporary folder."""

import pytest

from orchestrator.build import FMU_PACKAGES, REPO_ROOT, build_all


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
