"""Safe FMU unpacking: refused entries, the size cap, the content-addressed cache."""

import os
import stat
import threading
import zipfile

import pytest

from components.common.errors import ConfigError
from orchestrator.fmu.cache import cache_dir, check_archive, extract_fmu


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("SONOTRACK_CACHE_DIR", str(folder))
    monkeypatch.delenv("SONOTRACK_FMU_MAX_BYTES", raising=False)
    return folder


def _fmu(path, extra=()):
    """A small archive shaped like an FMU, plus extra (ZipInfo or name, bytes) entries."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("modelDescription.xml", "<fmiModelDescription/>")
        archive.writestr("binaries/linux64/model.so", b"\x7fELF" + bytes(100))
        archive.writestr("resources/data.txt", "1,2\n")
        for info, data in extra:
            archive.writestr(info, data)
    return path


def _symlink(name, target):
    info = zipfile.ZipInfo(name)
    info.external_attr = (stat.S_IFLNK | 0o777) << 16
    return info, target


@pytest.mark.parametrize("entry, reason", [
    (("/etc/evil", b"x"), "is an absolute path"),
    (("C:/evil.dll", b"x"), "is an absolute path"),
    (("../../evil", b"x"), "contains a '..' component"),
    (("resources/../../evil", b"x"), "contains a '..' component"),
    (("binaries\\win64\\evil.dll", b"x"), "contains a backslash"),
    (_symlink("resources/passwd", "/etc/passwd"), "is a symbolic link"),
], ids=["absolute", "drive", "dotdot", "inner-dotdot", "backslash", "symlink"])
def test_unsafe_entries_are_refused_before_anything_is_written(cache, tmp_path, entry, reason):
    fmu = _fmu(tmp_path / "bad.fmu", [entry])
    with pytest.raises(ConfigError, match=reason) as raised:
        extract_fmu(fmu)
    assert str(fmu) in str(raised.value) and repr(entry[0].filename if hasattr(
        entry[0], "filename") else entry[0]) in str(raised.value)
    assert not cache.exists() or not any(cache.rglob("*"))


def test_a_512_mb_zero_entry_is_refused_before_it_is_unpacked(cache, tmp_path):
    fmu = _fmu(tmp_path / "bomb.fmu")
    with zipfile.ZipFile(fmu, "a", zipfile.ZIP_DEFLATED) as archive:
        with archive.open("resources/zeros.bin", "w", force_zip64=True) as stream:
            block = bytes(1 << 20)
            for _ in range(512):
                stream.write(block)
    assert fmu.stat().st_size < 5 * 2**20
    with pytest.raises(ConfigError, match="more than the cap of 268435456") as raised:
        extract_fmu(fmu)
    assert "zeros.bin" in str(raised.value) and "SONOTRACK_FMU_MAX_BYTES" in str(raised.value)
    assert not cache.exists() or sum(p.stat().st_size for p in cache.rglob("*")
                                     if p.is_file()) == 0


def test_the_cap_is_also_enforced_while_unpacking(cache, tmp_path, monkeypatch):
    """Sizes declared by the archive are not trusted alone: the bytes written are counted."""
    fmu = _fmu(tmp_path / "a.fmu", [("resources/big.bin", bytes(10_000))])
    monkeypatch.setattr("orchestrator.fmu.cache.check_archive",
                        lambda path, limit: zipfile.ZipFile(path).infolist())
    monkeypatch.setenv("SONOTRACK_FMU_MAX_BYTES", "5000")
    with pytest.raises(ConfigError, match="past the cap of 5000"):
        extract_fmu(fmu)
    assert not any(p for p in (cache / "fmus").iterdir())


def test_not_a_zip_is_one_clear_error(cache, tmp_path):
    fake = tmp_path / "fake.fmu"
    fake.write_text("not a zip")
    with pytest.raises(ConfigError, match="not an FMU .cannot read it as a zip"):
        check_archive(fake)


def test_cache_is_by_content_and_reused(cache, tmp_path, monkeypatch):
    fmu = _fmu(tmp_path / "a.fmu")
    first = extract_fmu(fmu)
    assert first.parent == cache / "fmus" and len(first.name) == 64
    assert (first / "binaries" / "linux64" / "model.so").read_bytes()[:4] == b"\x7fELF"
    calls = []
    monkeypatch.setattr("orchestrator.fmu.cache._unpack", lambda *a: calls.append(a))
    copy = tmp_path / "elsewhere" / "same.fmu"
    copy.parent.mkdir()
    copy.write_bytes(fmu.read_bytes())
    assert extract_fmu(copy) == first and calls == []  # same bytes: nothing unpacked again
    monkeypatch.undo()
    monkeypatch.setenv("SONOTRACK_CACHE_DIR", str(cache))
    _fmu(fmu, [("resources/more.txt", "changed")])  # a rebuilt FMU: another entry
    assert extract_fmu(fmu) != first


def test_a_damaged_cache_entry_is_unpacked_again(cache, tmp_path):
    fmu = _fmu(tmp_path / "a.fmu")
    folder = extract_fmu(fmu)
    (folder / "binaries" / "linux64" / "model.so").write_bytes(b"truncated")
    assert extract_fmu(fmu) == folder
    assert (folder / "binaries" / "linux64" / "model.so").stat().st_size == 104


def test_concurrent_extractions_agree(cache, tmp_path):
    fmu = _fmu(tmp_path / "a.fmu", [("resources/big.bin", os.urandom(2_000_000))])
    results, errors = [], []

    def extract():
        try:
            results.append(extract_fmu(fmu))
        except Exception as error:  # noqa: BLE001 - reported below
            errors.append(error)

    threads = [threading.Thread(target=extract) for _ in range(6)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == [] and len(set(results)) == 1
    assert [p.name for p in (cache / "fmus").iterdir()] == [results[0].name]


def test_cache_dir_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("SONOTRACK_CACHE_DIR", str(tmp_path / "c"))
    assert cache_dir() == tmp_path / "c"
    monkeypatch.delenv("SONOTRACK_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert cache_dir() == tmp_path / "x" / "sonotrack"


@pytest.mark.parametrize("loader", ["extract_fmu", "extract_once"])
def test_a_missing_fmu_is_one_clear_error(cache, tmp_path, loader):
    # extract_once stats the file to notice a rebuild in place; a missing file must still be the
    # one-line ConfigError naming it, not a bare FileNotFoundError
    import orchestrator.fmu.handle as fmu_module
    import orchestrator.fmu.cache as extract_module

    load = getattr(fmu_module if loader == "extract_once" else extract_module, loader)
    missing = tmp_path / "gone.fmu"
    with pytest.raises(ConfigError, match=r"gone\.fmu: no such FMU file"):
        load(missing)
