"""The ELF version-needs reader of tests/support/elf_versions.py, against binutils' objdump.

Checked on a library gcc compiles here against this machine's glibc (dlopen and stat: glibc
2.34 and 2.33 give them new versions), so that the reader is seen finding a requirement newer
than the 2.17 floor the FMI binary must keep.
"""

import os
import re
import shutil
import subprocess

import pytest

from tests.support.elf_versions import glibc_floor, required_versions

_SOURCE = ("#include <dlfcn.h>\n#include <sys/stat.h>\n"
           "int probe(const char *p) { struct stat s; return dlopen(p, RTLD_NOW) != 0 "
           "&& stat(p, &s) == 0; }\n")


def _objdump_versions(path):
    """Needed library -> version names, from `objdump -p` (Version References)."""
    text = subprocess.run(["objdump", "-p", str(path)], check=True, capture_output=True,
                          text=True).stdout
    needs, current = {}, None
    for line in text.split("Version References:", 1)[-1].splitlines():
        if (m := re.match(r"\s+required from (\S+):", line)):
            current = needs.setdefault(m.group(1), set())
        elif current is not None and (m := re.match(r"\s+0x\w+ 0x\w+ \d+ (\S+)", line)):
            current.add(m.group(1))
    return needs


@pytest.fixture(scope="module")
def gcc_library(tmp_path_factory):
    if shutil.which("gcc") is None or shutil.which("objdump") is None:
        pytest.skip("gcc or objdump (binutils) is not installed")
    folder = tmp_path_factory.mktemp("elf")
    (folder / "probe.c").write_text(_SOURCE)
    library = folder / "libprobe.so"
    subprocess.run(["gcc", "-shared", "-fPIC", "-O1", "-o", str(library), str(folder / "probe.c"),
                    "-ldl"], check=True)
    return library


def test_the_reader_agrees_with_objdump(gcc_library):
    assert required_versions(gcc_library) == _objdump_versions(gcc_library)


def test_a_library_built_against_this_glibc_needs_its_new_dlopen(gcc_library):
    machine = os.confstr("CS_GNU_LIBC_VERSION")  # "glibc 2.36"
    version = tuple(int(p) for p in machine.split()[1].split(".")[:2])
    if version < (2, 34):
        pytest.skip(f"{machine}: dlopen has no newer version than 2.2.5 here")
    assert "GLIBC_2.34" in required_versions(gcc_library)["libc.so.6"]
    assert glibc_floor(gcc_library) >= (2, 34) > (2, 17)
