"""The symbol versions a shared library needs (its ELF ``.gnu.version_r``), read without tools.

``required_versions(path)`` maps each needed library to the version names it needs
(``{"libc.so.6": {"GLIBC_2.2.5", "GLIBC_2.14"}, ...}``): what the dynamic loader checks before it
loads the library, and so the oldest glibc it can load on. 64-bit little-endian ELF only (our
linux64 binaries).
"""

import re
import struct
from pathlib import Path

__all__ = ["required_versions", "glibc_floor"]

_SHT_GNU_VERNEED = 0x6FFFFFFE


def required_versions(path):
    """Needed library -> set of version names, from the ELF's version-needs section."""
    data = Path(path).read_bytes()
    if data[:4] != b"\x7fELF" or data[4] != 2 or data[5] != 1:
        raise ValueError(f"{path}: not a 64-bit little-endian ELF file")
    shoff, = struct.unpack_from("<Q", data, 0x28)
    shentsize, shnum = struct.unpack_from("<HH", data, 0x3A)
    sections = [struct.unpack_from("<IIQQQQIIQQ", data, shoff + i * shentsize)
                for i in range(shnum)]
    needs = {}
    for _, kind, _, _, offset, _, link, info, _, _ in sections:
        if kind != _SHT_GNU_VERNEED:
            continue
        strings = sections[link][4]

        def text(at):
            return data[strings + at:data.index(b"\0", strings + at)].decode()

        entry = offset
        for _ in range(info):  # sh_info: the number of Verneed entries
            _, count, file, aux, following = struct.unpack_from("<HHIII", data, entry)
            names = needs.setdefault(text(file), set())
            at = entry + aux
            for _ in range(count):
                _, _, _, name, step = struct.unpack_from("<IHHII", data, at)
                names.add(text(name))
                at += step
            entry += following
    return needs


def glibc_floor(path):
    """The newest GLIBC_x.y any needed library is asked for, as a tuple (2, 17); (0, 0) if none."""
    versions = [tuple(int(p) for p in m.group(1).split("."))
                for names in required_versions(path).values() for name in names
                if (m := re.fullmatch(r"GLIBC_([0-9.]+)", name))]
    return max(versions, default=(0, 0))
