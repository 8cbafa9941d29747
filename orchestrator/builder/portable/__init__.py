"""Portable FMUs: an FMU that carries its own CPython runtime and runs where no Python is.

``sonotrack build --portable`` builds each FMU as usual, then :func:`make_portable`:

1. runs it and records the modules it imports (:mod:`.recording`), widened by the static
   closure of their imports;
2. lays out the runtime (:mod:`.runtime`): the build's libpython, those standard-library
   modules, numpy when the model imports it, under ``binaries/linux64/python/``;
3. names that folder in the binding table (``runtime``, and ``runtime_numpy no`` when it
   carries no numpy, which the model then does not need), where the library looks for Python
   right after the environment variables (docs/fmi_binary.md, "Finding Python"), writes what
   was recorded and carried to ``binaries/linux64/python/sonotrack_runtime.json`` and declares
   ``needsExecutionTool="false"`` in modelDescription.xml;
4. leaves out the win64 binary (pythonfmu's DLL, which needs an installed Python and so would
   make that declaration false on Windows): a portable FMU is linux64 only.

In a host that already runs Python (fmpy, libcosimpy) the carried runtime is never loaded:
the FMU runs in the host's interpreter as a plain one does.
"""

import json
import re
import sys
import tempfile
import zipfile
from pathlib import Path

from components.common.errors import BuildError
from orchestrator.builder.fmi_binary import BINDING_FILE, edit_archive

from .recording import needed_stdlib, record_modules
from .runtime import EXCLUDED, RUNTIME_FOLDER, runtime_files, system_libraries

__all__ = ["RUNTIME_FOLDER", "MANIFEST", "SIZE_LIMIT", "make_portable", "EXCLUDED"]

MANIFEST = f"{RUNTIME_FOLDER}/sonotrack_runtime.json"
SIZE_LIMIT = 20_000_000  # bytes per FMU (issue 23)


def make_portable(fmu_path):
    """Put a runtime into a built FMU (rewritten in place) and return its manifest (a dict).

    Raises
    ------
    BuildError
        If the model cannot be run to record its imports, or the build's Python has no shared
        libpython.
    """
    fmu_path = Path(fmu_path)
    recorded = record_modules(fmu_path)
    with tempfile.TemporaryDirectory(prefix="sonotrack_code_") as folder:
        with zipfile.ZipFile(fmu_path) as archive:
            archive.extractall(folder, [n for n in archive.namelist()
                                        if n.startswith("resources/") and n.endswith(".py")])
        needed = needed_stdlib(recorded, [Path(folder) / "resources"])
    with_numpy = "numpy" in recorded
    files = runtime_files(needed["carried"], recorded, with_numpy)
    manifest = {
        "python": ".".join(map(str, sys.version_info[:3])),
        "numpy": _numpy_version() if with_numpy else None,
        "recorded_stdlib_modules": needed["recorded"],
        "carried_stdlib_modules": sorted(n for n in needed["carried"]
                                         if n.split(".")[0] not in EXCLUDED),
        "left_out_by_rule": sorted(n for n in needed["carried"] if n.split(".")[0] in EXCLUDED),
        "system_libraries": system_libraries(files),
        "files": len(files),
        "unpacked_bytes": sum(len(data) for data in files.values()),
    }

    def edit(entries):
        for name in [n for n in entries if n.startswith("binaries/win64/")]:
            del entries[name]  # pythonfmu's DLL needs an installed Python: not portable
        for inside, data in files.items():
            entries[f"{RUNTIME_FOLDER}/{inside}"] = data
        entries[MANIFEST] = json.dumps(manifest, indent=1).encode()
        table = entries[BINDING_FILE].decode()
        table = re.sub(r"^runtime(_numpy)?\t.*\n", "", table, flags=re.M)
        table += f"runtime\t{RUNTIME_FOLDER}\n"
        if not with_numpy:  # the library then does not look for numpy in the runtime
            table += "runtime_numpy\tno\n"
        entries[BINDING_FILE] = table.encode()
        description = entries["modelDescription.xml"].decode()
        if 'needsExecutionTool="' not in description:
            raise BuildError(f"{fmu_path}: modelDescription.xml declares no needsExecutionTool")
        entries["modelDescription.xml"] = description.replace(
            'needsExecutionTool="true"', 'needsExecutionTool="false"').encode()

    edit_archive(fmu_path, edit, compresslevel=9)
    return manifest


def _numpy_version():
    import numpy

    return numpy.__version__
