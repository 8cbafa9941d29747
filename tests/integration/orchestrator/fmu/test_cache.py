"""FMUs are unpacked once into the content-addressed cache, never into the temporary folder,
and an unsafe FMU stops `run` and `validate` with one line."""

import os
import shutil
import stat
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration

REPO = Path(__file__).resolve().parents[4]


def _sonotrack(args, tmp_path, cache):
    temporary = tmp_path / "tmpdir"
    temporary.mkdir(exist_ok=True)
    env = {**os.environ, "TMPDIR": str(temporary), "SONOTRACK_CACHE_DIR": str(cache)}
    env.pop("SONOTRACK_FMU_MAX_BYTES", None)
    completed = subprocess.run([sys.executable, "-m", "orchestrator.cli", *args], cwd=REPO,
                               env=env, capture_output=True, text=True, timeout=600)
    return completed, temporary


def _scenario(tmp_path, stop_time=2.0):
    text = (REPO / "scenarios" / "s_curve.toml").read_text()
    lines = [line for line in text.splitlines() if not line.startswith(("stop_time", "system"))]
    path = tmp_path / "short.toml"
    path.write_text(f'stop_time = {stop_time}\nsystem = "{REPO / "fmus" / "SystemStructure.ssd"}"\n'
                    + "\n".join(lines))
    return path


def _snapshot(cache):
    # fmu-locks/ records each use (its files' mtimes order the pruning): not unpacked content
    return {str(p.relative_to(cache)): (p.stat().st_ino, p.stat().st_mtime_ns)
            for p in cache.rglob("*") if "__pycache__" not in p.parts
            and p.relative_to(cache).parts[0] != "fmu-locks"}


def test_runs_leave_the_temporary_folder_empty_and_reuse_the_cache(fmu_dir, tmp_path):
    cache = tmp_path / "cache"
    scenario = _scenario(tmp_path)
    first, temporary = _sonotrack(["run", str(scenario), "--out", str(tmp_path / "a"),
                                   "--fmu-dir", str(fmu_dir), "--quiet"], tmp_path, cache)
    assert first.returncode == 0, first.stderr
    assert list(temporary.iterdir()) == []
    entries = sorted(p.name for p in (cache / "fmus").iterdir())
    assert len(entries) == len(list(fmu_dir.glob("*.fmu")))
    before = _snapshot(cache)
    second, temporary = _sonotrack(["run", str(scenario), "--out", str(tmp_path / "b"),
                                    "--fmu-dir", str(fmu_dir), "--quiet"], tmp_path, cache)
    assert second.returncode == 0, second.stderr
    assert list(temporary.iterdir()) == []
    assert _snapshot(cache) == before  # the second run unpacked nothing


def _tampered(fmu_dir, tmp_path, info, data):
    """A copy of the FMU folder whose SoundSource.fmu carries one more entry."""
    folder = tmp_path / "fmus"
    shutil.copytree(fmu_dir, folder)
    with zipfile.ZipFile(folder / "SoundSource.fmu", "a") as archive:
        archive.writestr(info, data)
    return folder


def _link(name):
    info = zipfile.ZipInfo(name)
    info.external_attr = (stat.S_IFLNK | 0o777) << 16
    return info


@pytest.mark.parametrize("info, reason", [
    ("/tmp/sonotrack-evil.txt", "is an absolute path"),
    ("resources\\evil.txt", "contains a backslash"),
    (_link("resources/passwd"), "is a symbolic link"),
    ("../evil.txt", "contains a '..' component"),
], ids=["absolute", "backslash", "link", "dotdot"])
def test_run_with_an_unsafe_fmu_is_one_line(fmu_dir, tmp_path, info, reason):
    folder = _tampered(fmu_dir, tmp_path, info, "/etc/passwd")
    cache = tmp_path / "cache"
    completed, temporary = _sonotrack(["run", str(_scenario(tmp_path)), "--out",
                                       str(tmp_path / "run"), "--fmu-dir", str(folder),
                                       "--quiet"], tmp_path, cache)
    lines = completed.stderr.strip().splitlines()
    assert completed.returncode == 2, completed.stderr
    assert len(lines) == 1 and "SoundSource.fmu" in lines[0] and reason in lines[0], lines
    assert list(temporary.iterdir()) == []
    assert not Path("/tmp/sonotrack-evil.txt").exists()
    assert not (tmp_path / "run" / "summary.json").exists()


def test_validate_refuses_a_512_mb_zero_entry_and_leaves_nothing(fmu_dir, tmp_path):
    folder = tmp_path / "fmus"
    folder.mkdir()
    bomb = folder / "SoundSource.fmu"
    shutil.copy(fmu_dir / "SoundSource.fmu", bomb)
    with zipfile.ZipFile(bomb, "a", zipfile.ZIP_DEFLATED) as archive:
        with archive.open("resources/zeros.bin", "w", force_zip64=True) as stream:
            block = bytes(1 << 20)
            for _ in range(512):
                stream.write(block)
    cache = tmp_path / "cache"
    completed, temporary = _sonotrack(["validate", str(bomb), "--no-simulate"], tmp_path,
                                      cache)
    assert completed.returncode != 0
    assert "zeros.bin" in completed.stdout and "more than the cap" in completed.stdout
    assert "Traceback" not in completed.stdout + completed.stderr
    left = sum(p.stat().st_size for p in tmp_path.rglob("*") if p.is_file()) - bomb.stat().st_size
    assert left < 1_000_000, left  # nothing of the 512 MB was written anywhere
    assert list(temporary.iterdir()) == []
