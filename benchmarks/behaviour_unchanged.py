"""Does a change leave behaviour unchanged? Two revisions' FMUs and shipped runs, byte for byte.

For a base revision (default ``e07e903``, main before the layer layout) and the working tree
(or ``--head REV``), this script builds the FMUs of each from its own sources, runs the four
shipped scenarios (``s_curve``, ``straight``, ``static_case1``, ``dynamic_case2``) without
plots, and compares:

- ``results.csv``: byte for byte;
- ``summary.json``: every figure, except the two that measure the machine (``wall_time_s``,
  ``realtime_factor``) and the record of the process that ran it (``process``: its id, host and
  start time differ at every run);
- every FMU's ``modelDescription.xml``: byte for byte once ``guid`` and
  ``generationDateAndTime`` are masked (the GUID names the FMU's code, so two revisions
  whose code differs differ there even where the behaviour does not; builds before commit
  d19c9b9 also drew a time-based GUID and stamped the build time);
- ``fmus/SystemStructure.ssd`` as committed, and as the generator writes it now.

A revision is checked out with ``git worktree`` and run with this checkout's virtual
environment, its own sources first on ``sys.path``; its FMI binary is compiled by its own
Makefile. Prints one line per compared file, writes ``benchmarks/results/behaviour_unchanged.json``
and exits with the number of differences.

    .venv/bin/python benchmarks/behaviour_unchanged.py                 # e07e903 vs working tree
    .venv/bin/python benchmarks/behaviour_unchanged.py --base HEAD~3 --head HEAD
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SCENARIOS = ("s_curve", "straight", "static_case1", "dynamic_case2")
# Differ at every run: the machine's speed, and which process ran (orchestrator.processes).
MACHINE_FIGURES = {"wall_time_s", "realtime_factor", "process"}
_BUILD_STAMPS = re.compile(rb'(guid|generationDateAndTime)="[^"]*"')


def _run(command, cwd, **kwargs):
    env = dict(os.environ, PYTHONPATH=str(cwd), MPLBACKEND="Agg")
    done = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, **kwargs)
    if done.returncode:
        raise SystemExit(f"{' '.join(map(str, command))} failed in {cwd}:\n{done.stderr[-2000:]}")
    return done.stdout


def produce(tree, out):
    """Build ``tree``'s FMUs and run the shipped scenarios into ``out``; return ``out``."""
    python = sys.executable
    bin_dir = Path(python).parent
    # -o: the venv is this checkout's; the tree's Makefile must not make one of its own.
    _run(["make", "-s", "-o", ".venv/.installed", f"BIN={bin_dir}", "fmi-binary"], tree)
    out.mkdir(parents=True, exist_ok=True)
    # The scenarios' system is the tree's fmus/SystemStructure.ssd, beside the FMUs it names.
    fmus = tree / "fmus"
    _run([python, "-m", "orchestrator.cli", "build", "--out", str(fmus)], tree)
    for fmu in sorted(fmus.glob("*.fmu")):
        with zipfile.ZipFile(fmu) as archive:
            text = archive.read("modelDescription.xml")
        (out / f"{fmu.stem}.modelDescription.xml").write_bytes(_BUILD_STAMPS.sub(rb'\1="-"', text))
    shutil.copy(tree / "fmus" / "SystemStructure.ssd", out / "SystemStructure.ssd")
    _run([python, "-m", "orchestrator.ssp", str(out / "generated.ssd")], tree)
    for name in SCENARIOS:
        run_dir = out / name
        _run([python, "-m", "orchestrator.cli", "run", str(tree / "scenarios" / f"{name}.toml"),
              "--out", str(run_dir), "--no-plots"], tree)
        summary = json.loads((run_dir / "summary.json").read_text())
        for key in MACHINE_FIGURES:
            summary.pop(key, None)
        (run_dir / "summary.figures.json").write_text(json.dumps(summary, indent=1, sort_keys=True))
    return out


def compared_files(folder):
    names = [p.name for p in sorted(folder.glob("*.modelDescription.xml"))]
    names += ["SystemStructure.ssd", "generated.ssd"]
    for name in SCENARIOS:
        names += [f"{name}/results.csv", f"{name}/summary.figures.json"]
    return names


def compare(base, head):
    """One row per file: (name, 'same' / 'DIFFERENT' / 'missing in ...')."""
    rows = []
    for name in sorted(set(compared_files(base)) | set(compared_files(head))):
        a, b = base / name, head / name
        if not a.exists() or not b.exists():
            rows.append((name, f"missing in {'base' if not a.exists() else 'head'}"))
        else:
            rows.append((name, "same" if a.read_bytes() == b.read_bytes() else "DIFFERENT"))
    return rows


def checkout(rev, into):
    subprocess.run(["git", "worktree", "add", "--detach", str(into), rev], cwd=REPO, check=True,
                   capture_output=True)
    return into


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", default="e07e903", help="revision compared against")
    parser.add_argument("--head", default=None, help="revision to check (default: working tree)")
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results"
                        / "behaviour_unchanged.json")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="sonotrack_same_") as scratch:
        scratch = Path(scratch)
        trees = []
        try:
            base_tree = checkout(args.base, scratch / "base_tree")
            trees.append(base_tree)
            if args.head:
                head_tree = checkout(args.head, scratch / "head_tree")
                trees.append(head_tree)
            else:
                head_tree = REPO
            print(f"building and running {args.base} ...", flush=True)
            base = produce(base_tree, (scratch / "base").resolve())
            print(f"building and running {args.head or 'the working tree'} ...", flush=True)
            head = produce(head_tree, (scratch / "head").resolve())
            rows = compare(base, head)
        finally:
            for tree in trees:
                subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=REPO,
                               capture_output=True)
    for name, verdict in rows:
        print(f"{verdict:>10}  {name}")
    different = [name for name, verdict in rows if verdict != "same"]
    head_rev = args.head or subprocess.run(["git", "describe", "--always", "--dirty"], cwd=REPO,
                                           capture_output=True, text=True).stdout.strip()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"base": args.base, "head": head_rev,
                                    "files_compared": len(rows), "different": different,
                                    "rows": dict(rows)}, indent=1) + "\n")
    print(f"{len(rows) - len(different)} of {len(rows)} files the same; written {args.out}")
    return len(different)


if __name__ == "__main__":
    sys.exit(main())
