"""The FMU cache stays bounded: least recently used entries go, entries in use never do.

Every extraction here runs in a child process, as a run does, so that its lock on the entry
ends when the process ends (the test process would otherwise hold every entry it touched).
"""

import os
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest

from components.common.errors import ConfigError
from orchestrator.fmu.cache import cache_limits, extract_fmu, prune_cache

REPO = Path(__file__).resolve().parents[4]
_EXTRACT = "import sys; from orchestrator.fmu.cache import extract_fmu; print(extract_fmu(sys.argv[1]))"
# Unpacks its FMU, says where, then reads a file of the entry each time it is asked to.
_HOLDER = """
import sys
from orchestrator.fmu.cache import extract_fmu
folder = extract_fmu(sys.argv[1])
print(folder, flush=True)
for line in sys.stdin:
    print((folder / "resources" / "data.txt").read_text().strip(), flush=True)
"""


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("SONOTRACK_CACHE_DIR", str(folder))
    for name in ("SONOTRACK_CACHE_MAX_FMUS", "SONOTRACK_CACHE_MAX_BYTES",
                 "SONOTRACK_FMU_MAX_BYTES"):
        monkeypatch.delenv(name, raising=False)
    return folder


def _fmu(path, payload=b""):
    """A small archive shaped like an FMU; ``payload`` makes its content (and digest) unique."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("modelDescription.xml", "<fmiModelDescription/>")
        archive.writestr("binaries/linux64/model.so", b"\x7fELF" + bytes(100) + payload)
        archive.writestr("resources/data.txt", f"{path.stem}\n")
    return path


def _env(**limits):
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    env.update({f"SONOTRACK_CACHE_MAX_{key.upper()}": str(value) for key, value in limits.items()})
    return env


def _extract_in_child(fmu, **limits):
    completed = subprocess.run([sys.executable, "-c", _EXTRACT, str(fmu)], env=_env(**limits),
                               capture_output=True, text=True, timeout=120, check=True)
    time.sleep(0.01)   # distinct last-use times even on a coarse clock
    return Path(completed.stdout.strip())


def _entries(cache):
    return {folder.name for folder in (cache / "fmus").iterdir()
            if not folder.name.startswith(".")}


def test_the_least_recently_used_entries_go_first(cache, tmp_path):
    fmus = {name: _fmu(tmp_path / f"{name}.fmu", name.encode()) for name in "abcd"}
    folders = {name: _extract_in_child(fmus[name], fmus=2) for name in "abc"}
    assert _entries(cache) == {folders["b"].name, folders["c"].name}   # a was oldest
    _extract_in_child(fmus["b"], fmus=2)   # b is used again: c is now the oldest
    folders["d"] = _extract_in_child(fmus["d"], fmus=2)
    assert _entries(cache) == {folders["b"].name, folders["d"].name}
    assert sorted(p.stem for p in (cache / "fmu-locks").iterdir()) == sorted(_entries(cache))
    # what is left is intact: reusing it unpacks nothing
    assert (folders["b"] / "resources" / "data.txt").read_text() == "b\n"


def test_the_size_bound_keeps_at_least_the_newest(cache, tmp_path):
    first = _extract_in_child(_fmu(tmp_path / "a.fmu", b"a"))
    second = _extract_in_child(_fmu(tmp_path / "b.fmu", b"b"), bytes=1)
    assert _entries(cache) == {second.name} and not first.exists()


def test_an_entry_in_use_is_never_pruned(cache, tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, str(_fmu(tmp_path / "held.fmu"))],
                              env=_env(), stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                              text=True)
    try:
        held = Path(holder.stdout.readline().strip())
        time.sleep(0.01)
        others = [_extract_in_child(_fmu(tmp_path / f"{n}.fmu", n.encode()), fmus=1)
                  for n in "xyz"]
        # the held entry is the oldest, far past the bound, and still complete
        assert _entries(cache) == {held.name, others[-1].name}
        holder.stdin.write("read\n")
        holder.stdin.flush()
        assert holder.stdout.readline().strip() == "held"
    finally:
        holder.stdin.close()
        assert holder.wait(timeout=60) == 0
    # once its user has exited, the same entry is pruned like any other
    assert held.name in prune_cache(max_fmus=1) and not held.exists()
    assert _entries(cache) == {others[-1].name}


def test_this_process_never_prunes_what_it_uses(cache, tmp_path):
    folders = [extract_fmu(_fmu(tmp_path / f"{n}.fmu", n.encode())) for n in "abc"]
    assert prune_cache(max_fmus=1) == []
    assert all((folder / "modelDescription.xml").is_file() for folder in folders)


@pytest.mark.parametrize("name, text", [("SONOTRACK_CACHE_MAX_FMUS", "0"),
                                        ("SONOTRACK_CACHE_MAX_BYTES", "lots")],
                         ids=["zero-fmus", "bytes-not-a-number"])
def test_a_bad_cache_bound_is_refused_with_its_name(cache, monkeypatch, name, text):
    monkeypatch.setenv(name, text)
    with pytest.raises(ConfigError, match=f"{name}={text!r}: expected a positive number"):
        cache_limits()


_USER = """
import sys, time
from orchestrator.fmu.cache import extract_fmu
for path in sys.argv[1:]:
    folder = extract_fmu(path)
    time.sleep(0.05)   # others prune meanwhile
    text = (folder / "resources" / "data.txt").read_text().strip()
    assert text == path.rsplit("/", 1)[1][:-4], (text, path)
    assert (folder / "binaries" / "linux64" / "model.so").stat().st_size >= 104
print("ok")
"""


def test_concurrent_users_and_pruners_never_see_a_missing_entry(cache, tmp_path):
    fmus = [str(_fmu(tmp_path / f"m{n}.fmu", bytes([n]))) for n in range(4)]
    for wave in range(3):
        children = [subprocess.Popen([sys.executable, "-c", _USER,
                                      *(fmus[(wave + k + j) % 4] for j in range(3))],
                                     env=_env(fmus=1), stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True) for k in range(6)]
        for child in children:
            out, err = child.communicate(timeout=120)
            assert child.returncode == 0 and out.strip() == "ok", err
    assert len(_entries(cache)) >= 1
    assert not list((cache / "fmus").glob(".pruned-*"))
