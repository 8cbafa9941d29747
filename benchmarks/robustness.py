"""Robustness figures: bad inputs handled, killed runs never stale, no temp leaks, flat memory.

Writes ``benchmarks/results/robustness.json`` with one top-level section per concern, so other
scripts may add theirs (a section this script does not produce, e.g. ``faults``, is kept as it
is when the file is rewritten):

- ``bad_inputs``: every case of the corpus in ``tests/data/bad/`` (its ``manifest.toml``) and
  this script's own cases (unusable ``--out``, unsafe FMU archives, paths leading outside),
  each run through the real CLI in a child process; "handled cleanly" means a non-zero exit,
  one line on stderr (``validate``: its report on stdout), the expected fragment, no
  traceback, no summary saying ok, within 60 s.
- ``kills``: ``sonotrack run`` killed with SIGKILL at random moments into fresh folders and
  into folders holding an older finished run, then resumed (run again into the same folder);
  SIGINT and SIGTERM once each; a sweep killed and resumed. ``stale_outputs_found`` counts
  folders where a summary said ok without a complete run behind it, or an older run's file
  sat beside a newer summary (target 0).
- ``temp_folder``: bytes left in a fresh TMPDIR after 20 runs (target 0).
- ``memory``: peak RSS of a child process running the default scenario for 30 s and for
  3,000 s of simulated time, interleaved pairs (target: ratio within 1.2).

Usage: ``python benchmarks/robustness.py [--only bad_inputs,kills,temp_folder,memory]
[--pairs 3] [--kills 10]``. Needs built FMUs in ``fmus/`` (``make fmus``).
"""

import argparse
import json
import os
import random
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
import tomllib
import zipfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import RESULTS, median  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
FMUS = ROOT / "fmus"
SSD = FMUS / "SystemStructure.ssd"
CORPUS = ROOT / "tests" / "data" / "bad"
SECTIONS = ("bad_inputs", "kills", "temp_folder", "memory")
CASE_TIMEOUT = 60.0


def _cli(args, cwd=ROOT, env=None, timeout=600):
    command = [sys.executable, "-m", "orchestrator.cli", *args]
    started = time.monotonic()
    try:
        completed = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True,
                                   timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, time.monotonic() - started
    return completed, time.monotonic() - started


def _scenario(folder, stop_time, name="s_curve"):
    """The shipped S-curve scenario with another stop time, its system given absolutely."""
    text = (ROOT / "scenarios" / "s_curve.toml").read_text()
    lines = [line for line in text.splitlines()
             if not line.startswith(("stop_time", "system", "name"))]
    path = Path(folder) / f"{name}_{stop_time:g}.toml"
    path.write_text(f"stop_time = {stop_time}\nsystem = \"{SSD}\"\n" + "\n".join(lines) + "\n")
    return path


def _summary(folder):
    try:
        return json.loads((Path(folder) / "summary.json").read_text())
    except (OSError, ValueError):
        return None


# ----- bad inputs -------------------------------------------------------------------------

def _clean(completed, seconds, expect, out, stream="stderr"):
    """Why a bad-input case was not handled cleanly, or None."""
    if completed is None:
        return f"no answer within {CASE_TIMEOUT:g} s"
    text = completed.stdout if stream == "stdout" else completed.stderr
    if completed.returncode == 0:
        return "exit status 0"
    if "Traceback" in completed.stdout + completed.stderr:
        return "traceback"
    if stream == "stderr" and len(completed.stderr.strip().splitlines()) != 1:
        return f"{len(completed.stderr.strip().splitlines())} stderr lines"
    if expect and expect not in text:
        return f"expected {expect!r}, got {text.strip()[-300:]!r}"
    summary = _summary(out) if out is not None else None
    if summary is not None and summary.get("status") == "ok":
        return "a summary says ok"
    return None


def _corpus_cases(work):
    manifest = CORPUS / "manifest.toml"
    if not manifest.is_file():
        return None
    cases = tomllib.loads(manifest.read_text()).get("case", [])
    results = []
    for number, case in enumerate(cases):
        out = work / f"corpus_{number}"
        default = ["run", "{file}", "--quiet", "--out", "{out}", "--fmu-dir", "{fmu_dir}"]
        args = [a.replace("{file}", str((CORPUS / case["file"]).resolve()))
                 .replace("{out}", str(out)).replace("{fmu_dir}", str(FMUS))
                for a in case.get("args", default)]
        completed, seconds = _cli(args, cwd=CORPUS, timeout=CASE_TIMEOUT)
        stream = "stdout" if args[0] == "validate" else "stderr"
        problem = _clean(completed, seconds, case.get("expect", ""), out, stream)
        results.append({"file": case["file"], "kind": case.get("kind"),
                        "seconds": round(seconds, 2), "problem": problem})
    return results


def _tampered_fmus(work, name, info, data=b"x"):
    folder = work / name
    shutil.copytree(FMUS, folder, ignore=shutil.ignore_patterns("*.ssp"))
    with zipfile.ZipFile(folder / "SoundSource.fmu", "a") as archive:
        archive.writestr(info, data)
    return folder


def _own_cases(work):
    """Run-output, archive and path cases (issue 11, points 6, 8, 9)."""
    cases = []
    scenario = _scenario(work, 1.0)
    a_file = work / "a_file"
    a_file.write_text("not a folder")
    cases.append(("--out on a file", ["run", str(scenario), "--out", str(a_file), "--quiet"],
                  "is a file, not a folder", None, "stderr"))
    cases.append(("--out under /proc", ["run", str(scenario), "--out",
                                        "/proc/self/sonotrack-results", "--quiet"],
                  "cannot write there", None, "stderr"))
    link = zipfile.ZipInfo("resources/passwd")
    link.external_attr = (stat.S_IFLNK | 0o777) << 16
    for label, info, reason in [("absolute", "/tmp/sonotrack-evil.txt", "is an absolute path"),
                                ("backslash", "resources\\evil.txt", "contains a backslash"),
                                ("link", link, "is a symbolic link"),
                                ("dotdot", "../evil.txt", "contains a '..' component")]:
        folder = _tampered_fmus(work, f"fmus_{label}", info, "/etc/passwd")
        out = work / f"run_{label}"
        cases.append((f"run --fmu-dir, FMU entry {label}",
                      ["run", str(scenario), "--out", str(out), "--fmu-dir", str(folder),
                       "--quiet"], reason, out, "stderr"))
    bomb_folder = work / "fmus_bomb"
    shutil.copytree(FMUS, bomb_folder, ignore=shutil.ignore_patterns("*.ssp"))
    with zipfile.ZipFile(bomb_folder / "SoundSource.fmu", "a", zipfile.ZIP_DEFLATED) as archive:
        with archive.open("resources/zeros.bin", "w", force_zip64=True) as stream:
            block = bytes(1 << 20)
            for _ in range(512):
                stream.write(block)
    cases.append(("validate, 512 MB zero entry", ["validate", str(bomb_folder / "SoundSource.fmu"),
                                                  "--no-simulate"],
                  "more than the cap", None, "stdout"))
    cases.append(("run --fmu-dir, 512 MB zero entry",
                  ["run", str(scenario), "--out", str(work / "run_bomb"), "--fmu-dir",
                   str(bomb_folder), "--quiet"], "more than the cap", work / "run_bomb",
                  "stderr"))
    study = work / "study"
    study.mkdir()
    (work / "outside.csv").write_text("x,y\n0.3,2.0\n0.8,3.0\n")
    outside = study / "outside.toml"
    outside.write_text(f'stop_time = 1.0\nsystem = "{SSD}"\n[parameters]\n'
                       'source.path = "../outside.csv"\n')
    cases.append(("scenario CSV outside its folder", ["run", str(outside), "--out",
                                                      str(work / "run_outside"), "--quiet"],
                  "--allow-outside", work / "run_outside", "stderr"))
    system = work / "system"
    shutil.copytree(FMUS, system, ignore=shutil.ignore_patterns("*.ssp"))
    text = (system / "SystemStructure.ssd").read_text()
    marker = "<ssd:ParameterBindings>"
    (system / "SystemStructure.ssd").write_text(text.replace(
        marker, marker + '<ssd:ParameterBinding source="../../../../etc/passwd"/>', 1))
    ssv_scenario = work / "ssv_outside.toml"
    ssv_scenario.write_text(f'stop_time = 1.0\nsystem = "{system / "SystemStructure.ssd"}"\n')
    cases.append((".ssv binding to ../../etc/passwd", ["run", str(ssv_scenario), "--out",
                                                       str(work / "run_ssv"), "--quiet"],
                  "--allow-outside", work / "run_ssv", "stderr"))
    results = []
    for label, args, expect, out, stream in cases:
        completed, seconds = _cli(args, timeout=CASE_TIMEOUT)
        problem = _clean(completed, seconds, expect, out, stream)
        results.append({"case": label, "seconds": round(seconds, 2), "problem": problem})
    return results


def bad_inputs(work):
    for name in ("corpus", "own"):
        (work / name).mkdir()
    corpus = _corpus_cases(work / "corpus")
    own = _own_cases(work / "own")
    tried = own + (corpus or [])
    return {
        "corpus": str(CORPUS.relative_to(ROOT)) if corpus is not None else "absent",
        "corpus_cases": len(corpus or []),
        "own_cases": len(own),
        "tried": len(tried),
        "handled_cleanly": sum(1 for case in tried if case["problem"] is None),
        "not_clean": [case for case in tried if case["problem"] is not None],
        "own": own,
    }


# ----- kills -----------------------------------------------------------------------------

def _files(folder):
    return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns, p.stat().st_size)
            for p in Path(folder).iterdir() if p.is_file()}


def _rows(path):
    with open(path, "rb") as stream:
        return max(0, stream.read().count(b"\n") - 1)


def _stale(out, old, stop_time, record_interval=0.02):
    """Stale or lying outputs in a folder after its run stopped: a list of findings."""
    findings = []
    if not out.exists():
        return findings
    now = _files(out)
    summary = _summary(out)
    if "summary.json" in now and summary is None:
        findings.append("summary.json does not parse")
    if summary is not None and summary.get("status") == "ok":
        complete = int(round(stop_time / record_interval)) + 1
        if summary.get("sim_time_s") != stop_time or _rows(out / "results.csv") != complete:
            findings.append("summary ok without a complete results.csv")
    if "summary.json" in now and now["summary.json"] != old.get("summary.json"):
        stale = sorted(name for name, stamp in now.items() if old.get(name) == stamp)
        findings += [f"older run's {name} beside a new summary" for name in stale]
    elif "summary.json" in now:
        changed = sorted(name for name in old if now.get(name) != old[name])
        findings += [f"{name} changed under the older run's summary" for name in changed]
    return findings


def _run_process(scenario, out, *extra):
    return subprocess.Popen([sys.executable, "-m", "orchestrator.cli", "run", str(scenario),
                             "--out", str(out), "--quiet", *extra], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def kills(work, count, seed=11):
    stop_time = 30.0
    scenario = _scenario(work, stop_time)
    finished = work / "finished"
    started = time.monotonic()
    completed, _ = _cli(["run", str(scenario), "--out", str(finished), "--quiet"])
    duration = time.monotonic() - started
    assert completed.returncode == 0, completed.stderr
    rng = random.Random(seed)
    record = {"sigkill_fresh": 0, "sigkill_existing": 0, "killed_before_finish": 0,
              "resumed": 0, "resumed_ok": 0, "signals": {}, "sweep": None,
              "stale_outputs_found": 0, "target_stale": 0, "findings": [],
              "full_run_seconds": round(duration, 2)}
    for attempt in range(count):
        existing = attempt % 2 == 1
        out = work / f"kill_{attempt}"
        if existing:
            shutil.copytree(finished, out)
        old = _files(out) if existing else {}
        process = _run_process(scenario, out)
        try:
            process.wait(timeout=rng.uniform(0.2, 1.0) * duration)
        except subprocess.TimeoutExpired:
            process.send_signal(signal.SIGKILL)
        process.communicate()
        record["sigkill_existing" if existing else "sigkill_fresh"] += 1
        record["killed_before_finish"] += process.returncode != 0
        findings = _stale(out, old, stop_time)
        # resume: run again into the same folder; it must finish ok with nothing stale
        before = _files(out) if out.exists() else {}
        completed, seconds = _cli(["run", str(scenario), "--out", str(out), "--quiet"])
        duration = seconds  # the machine's load moves: aim the next kill at this run's length
        record["resumed"] += 1
        summary = _summary(out)
        ok = completed.returncode == 0 and summary is not None and summary["status"] == "ok"
        record["resumed_ok"] += ok
        findings += [f"after resume: {f}" for f in _stale(out, before, stop_time)]
        if findings:
            record["findings"].append({"attempt": attempt, "existing": existing,
                                       "findings": findings})
            record["stale_outputs_found"] += 1
    long_scenario = _scenario(work, 3000.0)
    for number in (signal.SIGINT, signal.SIGTERM):
        out = work / f"signal_{number}"
        process = _run_process(long_scenario, out)
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not (
                (out / "results.csv").exists() and _rows(out / "results.csv") > 100):
            time.sleep(0.05)
        process.send_signal(number)
        _, stderr = process.communicate(timeout=120)
        summary = _summary(out) or {}
        record["signals"][signal.Signals(number).name] = {
            "exit_status": process.returncode, "stderr_lines": len(stderr.strip().splitlines()),
            "summary_status": summary.get("status"), "sim_time_s": summary.get("sim_time_s"),
            "rows_kept": _rows(out / "results.csv")}
    record["sweep"] = _killed_sweep(work)
    return record


def _killed_sweep(work):
    """A sweep of 6 runs killed after its first finished run, then resumed."""
    scenario = _scenario(work, 5.0, "sweep")
    out = work / "sweep"
    args = [sys.executable, "-m", "orchestrator.cli", "sweep", str(scenario), "--set",
            "planner.v_cruise=0.2,0.22,0.24,0.26,0.28,0.3", "--out", str(out), "--workers", "2",
            "--quiet"]
    # a session of its own, so the sweep and the workers it started die together
    process = subprocess.Popen(args, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, start_new_session=True)
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and process.poll() is None:
        done = [p for p in (out / "runs").glob("*/summary.json")
                if (_summary(p.parent) or {}).get("status") == "ok"] if out.exists() else []
        if done:
            break
        time.sleep(0.05)
    killed = process.poll() is None
    if killed:
        os.killpg(process.pid, signal.SIGKILL)  # the group this script started
    process.communicate()
    finished_before = sum(1 for p in (out / "runs").glob("*/summary.json")
                          if (_summary(p.parent) or {}).get("status") == "ok")
    resumed = subprocess.run(args, cwd=ROOT, capture_output=True, text=True, timeout=900)
    table = []
    if (out / "sweep.json").exists():
        table = json.loads((out / "sweep.json").read_text())
    return {"killed": killed, "ok_runs_when_killed": finished_before,
            "resume_exit_status": resumed.returncode, "resume_says": resumed.stdout.strip(),
            "rows": len(table), "rows_ok": sum(1 for r in table if r.get("status") == "ok")}


# ----- temporary folder ------------------------------------------------------------------

def temp_folder(work, runs=20):
    temporary = work / "tmpdir"
    temporary.mkdir()
    cache = work / "cache"
    env = {**os.environ, "TMPDIR": str(temporary), "SONOTRACK_CACHE_DIR": str(cache)}
    scenario = _scenario(work, 1.0)
    failures = 0
    for number in range(runs):
        completed, _ = _cli(["run", str(scenario), "--out", str(work / f"run_{number}"),
                             "--quiet"], env=env)
        failures += completed is None or completed.returncode != 0
    left = [p for p in temporary.rglob("*")]
    return {"runs": runs, "failed_runs": failures,
            "bytes_left": sum(p.stat().st_size for p in left if p.is_file()),
            "entries_left": len(left), "target_bytes": 0,
            "cache_bytes": sum(p.stat().st_size for p in cache.rglob("*") if p.is_file()),
            "cache_entries": len(list((cache / "fmus").iterdir()))}


# ----- memory -----------------------------------------------------------------------------

_MEMORY_CHILD = """
import sys
from orchestrator.run.runner import run_scenario
run_scenario(sys.argv[1], sys.argv[2], progress=False)
"""


def _peak_rss_mb(scenario, out):
    process = subprocess.Popen([sys.executable, "-c", _MEMORY_CHILD, str(scenario), str(out)],
                               cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    started = time.monotonic()
    _, status, usage = os.wait4(process.pid, 0)
    seconds = time.monotonic() - started
    if status != 0:
        raise RuntimeError(f"memory run of {scenario} failed: {process.stderr.read()!r}")
    return usage.ru_maxrss / 1024.0, seconds  # Linux reports kilobytes


def memory(work, pairs):
    short, long = _scenario(work, 30.0), _scenario(work, 3000.0)
    samples = {"30": [], "3000": []}
    seconds = {"30": [], "3000": []}
    for pair in range(pairs):
        order = [("30", short), ("3000", long)]
        if pair % 2:
            order.reverse()
        for label, scenario in order:
            rss, wall = _peak_rss_mb(scenario, work / f"mem_{label}_{pair}")
            samples[label].append(rss)
            seconds[label].append(wall)
    ratios = [b / a for a, b in zip(samples["30"], samples["3000"])]
    rows = _rows(work / "mem_3000_0" / "results.csv")
    return {
        "peak_rss_mb_30s": round(median(samples["30"]), 1),
        "peak_rss_mb_3000s": round(median(samples["3000"]), 1),
        "ratio_3000s_to_30s": round(median(ratios), 3),
        "ratios": [round(r, 3) for r in ratios],
        "samples_mb": {k: [round(v, 1) for v in vs] for k, vs in samples.items()},
        "wall_seconds": {k: [round(v, 1) for v in vs] for k, vs in seconds.items()},
        "rows_at_3000s": rows,
        "results_csv_mb_at_3000s": round(
            (work / "mem_3000_0" / "results.csv").stat().st_size / 2**20, 1),
        "target_ratio": 1.2,
        "met": median(ratios) <= 1.2,
        "how": "one child process per run (default s_curve scenario, plots on), ru_maxrss from "
               "os.wait4; interleaved pairs, median of the per-pair ratios",
    }


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", help=f"comma-separated sections of {', '.join(SECTIONS)}")
    parser.add_argument("--pairs", type=int, default=3, help="memory: interleaved pairs")
    parser.add_argument("--kills", type=int, default=10, help="SIGKILLs (half into old runs)")
    args = parser.parse_args(argv)
    chosen = args.only.split(",") if args.only else list(SECTIONS)
    if not all((FMUS / f"{name}.fmu").is_file() for name in
               ("SoundSource", "AcousticLocalizer", "CurvaturePlanner", "WheelController",
                "RobotPlant")):
        sys.exit("build the FMUs first: make fmus")
    path = RESULTS / "robustness.json"
    record = {}
    work = Path(tempfile.mkdtemp(prefix="sonotrack_robustness_"))
    try:
        for name in chosen:
            started = time.monotonic()
            folder = work / name
            folder.mkdir()
            if name == "bad_inputs":
                record[name] = bad_inputs(folder)
            elif name == "kills":
                record[name] = kills(folder, args.kills)
            elif name == "temp_folder":
                record[name] = temp_folder(folder)
            elif name == "memory":
                record[name] = memory(folder, args.pairs)
            else:
                sys.exit(f"unknown section {name!r}; sections: {', '.join(SECTIONS)}")
            record[name]["benchmark_seconds"] = round(time.monotonic() - started, 1)
            record[name]["measured_utc"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
            print(json.dumps({name: {k: v for k, v in record[name].items()
                                     if k not in ("own", "findings")}}, indent=2))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    record["generated_utc"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    record["machine"] = {"python": sys.version.split()[0], "cpus": os.cpu_count(),
                         "load_average_1min": os.getloadavg()[0]}
    RESULTS.mkdir(parents=True, exist_ok=True)
    from orchestrator.run.folder import atomic_write_json

    # read just before writing: sections written meanwhile by another script (e.g. faults)
    # or by another run of this one (other --only sections) are kept
    try:
        kept = json.loads(path.read_text())
    except (OSError, ValueError):
        kept = {}
    kept.update(record)
    atomic_write_json(path, kept)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
