"""``sonotrack sweep`` as a child process, for the tests that kill it: a short scenario and a
sweep started in a session of its own, with an optional pause (:mod:`.process_group`)."""

import os
import shutil
import subprocess
import sys

from orchestrator.builder.fmus import REPO_ROOT
from tests.support.process_group import pause_env

__all__ = ["short_scenario", "start_sweep"]


def short_scenario(folder, stop_time):
    """static_case1 cut to ``stop_time`` in ``folder``, its .ssd beside it (the FMUs then come
    from ``--fmu-dir``); returns the scenario's path."""
    text = (REPO_ROOT / "scenarios" / "static_case1.toml").read_text(encoding="utf-8")
    assert "stop_time = 12.0" in text
    path = folder / "short.toml"
    path.write_text(text.replace("stop_time = 12.0", f'stop_time = {stop_time}\nsystem = '
                                 '"SystemStructure.ssd"'), encoding="utf-8")
    shutil.copy(REPO_ROOT / "fmus" / "SystemStructure.ssd", folder / "SystemStructure.ssd")
    return path


def start_sweep(folder, fmu_dir, pause=None, runs=4, stop_time=1.0, engine=("--workers", "1"),
                pipes=True):
    """Start ``sonotrack sweep`` over seeds 1..``runs`` of :func:`short_scenario`.

    It runs in a new session (its process group is its pid), with its own FMU cache
    (``folder/cache``) and temporary folder (``folder/tmp``), and ``pause`` (``EVENT GLOB NTH``)
    armed if given. Returns (process, scenario path, sweep folder ``folder/sweep``, cache).
    """
    scenario = short_scenario(folder, stop_time)
    out, cache, scratch = folder / "sweep", folder / "cache", folder / "tmp"
    scratch.mkdir()
    extra = {"SONOTRACK_CACHE_DIR": str(cache), "TMPDIR": str(scratch)}
    env = pause_env(pause, **extra) if pause else dict(os.environ, **extra)
    stream = subprocess.PIPE if pipes else subprocess.DEVNULL
    process = subprocess.Popen(
        [sys.executable, "-m", "orchestrator.cli", "sweep", str(scenario), "--seeds",
         f"1..{runs}", *engine, "--out", str(out), "--fmu-dir", str(fmu_dir), "--quiet"],
        cwd=REPO_ROOT, stdout=stream, stderr=stream, env=env, start_new_session=True)
    return process, scenario, out, cache
