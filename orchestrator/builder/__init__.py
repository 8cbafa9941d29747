"""The build side: FMUs from the slaves in ``components/``, their documentation, their checks.

- :mod:`~orchestrator.builder.fmus`: :func:`build_all` / :func:`build_fmu` (pythonfmu, then our
  binary and documentation) and the SSP archive;
- :mod:`~orchestrator.builder.fmi_binary`: sonotrack's own FMI 2.0 binary (C sources and the
  Python that installs the compiled library into an FMU);
- :mod:`~orchestrator.builder.system_fmu`: the whole-system FMU (``TrackingSystem.fmu``) from a
  system description;
- :mod:`~orchestrator.builder.documentation`: model metadata and ``documentation/index.html``;
- :mod:`~orchestrator.builder.validation`: fmpy's validator, fmu-manipulation-toolbox's checker
  and a short run of each built FMU.

Imports :mod:`orchestrator.files` (the atomic writer, to rewrite an FMU in place),
:mod:`orchestrator.report` (the HTML writer), :mod:`orchestrator.ssp` (the archive) and
:mod:`orchestrator.fmu` (unpacking, for validation).
"""

from .fmus import (FMU_PACKAGES, REPO_ROOT, build_all, build_fmu, entry_script,
                   private_package_name, write_ssp_archive)
from .validation import FmuReport, validate_fmu, validate_fmus

__all__ = ["FMU_PACKAGES", "REPO_ROOT", "FmuReport", "build_all", "build_fmu", "entry_script",
           "private_package_name", "validate_fmu", "validate_fmus", "write_ssp_archive"]
