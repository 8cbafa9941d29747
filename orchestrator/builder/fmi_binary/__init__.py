"""sonotrack's own FMI 2.0 binary (linux64) and how ``sonotrack build`` puts it into an FMU.

pythonfmu builds the FMU (model description, resources with the slave's Python code); then
:func:`install_binary` replaces pythonfmu's ``binaries/linux64/<model>.so`` with the library
compiled by ``make`` from the C sources in this folder (:data:`SOURCES`: ``*.c`` and the private
header ``sonotrack_fmi2.h``) and writes ``resources/sonotrack_binding.txt``,
the table that library reads at ``fmi2Instantiate``: the GUID, where the slave's code lives, the
libpython and Python executable of the build (used only by hosts that run no Python) and every
variable's value reference, type, causality, variability and initial. The win64 binary stays
pythonfmu's. docs/fmi_binary.md describes the binary's contract.
"""

import hashlib
import re
import sys
import sysconfig
import zipfile
from pathlib import Path
from xml.etree import ElementTree

from components.common.errors import BuildError
from orchestrator.files.atomic import atomic_open

__all__ = ["LIBRARY", "SOURCES", "BINDING_FILE", "build_tag", "source_hash", "library_source_hash",
           "install_binary", "binding_table", "pythonfmu_binary", "restore_pythonfmu_binary"]

HERE = Path(__file__).resolve().parent
LIBRARY = HERE / "linux64" / "sonotrack_fmi2.so"
BINDING_FILE = "resources/sonotrack_binding.txt"
# What the library is compiled from: every C source and header in this folder (the Makefile
# compiles the same glob and embeds source_hash() of it in the library).
SOURCES = tuple(sorted(HERE.glob("*.c")) + sorted(HERE.glob("*.h")))
# How the library names its sources (the string is in the binary: see instance.c).
_SOURCE_ID = re.compile(rb"sonotrack-fmi2-sources sha256 ([0-9a-f]{64})\0")

_IGNORED_PARTS = {"__pycache__"}


def build_tag(name, sources):
    """Return 12 hex digits that identify the code an FMU carries.

    The private package of the FMU is named after this tag, so two builds of one model whose
    code differs in any byte load under different module names in one process, and two builds
    of identical code may share them.

    Parameters
    ----------
    name : str
        The model name.
    sources : iterable of path-like
        Files and folders whose content goes into the FMU (folders are walked; ``__pycache__``
        and ``*.pyc`` are skipped).
    """
    digest = hashlib.sha256(name.encode())
    for source in sources:
        source = Path(source)
        files = sorted(p for p in source.rglob("*") if p.is_file()) if source.is_dir() else [source]
        for path in files:
            relative = path.relative_to(source.parent)
            if _IGNORED_PARTS & set(relative.parts) or path.suffix == ".pyc":
                continue
            digest.update(str(relative).encode() + b"\0")
            digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:12]


def source_hash(folder=HERE):
    """Return the sha256 (hex) of the FMI binary's C sources: every ``*.c`` and ``*.h`` in ``folder``.

    ``make`` compiles it into the library, and :func:`install_binary` refuses a library whose
    embedded hash differs from the sources' (a stale build would put old C code into new FMUs).
    Each file's name and bytes count, so editing, adding, removing or renaming any source
    changes it.
    """
    folder = Path(folder)
    digest = hashlib.sha256()
    for path in sorted(folder.glob("*.c")) + sorted(folder.glob("*.h")):
        digest.update(path.name.encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()


def library_source_hash(library=LIBRARY):
    """Return the source hash compiled into a library, or None if it carries none."""
    found = _SOURCE_ID.search(Path(library).read_bytes())
    return found.group(1).decode() if found else None


def _python_facts():
    """libpython, the Python executable (its venv gives numpy) and the version of this build."""
    library = Path(sysconfig.get_config_var("LIBDIR") or "",
                   sysconfig.get_config_var("INSTSONAME") or "")
    if not sysconfig.get_config_var("Py_ENABLE_SHARED") or not library.is_file():
        library = Path("")  # a static Python: C hosts must set SONOTRACK_LIBPYTHON
    return str(library), sys.executable, f"{sys.version_info.major}.{sys.version_info.minor}"


def binding_table(description_xml, package, entry, class_name):
    """Return the text of ``resources/sonotrack_binding.txt`` for a model description.

    Parameters
    ----------
    description_xml : bytes
        The FMU's modelDescription.xml.
    package, entry, class_name : str
        The private package holding the cores, the entry module's file stem in resources/ and
        the slave class defined there.
    """
    root = ElementTree.fromstring(description_xml)
    libpython, python, version = _python_facts()
    lines = ["# sonotrack FMI binary binding, read by binaries/linux64 at fmi2Instantiate",
             f"guid\t{root.get('guid')}", f"libpython\t{libpython}", f"python\t{python}",
             f"python_version\t{version}", f"package\t{package}", f"entry\t{entry}",
             f"class\t{class_name}"]
    for variable in root.find("ModelVariables"):
        name = variable.get("name")
        if "." in name or "\t" in name or not name.isidentifier():
            raise BuildError(f"{class_name}: variable {name!r} is not a Python identifier; the "
                             f"binary reads each port as the slave attribute of that name")
        kind = next(child.tag for child in variable if child.tag in
                    ("Real", "Integer", "Boolean", "String"))
        causality = variable.get("causality", "local")
        variability = variable.get("variability", "continuous" if kind == "Real" else "discrete")
        lines.append("\t".join(["var", variable.get("valueReference"), kind, causality, variability,
                                variable.get("initial", "-"), name]))
    return "\n".join(lines) + "\n"


def install_binary(fmu_path, package, entry, class_name, library=LIBRARY):
    """Put sonotrack's linux64 binary and its binding table into a pythonfmu-built FMU.

    Parameters
    ----------
    fmu_path : path-like
        The ``.fmu`` file, rewritten in place (atomically).
    package, entry, class_name : str
        See :func:`binding_table`.
    library : path-like, optional
        The compiled binary (default: the one ``make`` builds).

    Raises
    ------
    BuildError
        If the library is missing or was not compiled from the C sources now in this folder
        (its recorded :func:`source_hash` differs): a stale library would put other C code
        into the FMU than the checkout holds.
    """
    fmu_path = Path(fmu_path)
    library = Path(library)
    if not library.is_file():
        raise BuildError(f"FMI binary {library} is missing: run `make` (target {library.name})")
    built_from, sources = library_source_hash(library), source_hash()
    if built_from != sources:
        recorded = f"sha256 {built_from[:12]}" if built_from else "none recorded"
        raise BuildError(f"FMI binary {library} was compiled from other C sources ({recorded}) "
                         f"than {HERE} holds now (sha256 {sources[:12]}): run `make` (target "
                         f"{library.name})")
    description, identifier = _description(fmu_path)
    table = binding_table(description, package, entry, class_name).encode()
    _rewrite(fmu_path, {f"binaries/linux64/{identifier}.so": library.read_bytes(),
                        BINDING_FILE: table})
    return fmu_path


def restore_pythonfmu_binary(fmu_path):
    """Put pythonfmu's own linux64 binary back into an FMU (for side-by-side comparisons)."""
    fmu_path = Path(fmu_path)
    _, identifier = _description(fmu_path)
    _rewrite(fmu_path, {f"binaries/linux64/{identifier}.so": pythonfmu_binary().read_bytes(),
                        BINDING_FILE: None})
    return fmu_path


def _description(fmu_path):
    with zipfile.ZipFile(fmu_path) as archive:
        try:
            description = archive.read("modelDescription.xml")
        except KeyError:
            raise BuildError(f"{fmu_path}: no modelDescription.xml") from None
    identifier = ElementTree.fromstring(description).find("CoSimulation").get("modelIdentifier")
    return description, identifier


def _rewrite(fmu_path, replaced):
    """Rewrite the zip with ``replaced`` entries (None: removed), atomically."""
    with zipfile.ZipFile(fmu_path) as archive:
        entries = [(info, archive.read(info)) for info in archive.infolist()]
    with (atomic_open(fmu_path, fsync=False) as stream,
          zipfile.ZipFile(stream, "w", zipfile.ZIP_DEFLATED) as archive):
        for info, data in entries:
            if info.filename not in replaced:
                archive.writestr(info, data)
        for name, data in replaced.items():
            if data is not None:
                archive.writestr(name, data)


def pythonfmu_binary():
    """Path of pythonfmu's own linux64 binary (for comparisons; FMUs ship sonotrack's)."""
    import pythonfmu

    return Path(pythonfmu.__file__).parent / "resources" / "binaries" / "linux64" / \
        "libpythonfmu-export.so"
