"""Build the whole-system FMU (``TrackingSystem.fmu``) from a system description.

The FMU is built like the five others, by :func:`orchestrator.builder.fmus.build_fmu`, from
the slave ``components/system/fmu.py``; it carries ``components/common``, the system package
(the master) and every sub-package its instances' slaves live in: the very code the five FMUs
carry, under one private package name, so their defaults and its defaults cannot differ. The
description (:class:`components.system.SystemDescription`: instances, connections, schedule,
parameter values) goes into ``resources/sonotrack_system.json``; making it from a scenario is
the run layer's business (``orchestrator/run/as_fmu.py``), since the builder sits below it.
"""

import tempfile
import zipfile
from pathlib import Path

from components.common.errors import BuildError
from components.system import DESCRIPTION_FILE, SYSTEM_MODEL
from orchestrator.builder.fmi_binary import BINDING_FILE
from orchestrator.builder.fmus import COMPONENTS, REPO_ROOT, build_fmu, carried_package

__all__ = ["SYSTEM_MODEL", "SYSTEM_NOTES", "build_system_fmu", "code_mismatches"]

SYSTEM_NOTES = REPO_ROOT / "docs" / "system_fmu.md"
_SYSTEM_PACKAGE = "system"


def build_system_fmu(description, dest_dir, components_dir=COMPONENTS, portable=False):
    """Build ``TrackingSystem.fmu`` running ``description`` and return its path.

    Parameters
    ----------
    description : components.system.SystemDescription
        What the FMU runs.
    dest_dir : path-like
        Folder the FMU is written to (created if missing).
    components_dir : path-like, optional
        The ``components`` package to take the slaves and cores from.
    portable : bool, optional
        Carry a Python runtime (:func:`orchestrator.builder.fmus.build_fmu`).

    Returns
    -------
    pathlib.Path
        ``dest_dir / "TrackingSystem.fmu"``.

    Raises
    ------
    BuildError
        If a sub-package the description names is not in ``components_dir``.
    """
    components_dir = Path(components_dir)
    missing = [p for p in description.packages if not (components_dir / p / "fmu.py").is_file()]
    if missing:
        raise BuildError(f"FMU {SYSTEM_MODEL}: no slave module for the parts "
                         f"{', '.join(missing)} in {components_dir}")
    with tempfile.TemporaryDirectory(prefix="sonotrack_system_") as folder:
        carried = Path(folder) / DESCRIPTION_FILE
        carried.write_text(description.to_json(), encoding="utf-8")
        return build_fmu(SYSTEM_MODEL, dest_dir, components_dir,
                         packages={SYSTEM_MODEL: _SYSTEM_PACKAGE}, bundle=description.packages,
                         resources=[carried], notes_file=SYSTEM_NOTES, portable=portable)


def code_mismatches(fmus, components_dir=COMPONENTS):
    """Which FMUs carry other code than ``components_dir`` holds now, one line each.

    The system FMU runs the code of ``components_dir``; ``sonotrack run`` runs what the five
    FMUs carry. Built from other code (an older checkout, another engineer's defaults), they
    would disagree, so the system FMU is built only beside FMUs of the same code.

    Parameters
    ----------
    fmus : dict of str to (str, path-like)
        Model name -> (sub-package of ``components``, ``.fmu`` file).
    components_dir : path-like, optional

    Returns
    -------
    list of str
        Empty when every FMU carries the code ``components_dir`` holds.
    """
    problems = []
    for model, (package, path) in sorted(fmus.items()):
        expected = carried_package(model, components_dir, [package])
        try:
            with zipfile.ZipFile(path) as archive:
                table = archive.read(BINDING_FILE).decode("utf-8", "replace")
        except (OSError, KeyError, zipfile.BadZipFile):
            table = ""
        carried = next((line.split("\t", 1)[1] for line in table.splitlines()
                        if line.startswith("package\t")), None)
        if carried != expected:
            problems.append(f"{path}: carries the code {carried or '(no sonotrack binding)'}, "
                            f"not that of {components_dir} now ({expected})")
    return problems


def stale_fmus(folder, components_dir=COMPONENTS):
    """The FMUs in ``folder`` that sonotrack built from other code than ``components_dir``
    holds now, one line each (empty when none is).

    Whatever runs FMUs (``run``, ``sweep``, ``reproduce``) gets the answers of the code they
    carry: FMUs left from an older checkout, not rebuilt after a change, give that code's
    results under today's name. Only ``<Model>.fmu`` files of our five models with a sonotrack
    binding are judged (another tool's FMU in the system is not ours to date).
    """
    from components import FMU_PACKAGES

    present = {model: (package, Path(folder) / f"{model}.fmu")
               for model, package in FMU_PACKAGES.items()
               if (Path(folder) / f"{model}.fmu").is_file()}
    return [line for line in code_mismatches(present, components_dir)
            if "(no sonotrack binding)" not in line]


def stale_fmus_warning(command, folder, components_dir=COMPONENTS):
    """One warning line for :func:`stale_fmus` of ``folder``, or None."""
    stale = stale_fmus(folder, components_dir)
    if not stale:
        return None
    names = ", ".join(line.split(": carries", 1)[0] for line in stale)
    return (f"sonotrack {command}: warning: {names} carry other code than {components_dir} "
            "holds now: the results will be those of the code they carry; rebuild them with "
            "`make fmus` (or `sonotrack build`)")
