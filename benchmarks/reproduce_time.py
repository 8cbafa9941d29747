"""Wall time of the full paper reproduction (target: within 10 minutes on two idle cores).

Builds the FMUs from this checkout into a fresh folder, then times, as a user's shell would,
one whole ``sonotrack reproduce --out DIR --workers 2 --quiet --fmu-dir FMUS`` into an empty
folder (interpreter start-up, every run computed, the verdicts, figures and reports, exit).
Recorded beside it: the load average before the start (the target is for idle cores), the
command's own figures from reproduction.json (runs planned and computed, failed runs, the run
phase, the wall time by its own clock), the simulated CPU time of the runs (free field and
room) from the sweep's table, and the verdict counts, so a time is never read apart from what
was computed in it.

One measurement per call (a full study is 8-10 minutes); run it on an idle machine.

Writes benchmarks/results/reproduce_time.json.

    python benchmarks/reproduce_time.py [--runs 20] [--workers 2]
"""

import argparse
import collections
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import build_fresh, write_result  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
FMUS = ["RobotPlant", "SoundSource", "AcousticLocalizer", "CurvaturePlanner", "WheelController"]
TARGET_S = 600.0


def _environment():
    # as a user's shell runs Python: bytecode cached (this session's environment turns it off)
    return {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def _simulation_seconds(table):
    """Sum of the runs' own wall times in the sweep's table: (all, room, room runs)."""
    rows = list(csv.DictReader(table.open()))
    seconds = [(r["cell"].startswith("room:"), float(r["wall_time_s"] or 0.0)) for r in rows]
    room = [s for is_room, s in seconds if is_room]
    return sum(s for _, s in seconds), sum(room), len(room)


def measure(runs, workers):
    fmu_dir = Path(next(iter(build_fresh(FMUS).values()))).parent
    out = Path(tempfile.mkdtemp(prefix="sonotrack_reproduce_time_")) / "study"
    command = [sys.executable, "-m", "orchestrator.cli", "reproduce", "--out", str(out),
               "--runs", str(runs), "--workers", str(workers), "--quiet",
               "--fmu-dir", str(fmu_dir)]
    load_before = os.getloadavg()
    started = time.perf_counter()
    completed = subprocess.run(command, cwd=ROOT, capture_output=True, text=True,
                               env=_environment())
    wall = time.perf_counter() - started
    if completed.returncode != 0:
        raise SystemExit(f"reproduce failed (exit {completed.returncode}): "
                         f"{completed.stderr.strip().splitlines()[-1:]}")
    report = json.loads((out / "reproduction.json").read_text())
    settings = report["settings"]
    simulated, room, room_runs = _simulation_seconds(out / "runs" / "sweep.csv")
    verdicts = collections.Counter(c["verdict"] for c in report["claims"] if c["tally"])
    shutil.rmtree(out.parent)  # 1960 runs' records: read, not kept
    return {
        "command": " ".join(["sonotrack"] + command[3:]),
        "wall_s": wall,
        "target_s": TARGET_S,
        "within_target": wall <= TARGET_S,
        "load_average_before": list(load_before),
        "load_average_after": list(os.getloadavg()),
        "cpus": os.cpu_count(),
        "runs_total": settings["runs_total"],
        "runs_computed": settings["runs_computed"],
        "runs_reused": settings["runs_reused"],
        "failed_runs": {"free field": settings["failed_runs"],
                        "room": report["free_field_and_room"]["failed_runs"]},
        "command_wall_s": settings["wall_time_s"],
        "run_phase_s": settings["run_time_s"],
        "after_runs_s": settings["wall_time_s"] - settings["run_time_s"],
        "simulation_s": simulated,
        "simulation_room_s": room,
        "room_runs": room_runs,
        "tallied_verdicts": dict(verdicts),
        "stderr_last_lines": completed.stderr.strip().splitlines()[-3:],
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=20, help="runs per cell (default 20)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    args = parser.parse_args()
    record = measure(args.runs, args.workers)
    path = write_result("reproduce_time", record)
    print(f"reproduce: {record['runs_computed']} runs in {record['wall_s']:.0f} s wall "
          f"(target {TARGET_S:.0f} s; load before {record['load_average_before'][0]:.2f}) "
          f"-> {path}")


if __name__ == "__main__":
    main()
