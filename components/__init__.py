"""Pure model cores of sonotrack and one thin pythonfmu slave per FMU.

Sub-packages: ``common`` (errors, state snapshots, the shared slave base), ``plant``,
``acoustics``, ``source``, ``planner`` and ``control``. Each sub-package uses only relative
imports (``from ..common import errors``), so that ``sonotrack build`` can copy it into an FMU
under a private package name and the FMU runs without this repository installed.
"""

__all__ = ["FMU_PACKAGES"]

# FMU model name -> sub-package whose fmu.py holds the slave class of that name (here, not in
# orchestrator.builder.fmus, so that checking a scenario does not import the FMU builder).
FMU_PACKAGES = {
    "RobotPlant": "plant",
    "SoundSource": "source",
    "AcousticLocalizer": "acoustics",
    "CurvaturePlanner": "planner",
    "WheelController": "control",
}
