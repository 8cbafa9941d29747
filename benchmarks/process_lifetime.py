"""How long what a killed command started outlives it: ``kill -9`` at a random moment.

Each case starts a real command in a session of its own (its process group then holds all it
starts), waits until its children exist, waits a random further delay (so the kill lands in
different phases: warm-up, runs, table writes, drawing), sends SIGKILL to the command alone and
measures, polling ``/proc`` every millisecond, until no process of the group runs (zombies count
as ended). Also recorded per kill: whether the command's stdout read to end-of-file within 3 s,
and how many FMU cache locks were still held 3 s after the kill.

Cases:

* ``sweep``: ``sonotrack sweep`` (static_case1 cut to 3 s, seeds 1..12, ``--workers 2``);
  its workers end by the parent-death signal (and the lifeline);
* ``sweep-lifeline``: a local engine started from a thread (so the parent-death signal is not
  armed) running 2 workers: its workers end by the lifeline pipe alone;
* ``run``: ``sonotrack run`` (static_case1, plots on): the plot renderer, warming up or
  drawing;
* ``libcosim``: a caller of ``run_libcosim_ssd`` on a long run: libcosim's child.

Writes benchmarks/results/process_lifetime.json.

    .venv/bin/python benchmarks/process_lifetime.py [--repeats 10] [--seed 26]
"""

import argparse
import fcntl
import json
import os
import random
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import median, write_result  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
PYTHON = sys.executable

_LIFELINE_ONLY = """
import threading, time
from orchestrator.sweep.engine import LocalEngine
engine = LocalEngine(workers=2)
starter = threading.Thread(target=engine.start)
starter.start()
starter.join()
engine.run(time.sleep, [("a", 0.3), ("b", 0.3)], lambda key, result: None)
print("ready", flush=True)
time.sleep(600)
"""

_LIBCOSIM = """
import sys
from orchestrator.hosts.libcosim import run_libcosim_ssd
run_libcosim_ssd(sys.argv[1], 0.01, 600.0, ["plant.x"])
"""


def _group(pgid):
    """Pids of the running (not zombie) processes of group ``pgid``."""
    found = []
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            with open(f"/proc/{entry.name}/stat", "rb") as stream:
                text = stream.read()
        except OSError:
            continue
        fields = text[text.rfind(b")") + 2:].split()
        if int(fields[2]) == pgid and fields[0] not in (b"Z", b"X"):
            found.append(int(entry.name))
    return found


def _held_locks(cache):
    held = 0
    for path in Path(cache, "fmu-locks").glob("*.lock"):
        fd = os.open(path, os.O_RDWR)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            held += 1
        finally:
            os.close(fd)
    return held


def _eof_within(stream, seconds):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        readable, _, _ = select.select([stream], [], [], max(0.0, deadline - time.monotonic()))
        if readable and not os.read(stream.fileno(), 65536):
            return True
    return False


def _scenario(folder):
    text = (REPO / "scenarios" / "static_case1.toml").read_text(encoding="utf-8")
    path = folder / "short.toml"
    path.write_text(text.replace("stop_time = 12.0", 'stop_time = 3.0\nsystem = '
                                 '"SystemStructure.ssd"'), encoding="utf-8")
    shutil.copy(REPO / "fmus" / "SystemStructure.ssd", folder / "SystemStructure.ssd")
    return path


def _command(case, folder):
    """(argv, line to wait for on stdout or None)."""
    if case == "sweep":
        return ([PYTHON, "-m", "orchestrator.cli", "sweep", str(_scenario(folder)), "--seeds",
                 # enough runs that a kill within the first seconds lands mid-sweep on an
                 # idle machine too (12 short runs end in about a second there)
                 "1..200", "--workers", "2", "--out", str(folder / "sweep"), "--fmu-dir",
                 str(REPO / "fmus"), "--quiet"], None)
    if case == "sweep-lifeline":
        return [PYTHON, "-c", _LIFELINE_ONLY], "ready"
    if case == "run":
        return ([PYTHON, "-m", "orchestrator.cli", "run", str(_scenario(folder)), "--out",
                 str(folder / "run"), "--fmu-dir", str(REPO / "fmus"), "--quiet"], None)
    if case == "libcosim":
        ssd = REPO / "fmus" / "SystemStructure.ssd"
        return [PYTHON, "-c", _LIBCOSIM, str(ssd)], None
    raise ValueError(case)


def kill_once(case, rng):
    """One kill of ``case``; returns a dict of what was measured."""
    with tempfile.TemporaryDirectory(prefix="sonotrack_kill_") as folder:
        folder = Path(folder)
        cache = folder / "cache"
        argv, ready = _command(case, folder)
        env = dict(os.environ, SONOTRACK_CACHE_DIR=str(cache), TMPDIR=str(folder))
        process = subprocess.Popen(argv, cwd=REPO, stdout=subprocess.PIPE,
                                   stderr=subprocess.DEVNULL, env=env, start_new_session=True)
        try:
            if ready:
                assert process.stdout.readline().decode().strip() == ready
            while len(_group(process.pid)) < 2 and process.poll() is None:
                time.sleep(0.005)
            delay = rng.uniform(0.0, 1.5)
            time.sleep(delay)
            children = len(_group(process.pid)) - 1
            if process.poll() is not None or children < 1:
                return {"case": case, "delay_s": delay, "killed": False}
            os.kill(process.pid, signal.SIGKILL)
            killed = time.monotonic()
            process.wait()
            while _group(process.pid) and time.monotonic() - killed < 10.0:
                time.sleep(0.001)
            gone_s = time.monotonic() - killed
            left = len(_group(process.pid))
            eof = _eof_within(process.stdout, 3.0)
            time.sleep(max(0.0, 3.0 - (time.monotonic() - killed)))
            locks = _held_locks(cache) if cache.exists() else 0
            return {"case": case, "delay_s": round(delay, 3), "killed": True,
                    "children": children, "gone_s": round(gone_s, 4), "left_after_10_s": left,
                    "stdout_eof": eof, "locks_held_after_3_s": locks}
        finally:
            for pid in _group(process.pid):
                os.kill(pid, signal.SIGKILL)
            if process.poll() is None:
                process.kill()
            process.wait()


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=10, help="kills per case")
    parser.add_argument("--seed", type=int, default=26, help="seed of the random kill delays")
    parser.add_argument("--cases", default="sweep,sweep-lifeline,run,libcosim")
    args = parser.parse_args(argv)
    if not sys.platform.startswith("linux"):
        raise SystemExit("process_lifetime.py reads /proc: Linux only")
    rng = random.Random(args.seed)
    kills = []
    for _ in range(args.repeats):
        for case in args.cases.split(","):
            kills.append(kill_once(case, rng))
            print(json.dumps(kills[-1]), flush=True)
    summary = {}
    for case in args.cases.split(","):
        done = [k for k in kills if k["case"] == case and k["killed"]]
        times = sorted(k["gone_s"] for k in done)
        summary[case] = {
            "kills": len(done),
            # a command that ended before its kill proves nothing: counted, never "all gone"
            "ended_before_the_kill": sum(1 for k in kills if k["case"] == case
                                         and not k["killed"]),
            "gone_s_median": round(median(times), 4) if times else None,
            "gone_s_max": times[-1] if times else None,
            "all_gone": bool(done) and all(k["left_after_10_s"] == 0 for k in done),
            "stdout_eof_every_time": all(k["stdout_eof"] for k in done),
            "locks_held_after_3_s_max": max((k["locks_held_after_3_s"] for k in done),
                                            default=0),
        }
        print(f"{case:>15}: {summary[case]}")
    path = write_result("process_lifetime", {
        "command": "benchmarks/process_lifetime.py " + " ".join(argv or sys.argv[1:]),
        "load_average": os.getloadavg(), "summary": summary, "kills": kills})
    print(f"written {path}")
    return 0 if all(s["all_gone"] and s["gone_s_max"] is not None and s["gone_s_max"] < 1.0
                    for s in summary.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
