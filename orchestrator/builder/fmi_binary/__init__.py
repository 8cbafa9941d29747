"""sonotrack's own FMI 2.0 binary (linux64) and how ``sonotrack build`` puts it into an FMU.

pythonfmu builds the FMU (model description, resources with the slave's Python code); then
:func:`install_binary` replaces pythonfmu's ``binaries/linux64/<model>.so`` with the library
compiled by ``make`` from the C sources in this folder (:data:`SOURCES`: ``*.c`` and the private
header ``sonotrack_fmi2.h``), puts the process-wide lock library it needs beside it
(:data:`LOCK_LIBRARY`, ``process_lock.c`` says why) and writes ``resources/sonotrack_binding.txt``,
the table that library reads at ``fmi2Instantiate``: the GUID, where the slave's code lives, the
libpython and Python executable of the build (used only by hosts that run no Python) and every
variable's value reference, type, causality, variability and initial. It also moves the
pythonfmu the FMU carries under a private name, run-time modules only (:mod:`.carried_pythonfmu`),
and deflates every entry. The win64 binary stays pythonfmu's. docs/fmi_binary.md describes the
binary's contract.
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

from .carried_pythonfmu import carry, installed_runtime

__all__ = ["LIBRARY", "LOCK_LIBRARY", "SOURCES", "BINDING_FILE", "build_tag", "source_hash", "library_source_hash",
           "install_binary", "binding_table", "pythonfmu_binary", "restore_pythonfmu_binary",
           "edit_archive"]

HERE = Path(__file__).resolve().parent
LIBRARY = HERE / "linux64" / "sonotrack_fmi2.so"
# Needed by LIBRARY under this name (its soname), from the same folder of the FMU.
LOCK_LIBRARY = HERE / "linux64" / "libsonotrack_fmi2_lock.so.1"
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
    of identical code may share them. The code counted is ``sources`` and the run-time
    pythonfmu the FMU carries inside that package.

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
    for name, data in sorted(installed_runtime().items()):
        digest.update(f"pythonfmu/{name}".encode() + b"\0" + data + b"\0")
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
        The compiled binary (default: the one ``make`` builds); the lock library is taken
        from the same folder.

    Raises
    ------
    BuildError
        If the library or the lock library is missing or was not compiled from the C sources
        now in this folder (its recorded :func:`source_hash` differs): a stale library would
        put other C code into the FMU than the checkout holds.
    """
    fmu_path = Path(fmu_path)
    library = Path(library)
    lock = library.with_name(LOCK_LIBRARY.name)
    for compiled in (library, lock):
        _check_compiled(compiled)
    description, identifier = _description(fmu_path)
    table = binding_table(description, package, entry, class_name).encode()

    def edit(files):
        carry(files, package, entry)
        files[f"binaries/linux64/{identifier}.so"] = library.read_bytes()
        files[f"binaries/linux64/{lock.name}"] = lock.read_bytes()
        files[BINDING_FILE] = table

    edit_archive(fmu_path, edit)
    return fmu_path


def _check_compiled(library):
    """Refuse a missing library or one compiled from other sources than the checkout's."""
    if not library.is_file():
        raise BuildError(f"FMI binary {library} is missing: run `make` (target {library.name})")
    built_from, sources = library_source_hash(library), source_hash()
    if built_from != sources:
        recorded = f"sha256 {built_from[:12]}" if built_from else "none recorded"
        raise BuildError(f"FMI binary {library} was compiled from other C sources ({recorded}) "
                         f"than {HERE} holds now (sha256 {sources[:12]}): run `make` (target "
                         f"{library.name})")


def restore_pythonfmu_binary(fmu_path):
    """Put pythonfmu's own linux64 binary back into an FMU (for side-by-side comparisons)."""
    fmu_path = Path(fmu_path)
    _, identifier = _description(fmu_path)
    def edit(files):
        files[f"binaries/linux64/{identifier}.so"] = pythonfmu_binary().read_bytes()
        files.pop(f"binaries/linux64/{LOCK_LIBRARY.name}", None)
        files.pop(BINDING_FILE, None)

    edit_archive(fmu_path, edit)
    return fmu_path


def _description(fmu_path):
    with zipfile.ZipFile(fmu_path) as archive:
        try:
            description = archive.read("modelDescription.xml")
        except KeyError:
            raise BuildError(f"{fmu_path}: no modelDescription.xml") from None
    identifier = ElementTree.fromstring(description).find("CoSimulation").get("modelIdentifier")
    return description, identifier


def edit_archive(fmu_path, edit, compresslevel=None):
    """Rewrite the zip atomically: ``edit`` changes a dict of its files (name to bytes) in place.

    Every entry is deflated (pythonfmu stores most of them; ``compresslevel`` as zipfile's,
    default 6); an entry that stays keeps its permissions, a new one is readable by everyone
    (executable for a library). Entries are written in name order and dated 1980-01-01 (zip's
    earliest date), so that a build from the same code gives the same bytes.
    """
    with zipfile.ZipFile(fmu_path) as archive:
        infos = {info.filename: info for info in archive.infolist()}
        files = {name: archive.read(info) for name, info in infos.items()}
    edit(files)
    with (atomic_open(fmu_path, fsync=False) as stream,
          zipfile.ZipFile(stream, "w", zipfile.ZIP_DEFLATED,
                          compresslevel=compresslevel) as archive):
        for name in sorted(files):
            info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
            kept = infos.get(name)
            if kept is not None:
                info.external_attr = kept.external_attr
            else:
                mode = 0o755 if name.startswith("binaries/") else 0o644
                info.external_attr = (0o100000 | mode) << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            archive.writestr(info, files[name])


def pythonfmu_binary():
    """Path of pythonfmu's own linux64 binary (for comparisons; FMUs ship sonotrack's)."""
    import pythonfmu

    return Path(pythonfmu.__file__).parent / "resources" / "binaries" / "linux64" / \
        "libpythonfmu-export.so"
