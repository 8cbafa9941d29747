"""Which standard-library modules a model needs: recorded by running it, widened by a stated rule.

:func:`record_modules` runs a built (plain) FMU in a fresh process of the build's base Python,
started isolated and without ``site`` (``-I -S``), which then imports ``site`` itself without
running it (the runtime an FMU carries imports ``site`` at start) and numpy's folder is added
to ``sys.path``. The FMU's own library is loaded with ``ctypes``: the interpreter is running, so
it uses it, exactly as it does in any Python host, and runs its bootstrap (the modules the
library itself imports). The run takes every FMI call the model's Python side sees: instantiate,
set up, initialise, 100 steps at the default step size with the inputs at their start values,
every Real output read, an FMU state taken, serialized, read back and restored, one more step,
a refused input (NaN, the refusal path), terminate, reset and free. ``sys.modules`` is then
listed; nothing is guessed.

:func:`needed_stdlib` applies the safety margin: the carried standard library is the recorded
modules *and every module any of them imports anywhere in its code*, transitively
(``modulefinder``'s static closure, which also reads imports inside functions and in ``try``
blocks), within the standard library; the same closure is taken of the model's own code. So a
code path the recording did not take can still import a standard module its code names; only a
module named at run time by a string (``importlib.import_module(name)``) could be missed.
"""

import json
import modulefinder
import subprocess
import sys
import sysconfig
import tempfile
import warnings
import zipfile
from pathlib import Path

from components.common.errors import BuildError

__all__ = ["record_modules", "needed_stdlib", "stdlib_folder", "dynload_folder"]

# Run in the recording process: argv = binary, resources folder, guid, step size, numpy's site.
_RECORDER = r'''
import sys
import site  # the carried runtime imports site at start (not run here: -S)
sys.path.append(sys.argv[5])
import ctypes
lib = ctypes.CDLL(sys.argv[1])
uri = ("file://" + sys.argv[2]).encode()
lib.fmi2Instantiate.restype = ctypes.c_void_p
c = lib.fmi2Instantiate(b"recorder", 1, sys.argv[3].encode(), uri, None, 0, 0)
if not c:
    raise SystemExit("fmi2Instantiate returned NULL")
c = ctypes.c_void_p(c)
h = float(sys.argv[4])
check = lambda status, call: status == 0 or sys.exit(f"{call} returned {status}")
check(lib.fmi2SetupExperiment(c, 0, ctypes.c_double(0.0), ctypes.c_double(0.0), 0, ctypes.c_double(0.0)), "setup")
check(lib.fmi2EnterInitializationMode(c), "enter")
check(lib.fmi2ExitInitializationMode(c), "exit")
for k in range(100):
    check(lib.fmi2DoStep(c, ctypes.c_double(k * h), ctypes.c_double(h), 1), "doStep")
table = open(sys.argv[2] + "/sonotrack_binding.txt").read().splitlines()
reals = [int(f[1]) for f in (line.split("\t") for line in table)
         if f[0] == "var" and f[2] == "Real"]
inputs = [int(f[1]) for f in (line.split("\t") for line in table)
          if f[0] == "var" and f[2] == "Real" and f[3] == "input"]
refs = (ctypes.c_uint * len(reals))(*reals)
values = (ctypes.c_double * len(reals))()
check(lib.fmi2GetReal(c, refs, len(reals), values), "getReal")
state = ctypes.c_void_p()
check(lib.fmi2GetFMUstate(c, ctypes.byref(state)), "getFMUstate")
size = ctypes.c_size_t()
check(lib.fmi2SerializedFMUstateSize(c, state, ctypes.byref(size)), "size")
data = (ctypes.c_char * size.value)()
check(lib.fmi2SerializeFMUstate(c, state, data, size), "serialize")
again = ctypes.c_void_p()
check(lib.fmi2DeSerializeFMUstate(c, data, size, ctypes.byref(again)), "deserialize")
check(lib.fmi2SetFMUstate(c, again), "setFMUstate")
lib.fmi2FreeFMUstate(c, ctypes.byref(state))
lib.fmi2FreeFMUstate(c, ctypes.byref(again))
check(lib.fmi2DoStep(c, ctypes.c_double(100 * h), ctypes.c_double(h), 1), "doStep")
if inputs:  # the refusal path: a NaN input is refused when the model reads it
    lib.fmi2SetReal(c, (ctypes.c_uint * 1)(inputs[0]), 1, (ctypes.c_double * 1)(float("nan")))
    lib.fmi2DoStep(c, ctypes.c_double(101 * h), ctypes.c_double(h), 1)
lib.fmi2Terminate(c)
lib.fmi2Reset(c)
lib.fmi2FreeInstance(c)
print("MODULES " + " ".join(sorted(sys.modules)))
'''


def stdlib_folder():
    """The build Python's standard library (``lib/python3.X``)."""
    return Path(sysconfig.get_paths()["stdlib"])


def dynload_folder():
    """The build Python's ``lib-dynload`` (the standard library's extension modules)."""
    return Path(sysconfig.get_config_var("DESTSHARED"))


def record_modules(fmu_path):
    """Every module in ``sys.modules`` after running the FMU ``fmu_path`` as described above.

    Raises
    ------
    BuildError
        If the run fails (the message has the recording process's stderr).
    """
    import numpy

    fmu_path = Path(fmu_path)
    with tempfile.TemporaryDirectory(prefix="sonotrack_record_") as folder:
        with zipfile.ZipFile(fmu_path) as archive:
            archive.extractall(folder)
            description = archive.read("modelDescription.xml").decode()
        identifier = description.split('modelIdentifier="', 1)[1].split('"', 1)[0]
        guid = description.split(' guid="', 1)[1].split('"', 1)[0]
        step = description.split('stepSize="', 1)[1].split('"', 1)[0] \
            if 'stepSize="' in description else "0.01"
        binary = Path(folder) / "binaries" / "linux64" / f"{identifier}.so"
        completed = subprocess.run(
            [getattr(sys, "_base_executable", sys.executable), "-I", "-S", "-c", _RECORDER,
             str(binary), str(Path(folder) / "resources"), guid, step,
             str(Path(numpy.__file__).parent.parent)],
            capture_output=True, text=True, timeout=600, cwd=folder)
    lines = [x for x in completed.stdout.splitlines() if x.startswith("MODULES ")]
    if completed.returncode != 0 or not lines:
        raise BuildError(f"{fmu_path.name}: recording the modules it imports failed: "
                         f"{completed.stderr.strip()[-2000:]}")
    return set(lines[-1].split()[1:])


def _is_stdlib(name, stdlib, dynload):
    """True for a module of the standard library (a file under ``stdlib`` outside
    site-packages, an extension module in ``dynload``, or built in)."""
    spec_file = _module_file(name)
    if spec_file is None:
        return name in sys.builtin_module_names
    path = Path(spec_file)
    if dynload in path.parents:
        return True
    return stdlib in path.parents and "site-packages" not in path.parts


def _module_file(name):
    module = sys.modules.get(name)
    if module is not None:
        return getattr(module, "__file__", None)
    import importlib.util

    try:
        with warnings.catch_warnings():  # finding lib2to3's modules imports it: deprecated
            warnings.simplefilter("ignore", DeprecationWarning)
            spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return None
    return spec.origin if spec is not None and spec.has_location else None


def needed_stdlib(recorded, code_folders=()):
    """The standard-library modules to carry: the recorded ones and their static closure.

    Parameters
    ----------
    recorded : iterable of str
        Module names from :func:`record_modules`.
    code_folders : iterable of path-like
        The model's own code (its private package): the closure of its imports is added too.

    Returns
    -------
    dict
        ``{"recorded": sorted names, "carried": sorted names}``, both standard library only.
    """
    stdlib, dynload = stdlib_folder(), dynload_folder()
    finder = modulefinder.ModuleFinder(path=[str(stdlib), str(dynload)])
    recorded_std = sorted(n for n in recorded if _is_stdlib(n, stdlib, dynload))
    for name in recorded_std:
        if name in sys.builtin_module_names or name == "__main__":
            continue
        try:
            finder.import_hook(name)
        except ImportError:
            pass  # a frozen-only or platform-absent module: the recording holds it anyway
    for folder in code_folders:
        for path in sorted(Path(folder).rglob("*.py")):
            try:
                finder.run_script(str(path))
            except (ImportError, SyntaxError):
                pass
    closure = {n for n in finder.modules if n != "__main__"}
    carried = sorted(set(recorded_std) | {n for n in closure if _is_stdlib(n, stdlib, dynload)})
    return {"recorded": recorded_std, "carried": carried}


def main(argv=None):
    """``python -m orchestrator.builder.portable.recording FMU``: print what it records."""
    for path in argv or sys.argv[1:]:
        recorded = record_modules(path)
        print(json.dumps(needed_stdlib(recorded), indent=1))


if __name__ == "__main__":
    main()
