"""Pure model cores of sonotrack and one thin pythonfmu slave per FMU.

Sub-packages: ``common`` (errors, state snapshots, the shared slave base), ``plant``,
``acoustics``, ``source``, ``planner`` and ``control``. Each sub-package uses only relative
imports (``from ..common import errors``), so that ``sonotrack build`` can copy it into an FMU
under a private package name and the FMU runs without this repository installed.
"""
