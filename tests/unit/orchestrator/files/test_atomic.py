"""The one atomic writer: the old file survives any failure, nothing half-written is left."""

import json
import os
import zipfile

import pytest

from orchestrator.files import atomic
from orchestrator.files.atomic import (
    TEMPORARY_PREFIX, TEMPORARY_SUFFIX, atomic_open, atomic_write_bytes, atomic_write_json,
    atomic_write_text,
)

OLD = b'{"status": "ok", "value": 1.5}\n'


@pytest.fixture
def target(tmp_path):
    path = tmp_path / "summary.json"
    path.write_bytes(OLD)
    return path


class _SerializerBroke(RuntimeError):
    pass


def test_a_writer_that_fails_midway_leaves_the_old_file_whole(target):
    """Half the new bytes are written, then the serializer raises: the old file is intact."""
    with pytest.raises(_SerializerBroke):
        with atomic_open(target) as stream:
            stream.write(b'{"status": "runn')
            stream.flush()
            raise _SerializerBroke("cannot serialise the rest")
    assert target.read_bytes() == OLD
    assert [p.name for p in target.parent.iterdir()] == ["summary.json"]


def test_a_failing_serializer_before_any_write_leaves_the_old_file(target):
    class Unserialisable:
        pass

    with pytest.raises(TypeError):
        atomic_write_json(target, {"status": "running", "value": Unserialisable()})
    assert target.read_bytes() == OLD
    assert [p.name for p in target.parent.iterdir()] == ["summary.json"]


@pytest.mark.parametrize("fsync", [True, False], ids=["fsync", "no-fsync"])
def test_a_failed_rename_leaves_the_old_file_and_no_temporary(target, monkeypatch, fsync):
    def broken_replace(source, destination):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic.os, "replace", broken_replace)
    with pytest.raises(OSError, match="No space left"):
        atomic_write_bytes(target, b'{"status": "runn', fsync=fsync)
    assert target.read_bytes() == OLD
    assert [p.name for p in target.parent.iterdir()] == ["summary.json"]


def test_the_target_is_only_ever_written_by_one_rename_from_a_hidden_partial(target, monkeypatch):
    calls, synced = [], []
    original_replace, original_fsync = os.replace, os.fsync
    monkeypatch.setattr(atomic.os, "replace",
                        lambda a, b: (calls.append((a, b)), original_replace(a, b))[1])
    monkeypatch.setattr(atomic.os, "fsync", lambda fd: (synced.append(fd), original_fsync(fd)))
    atomic_write_text(target, "a,b\n1,2\n")
    assert target.read_text() == "a,b\n1,2\n"
    ((source, destination),) = calls
    assert destination == target and source.parent == target.parent
    assert source.name.startswith(TEMPORARY_PREFIX + "summary.json.")
    assert source.name.endswith(TEMPORARY_SUFFIX)
    assert len(synced) == 2          # the file, then its folder
    synced.clear()
    atomic_write_text(target, "x", fsync=False)
    assert synced == []


def test_new_files_get_an_ordinary_mode_and_zip_archives_can_be_written(tmp_path):
    mask = os.umask(0o022)
    try:
        path = tmp_path / "model.fmu"
        with atomic_open(path, fsync=False) as stream, zipfile.ZipFile(stream, "w") as archive:
            archive.writestr("modelDescription.xml", "<fmiModelDescription/>")
        assert path.stat().st_mode & 0o777 == 0o644
    finally:
        os.umask(mask)
    with zipfile.ZipFile(path) as archive:
        assert archive.read("modelDescription.xml") == b"<fmiModelDescription/>"


def test_json_is_the_indented_text_of_json_dumps_for_finite_values(tmp_path):
    """summary.json is compared byte for byte with a baseline: finite values are unchanged."""
    data = {"status": "ok", "scenario": "s_curve \u00b5", "final_distance_m": 0.123456789,
            "counts": [1, 2, 3], "nested": {"a": None, "b": True, "c": -1e-12}}
    path = tmp_path / "summary.json"
    atomic_write_json(path, data)
    assert path.read_text(encoding="utf-8") == json.dumps(data, indent=2) + "\n"


def test_text_mode_writes_utf8_with_its_line_ends_and_refuses_other_modes(tmp_path):
    path = tmp_path / "sweep.csv"
    with atomic_open(path, "w", newline="") as stream:
        stream.write("a,\u00b5\r\n1,2\n")
    assert path.read_bytes() == "a,\u00b5\r\n1,2\n".encode("utf-8")
    with pytest.raises(ValueError, match="mode = 'a'"):
        with atomic_open(path, "a"):
            pass
