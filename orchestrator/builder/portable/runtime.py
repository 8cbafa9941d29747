"""The relocatable CPython runtime a portable FMU carries, and what goes into it.

The runtime is the build's own Python 3.11 (its shared ``libpython``, the standard-library
modules :mod:`.recording` says the model needs) and the venv's numpy if the model imports it
(RobotPlant and CurvaturePlanner do not), laid out as a Python installation under
``binaries/linux64/python/`` of the FMU, so that the interpreter finds its standard library
from its own location::

    binaries/linux64/python/lib/libpython3.11.so.1.0
    binaries/linux64/python/lib/python3.11/os.pyc, json/ ...    the carried modules
    binaries/linux64/python/lib/python3.11/lib-dynload/*.so     their extension modules
    binaries/linux64/python/lib/python3.11/site-packages/numpy  numpy without tests, stubs, headers

What the recording saw imported is carried compiled, as unchecked-hash ``.pyc`` files in place
of the sources (nothing is compiled at the first instantiation or written into the unzipped
FMU, whatever time stamps unzipping gives the files; tracebacks through them show no source
lines); the rest of the closure, the margin, is carried as source. Modules frozen into libpython
run from there: of their files only ``os``'s is carried, the landmark by which the interpreter
finds its standard library. Every ELF file is stripped of its symbol table (``strip
--strip-unneeded``: only the dynamic symbols are used at run time), unless stripping would
break it (:func:`_stripped`).

Left out by rule, not by recording: the standard library's tests, GUI and developer tools
(:data:`EXCLUDED`), which enter the static closure only through ``pydoc`` and ``doctest``, and
the OpenSSL modules (``_ssl``, ``_hashlib``: 5.4 MB of libraries; ``hashlib`` falls back to
its built-in hashes, no model uses ``ssl``). The libraries the carried extension modules need
beyond glibc, ``libstdc++``, ``libgcc_s`` and ``libz`` are listed by :func:`system_libraries`
(libffi for ``ctypes``, for one): where one is missing, importing that module fails and its
importer falls back (numpy runs without ctypes).
"""

import importlib.util
import re
import py_compile
import shutil
import struct
import subprocess
import sys
import sysconfig
import tempfile
import warnings
from pathlib import Path

from components.common.errors import BuildError

from .recording import dynload_folder, stdlib_folder

__all__ = ["RUNTIME_FOLDER", "EXCLUDED", "runtime_files", "libpython", "system_libraries"]

RUNTIME_FOLDER = "binaries/linux64/python"
EXCLUDED = ("test", "tkinter", "_tkinter", "idlelib", "turtledemo", "lib2to3", "pydoc_data",
            "ensurepip", "_testcapi", "_testinternalcapi", "_testbuffer", "_ssl", "_hashlib",
            "readline", "_curses", "_curses_panel", "_sqlite3", "_dbm", "_gdbm", "nis", "_crypt")
# Always carried: the interpreter's landmark and every codec (codecs are looked up by a name
# given at run time, a locale's for one, which neither the recording nor the closure sees).
_ALWAYS = ("os", "encodings")
# numpy folders and files that no import reaches: tests, typing stubs, C headers, f2py.
_NUMPY_SKIPPED_PARTS = {"tests", "include", "f2py", "_pyinstaller", "__pycache__", "testing",
                        "distutils"}
# numpy's test-only extension modules (its own test suite imports them)
_TEST_EXTENSION = re.compile(r"^(_\w+_tests|_simd)\.cpython")
_NUMPY_SKIPPED_SUFFIXES = {".pyi", ".pxd", ".h", ".c", ".txt", ".pyx"}
# libraries any Linux with glibc has (numpy's manylinux wheel assumes them too)
_SYSTEM = ("libc.so", "libm.so", "libpthread.so", "libdl.so", "librt.so", "libutil.so",
           "ld-linux", "linux-vdso", "libstdc++.so", "libgcc_s.so", "libz.so")


def libpython():
    """The build Python's shared libpython (Debian's python3.11 is linked statically, but its
    package libpython3.11 puts the same build's shared library where sysconfig says)."""
    library = Path(sysconfig.get_config_var("LIBDIR") or "",
                   sysconfig.get_config_var("INSTSONAME") or "")
    if not library.name.startswith("libpython") or not library.is_file():
        raise BuildError(f"--portable needs the build Python's shared libpython ({library} "
                         f"does not exist): install it (Debian: apt-get install libpython3.11) "
                         f"or make the venv with a Python built with --enable-shared")
    return library


def _excluded(name):
    return name.split(".")[0] in EXCLUDED


def _module_paths(name, stdlib, dynload):
    """(source file, path in the runtime) of one standard module, or None (built in)."""
    try:
        with warnings.catch_warnings():  # finding lib2to3's modules imports it: deprecated
            warnings.simplefilter("ignore", DeprecationWarning)
            spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return None
    if spec is None:
        return None
    if spec.origin == "frozen":  # in libpython; os's file is the landmark of the stdlib
        if name != "os":
            return None
        origin = stdlib / "os.py"
    elif not spec.has_location or spec.origin is None:
        return None
    else:
        origin = Path(spec.origin)
    version = f"python{sys.version_info.major}.{sys.version_info.minor}"
    if dynload in origin.parents:
        return origin, f"lib/{version}/lib-dynload/{origin.name}"
    if stdlib in origin.parents:
        return origin, f"lib/{version}/{origin.relative_to(stdlib).as_posix()}"
    return None


def _stripped(path, work):
    """The bytes of ``path`` stripped of its symbols (``strip`` from binutils), or unchanged
    where stripping would leave a load segment off its page alignment: strip does that to
    some libraries patchelf has edited (auditwheel's, in numpy's wheel), which then fail to
    load ("ELF load command address/offset not page-aligned")."""
    copy = Path(work) / path.name
    shutil.copyfile(path, copy)
    strip = shutil.which("strip")
    if strip is None:
        raise BuildError("--portable needs `strip` (Debian: apt-get install binutils)")
    subprocess.run([strip, "--strip-unneeded", str(copy)], check=True, capture_output=True)
    data, original = copy.read_bytes(), path.read_bytes()
    return data if _loadable(data) and len(data) < len(original) else original


def _loadable(data):
    """True if every PT_LOAD segment of a 64-bit ELF maps at an offset congruent to its
    address modulo the page and its alignment (what the dynamic loader requires)."""
    phoff, = struct.unpack_from("<Q", data, 0x20)
    phentsize, phnum = struct.unpack_from("<HH", data, 0x36)
    for i in range(phnum):
        kind, _, offset, address, _, _, _, align = struct.unpack_from(
            "<IIQQQQQQ", data, phoff + i * phentsize)
        if kind == 1 and ((address - offset) % 4096 or (align and (address - offset) % align)):
            return False
    return True


def _pyc(source, shown, work):
    """An unchecked-hash .pyc of ``source`` (tracebacks name it ``shown``)."""
    target = Path(work) / "compiled.pyc"
    py_compile.compile(str(source), cfile=str(target), dfile=shown, doraise=True,
                       invalidation_mode=py_compile.PycInvalidationMode.UNCHECKED_HASH)
    return target.read_bytes()


def _module_name(inside):
    """``lib/python3.11/site-packages/numpy/_core/__init__.py`` -> ``numpy._core``."""
    parts = Path(inside).with_suffix("").parts[2:]
    parts = parts[1:] if parts and parts[0] in ("site-packages", "lib-dynload") else parts
    parts = parts[:-1] if parts and parts[-1] == "__init__" else parts
    return ".".join(parts)


def _add_file(files, source, inside, work, recorded):
    """Put one module file into ``files``: a .py the recording saw imported as .pyc (the
    margin stays source), extension modules stripped."""
    if source.suffix == ".py" and _module_name(inside) in recorded:
        files[inside[:-3] + ".pyc"] = _pyc(source, inside, work)
    elif source.suffix == ".so":
        files[inside] = _stripped(source, work)
    else:
        files[inside] = source.read_bytes()


def runtime_files(stdlib_modules, recorded, with_numpy=True):
    """The runtime's files: path inside :data:`RUNTIME_FOLDER` -> bytes.

    Parameters
    ----------
    stdlib_modules : iterable of str
        The standard-library modules to carry (:func:`.recording.needed_stdlib`'s
        ``carried``); :data:`EXCLUDED` ones are dropped, :data:`_ALWAYS` ones added.
    recorded : set of str
        Every module the recording saw imported: these are carried compiled.
    with_numpy : bool
        Carry numpy (its package and the libraries of its wheel, ``numpy.libs``).
    """
    stdlib, dynload = stdlib_folder(), dynload_folder()
    version = f"python{sys.version_info.major}.{sys.version_info.minor}"
    files = {}
    with tempfile.TemporaryDirectory(prefix="sonotrack_runtime_") as work:
        library = libpython()
        files[f"lib/{library.name}"] = _stripped(library, work)
        names = {n for n in stdlib_modules if not _excluded(n)} | set(_ALWAYS)
        for name in sorted(names):
            found = _module_paths(name, stdlib, dynload)
            if found is None:
                continue
            source, inside = found
            _add_file(files, source, inside, work, recorded)
            if name == "encodings":
                for codec in sorted(source.parent.glob("*.py")):
                    _add_file(files, codec, f"lib/{version}/encodings/{codec.name}", work,
                              recorded)
        # a package's __init__ is carried with any of its modules
        for inside in [p for p in files if p.count("/") > 2]:
            package = Path(inside).parent
            init = f"{package.as_posix()}/__init__.pyc"
            relative = package.relative_to(f"lib/{version}")
            source = stdlib / relative / "__init__.py"
            if relative.parts[0] != "lib-dynload" and init not in files and source.is_file():
                _add_file(files, source, f"{package.as_posix()}/__init__.py", work, recorded)
        files[f"lib/{version}/lib-dynload/.keep"] = b""  # the interpreter checks the folder
        if with_numpy:
            files.update(_numpy_files(version, work, recorded))
    return files


def _numpy_files(version, work, recorded):
    import numpy

    site = Path(numpy.__file__).parent.parent
    files = {}
    for folder in (site / "numpy", site / "numpy.libs"):
        for path in sorted(p for p in folder.rglob("*") if p.is_file()):
            relative = path.relative_to(site)
            if _NUMPY_SKIPPED_PARTS & set(relative.parts) or \
                    path.suffix in _NUMPY_SKIPPED_SUFFIXES:
                continue
            inside = f"lib/{version}/site-packages/{relative.as_posix()}"
            if path.suffix == ".py" and _module_name(inside) in recorded:
                files[inside[:-3] + ".pyc"] = _pyc(path, inside, work)
            elif _TEST_EXTENSION.search(path.name):
                continue
            elif ".so" in path.suffixes or path.suffix == ".so":
                files[inside] = _stripped(path, work)
            else:
                files[inside] = path.read_bytes()
    return files


def system_libraries(files):
    """Libraries the carried extension modules and libpython need beyond those every glibc
    system has (:data:`_SYSTEM`), as ``{library: [modules]}``, read with ``ldd`` here."""
    needs = {}
    with tempfile.TemporaryDirectory(prefix="sonotrack_ldd_") as work:
        for inside, data in files.items():
            if not inside.endswith(".so") or "site-packages" in inside:
                continue
            copy = Path(work) / Path(inside).name
            copy.write_bytes(data)
            listed = subprocess.run(["ldd", str(copy)], capture_output=True, text=True).stdout
            for line in listed.splitlines():
                library = line.strip().split(" ")[0]
                if library and not library.startswith(_SYSTEM) and "=>" in line:
                    needs.setdefault(library, []).append(Path(inside).name.split(".")[0])
    return needs
