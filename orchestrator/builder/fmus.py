"""Build the sonotrack FMUs from the thin pythonfmu slaves in ``components/``.

Each FMU is built by pythonfmu 0.7.0 from an entry script and a private copy of the cores it
needs (``components/common`` plus the slave's sub-package) under a package name unique to that
FMU and to its code (``_sonotrack_<name>_<tag>``, the tag a hash of the bundled sources). A
private name matters: the FMUs share one Python interpreter in the host, so two FMUs (or two
builds of one FMU) bundling a package of the same name would see only the first one imported. The entry script is the slave module ``components/<part>/fmu.py`` itself,
its relative imports rewritten to the private package: pythonfmu 0.7.0's binary must find the
slave class *defined* in the entry module (a class merely imported there instantiates once and
then corrupts the interpreter on the second instance, as seen with two WheelControllers). The model description comes out compliant because every slave
derives from :class:`components.common.slave.SonotrackSlave`; :func:`build_fmu` checks that.
Then the linux64 binary is replaced by sonotrack's own (:mod:`orchestrator.builder.fmi_binary`), and
finally :mod:`orchestrator.builder.documentation` adds the metadata and ``documentation/index.html``.
"""

import datetime
import hashlib
import importlib
import os
import re
import shutil
import sys
import tempfile
import uuid
import zipfile
from pathlib import Path
from xml.etree import ElementTree

from components import FMU_PACKAGES
from components.common.errors import BuildError
from orchestrator.builder.fmi_binary import build_tag, edit_archive, install_binary
from orchestrator.builder.documentation import document_fmu

__all__ = [
    "FMU_PACKAGES", "REPO_ROOT", "build_fmu", "build_all", "carried_package", "entry_script",
    "private_package_name", "pin_identity", "write_ssp_archive",
]

REPO_ROOT = Path(__file__).resolve().parents[2]
COMPONENTS = REPO_ROOT / "components"


_STATE_OPTIONS = {"canGetAndSetFMUstate": True, "canSerializeFMUstate": True}
_IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "fmu_*.py.bak")


def private_package_name(name, tag):
    """Return the package name under which the FMU ``name`` carries its cores.

    ``tag`` identifies the build's code (:func:`orchestrator.builder.fmi_binary.build_tag`): two builds
    of one model with different code never share a module in a host's ``sys.modules``.
    """
    return f"_sonotrack_{name.lower()}_{tag}"


def build_fmu(name, dest_dir, components_dir=COMPONENTS, packages=None, bundle=(),
              resources=(), notes_file=None, portable=False):
    """Build one FMU and return the path of the ``.fmu`` file.

    Parameters
    ----------
    name : str
        Model name, a key of ``packages`` (default :data:`FMU_PACKAGES`).
    dest_dir : path-like
        Folder the FMU is written to (created if missing).
    components_dir : path-like, optional
        The ``components`` package to take the slave and cores from.
    packages : dict, optional
        Model name to sub-package mapping; defaults to :data:`FMU_PACKAGES`.
    bundle : iterable of str, optional
        Further sub-packages of ``components_dir`` the FMU carries (the whole-system FMU
        carries every part it runs).
    resources : iterable of path-like, optional
        Files put into the FMU's ``resources/`` folder (and beside the entry script while
        pythonfmu builds, where the slave finds them as its ``resources``).
    notes_file : path-like, optional
        The notes of ``documentation/index.html``; default ``docs/<sub-package>.md``.
    portable : bool, optional
        Carry a Python runtime (:mod:`orchestrator.builder.portable`): the FMU runs where no
        Python is installed.

    Returns
    -------
    pathlib.Path
        ``dest_dir / f"{name}.fmu"``.
    """
    from pythonfmu.builder import FmuBuilder

    packages = FMU_PACKAGES if packages is None else packages
    if name not in packages:
        raise BuildError(f"unknown FMU {name!r}; valid choices: {', '.join(sorted(packages))}")
    components_dir = Path(components_dir)
    subpackage = packages[name]
    slave_file = components_dir / subpackage / "fmu.py"
    if not slave_file.is_file():
        raise BuildError(f"FMU {name}: slave module {slave_file} does not exist")
    dest_dir = Path(dest_dir)
    dest_dir.mkdir(parents=True, exist_ok=True)
    parts = list(dict.fromkeys([subpackage, *bundle]))
    resources = [Path(r) for r in resources]
    private = carried_package(name, components_dir, parts, resources)
    with tempfile.TemporaryDirectory(prefix="sonotrack_build_") as stage:
        stage = Path(stage)
        package_dir = stage / private
        package_dir.mkdir()
        (package_dir / "__init__.py").write_text(
            f'"""Private copy of the sonotrack cores bundled in the {name} FMU."""\n')
        shutil.copytree(components_dir / "common", package_dir / "common", ignore=_IGNORE)
        for part in parts:
            shutil.copytree(components_dir / part, package_dir / part, ignore=_IGNORE)
        for resource in resources:
            shutil.copy2(resource, stage / resource.name)
        script = stage / f"{name}.py"
        script.write_text(entry_script(slave_file.read_text(), private, subpackage))
        saved_path = list(sys.path)
        # before and after: pythonfmu imports the entry script by the model's name, and a
        # module of that name left by an earlier build or a loaded FMU would be used instead
        _forget_modules(name, private)
        try:
            fmu_path = FmuBuilder.build_FMU(script, dest=dest_dir / f"{name}.fmu",
                                            project_files=[package_dir] + [
                                                stage / r.name for r in resources],
                                            **_STATE_OPTIONS)
        except Exception as exc:  # pythonfmu raises bare exceptions; name the FMU
            raise BuildError(f"FMU {name}: pythonfmu build failed: {exc!r}") from exc
        finally:
            sys.path[:] = saved_path
            _forget_modules(name, private)
    _check_built(Path(fmu_path), name)
    pin_identity(fmu_path, name, private)
    install_binary(fmu_path, private, name, name)
    if portable:
        from orchestrator.builder.portable import make_portable

        make_portable(fmu_path)
    # last: metadata and documentation/index.html from the final modelDescription.xml
    document_fmu(fmu_path, slave_file,
                 notes_file or components_dir.parent / "docs" / f"{subpackage}.md")
    return Path(fmu_path)


# Names the GUIDs of sonotrack's FMUs (uuid5 of this namespace and what the FMU carries).
GUID_NAMESPACE = uuid.UUID("5f0c1d0e-7a4b-5c3e-9d2f-50a07c0a0001")


def pin_identity(fmu_path, name, private):
    """Make a build reproducible: the same code gives the same FMU, byte for byte.

    pythonfmu writes a time-based GUID (uuid1) and the build time into modelDescription.xml.
    The GUID becomes a name-based one (uuid5) of the model, its private package (whose tag
    hashes every source it carries) and the model description itself, so it changes exactly
    when the FMU's code or interface does; ``generationDateAndTime`` is the time of
    ``SOURCE_DATE_EPOCH`` if that is set (the reproducible-builds convention) and left out
    otherwise (the attribute is optional in FMI 2.0). With :func:`edit_archive`'s fixed entry
    dates and order, a rebuild from unchanged code leaves every stored run's key (the FMUs'
    SHA-256) unchanged, so a sweep or study resumes instead of computing every run again.
    """
    def edit(files):
        text = files["modelDescription.xml"].decode("utf-8")
        text = re.sub(r'\s+generationDateAndTime="[^"]*"', "", text, count=1)
        blank = re.sub(r'guid="[^"]*"', 'guid=""', text, count=1)
        digest = hashlib.sha256(blank.encode("utf-8")).hexdigest()
        guid = uuid.uuid5(GUID_NAMESPACE, f"{name}/{private}/{digest}")
        text = re.sub(r'guid="[^"]*"', f'guid="{guid}"', text, count=1)
        epoch = os.environ.get("SOURCE_DATE_EPOCH", "").strip()
        if epoch:
            try:
                when = datetime.datetime.fromtimestamp(int(epoch), datetime.timezone.utc)
            except (ValueError, OverflowError, OSError):
                raise BuildError(f"SOURCE_DATE_EPOCH = {epoch!r}: must be whole seconds since "
                                 "1970-01-01 UTC") from None
            text = text.replace(f'guid="{guid}"', f'guid="{guid}" generationDateAndTime='
                                f'"{when.strftime("%Y-%m-%dT%H:%M:%SZ")}"', 1)
        files["modelDescription.xml"] = text.encode("utf-8")

    edit_archive(fmu_path, edit)


def _forget_modules(name, private):
    """Drop the entry module ``name`` and the private package from ``sys.modules``."""
    for module in [m for m in sys.modules if m == name or m == private
                   or m.startswith(private + ".")]:
        del sys.modules[module]
    importlib.invalidate_caches()


def carried_package(name, components_dir, parts, resources=()):
    """The private package name of FMU ``name`` built now from ``components_dir``.

    ``parts`` are the sub-packages it carries beside ``common`` (its own first), ``resources``
    the files it carries in ``resources/``. An FMU built earlier from other code carries
    another name (:func:`private_package_name` of another tag).
    """
    components_dir = Path(components_dir)
    return private_package_name(
        name, build_tag(name, [components_dir / "common"]
                        + [components_dir / part for part in parts] + [Path(r) for r in resources]))


def entry_script(slave_source, private, subpackage):
    """Return the slave module's source with its relative imports made absolute.

    ``from ..common.x import y`` becomes ``from <private>.common.x import y`` and
    ``from .x import y`` becomes ``from <private>.<subpackage>.x import y``.
    """
    source = re.sub(r"^(\s*)from \.\.(\w)", rf"\1from {private}.\2", slave_source, flags=re.M)
    source = re.sub(r"^(\s*)from \.(\w)", rf"\1from {private}.{subpackage}.\2", source, flags=re.M)
    source = re.sub(r"^(\s*)from \. import", rf"\1from {private}.{subpackage} import", source,
                    flags=re.M)
    if re.search(r"^\s*from \.", source, flags=re.M):
        raise BuildError(f"slave of {subpackage}: unsupported relative import in fmu.py")
    return source


def build_all(dest_dir, names=None, components_dir=COMPONENTS, portable=False):
    """Build several FMUs (default: every FMU whose slave exists) and return their paths
    (``portable``: each carries a Python runtime, see :func:`build_fmu`)."""
    if names is None:
        names = [n for n, pkg in FMU_PACKAGES.items()
                 if (Path(components_dir) / pkg / "fmu.py").is_file()]
    return [build_fmu(name, dest_dir, components_dir, portable=portable) for name in names]


def _check_built(fmu_path, name):
    """Fail the build if the written model description lacks what our base class adds."""
    with zipfile.ZipFile(fmu_path) as archive:
        root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    problems = []
    if root.find("UnitDefinitions") is None:
        problems.append("no <UnitDefinitions>")
    if root.find("ModelStructure/InitialUnknowns") is None and \
            root.find("ModelStructure/Outputs") is not None:
        problems.append("no <InitialUnknowns>")
    for variable in root.find("ModelVariables"):
        if variable.find("Real") is not None and variable.find("Real").get("unit") is None:
            problems.append(f"Real variable {variable.get('name')} has no unit")
        if not variable.get("description"):
            problems.append(f"variable {variable.get('name')} has no description")
    if problems:
        raise BuildError(f"FMU {name}: slave is not a SonotrackSlave or declares ports "
                         f"incompletely: {'; '.join(problems)}")


def write_ssp_archive(ssd_path, archive_path, fmu_dir=None):
    """Zip a ``.ssd`` and the FMUs it names into an ``.ssp`` archive for other tools.

    The archive holds ``SystemStructure.ssd`` with sources rewritten to ``resources/<fmu>``
    and each FMU once under ``resources/``.
    """
    from orchestrator.ssp import read_ssd, ssd_to_string

    description = read_ssd(ssd_path)
    fmu_dir = Path(fmu_dir) if fmu_dir is not None else Path(ssd_path).parent
    sources = sorted({c.source for c in description.components})
    missing = [s for s in sources if not (fmu_dir / s).is_file()]
    if missing:
        raise BuildError(f"{archive_path}: FMUs missing from {fmu_dir}: {', '.join(missing)}")
    text = ssd_to_string(description.with_source_prefix("resources/"))
    with zipfile.ZipFile(archive_path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("SystemStructure.ssd", text)
        for source in sources:
            archive.write(fmu_dir / source, f"resources/{source}")
    return Path(archive_path)
