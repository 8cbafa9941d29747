"""Run the bad-input corpus (tests/data/bad/manifest.toml) through ``sonotrack``'s entry point.

``python -m tests.support.bad_inputs FMU_DIR OUT_DIR`` runs every case in this one process
(importing the CLI once instead of 60 times), each through :func:`orchestrator.cli.main` with
stdout and stderr captured and a time limit, and prints one JSON object per case: exit status,
stdout, stderr, seconds, whether it hit the limit and whether an exception escaped ``main``.
Also used by ``benchmarks/robustness.py``.
"""

import contextlib
import io
import json
import os
import signal
import sys
import time
import tomllib
import traceback
from pathlib import Path

__all__ = ["CORPUS", "load_cases", "case_arguments", "run_case"]

CORPUS = Path(__file__).resolve().parent.parent / "data" / "bad"
DEFAULT_ARGS = ["run", "{file}", "--quiet", "--out", "{out}", "--fmu-dir", "{fmu_dir}"]
TIME_LIMIT = 60   # seconds per case


def load_cases():
    """The manifest's cases, each a dict (``file``, ``kind``, ``point``, ``expect``, ``args``)."""
    with open(CORPUS / "manifest.toml", "rb") as stream:
        return tomllib.load(stream)["case"]


def case_arguments(case, fmu_dir, out):
    """The command line of one case, placeholders filled in."""
    values = {"file": str(CORPUS / case["file"]), "out": str(out), "fmu_dir": str(fmu_dir)}
    return [a.format(**values) for a in case.get("args", DEFAULT_ARGS)]


class _TimeLimit(BaseException):
    pass


def run_case(argv, limit=TIME_LIMIT):
    """Call ``main(argv)``; return exit status, captured output and what went wrong."""
    from orchestrator.cli import main

    def expire(signum, frame):
        raise _TimeLimit()

    out, err = io.StringIO(), io.StringIO()
    result = {"argv": argv, "status": None, "escaped": None, "timed_out": False}
    previous = signal.signal(signal.SIGALRM, expire)
    signal.alarm(limit)
    started = time.perf_counter()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            result["status"] = main(argv)
    except SystemExit as exit_:   # argparse exits
        result["status"] = exit_.code if isinstance(exit_.code, int) else 1
    except _TimeLimit:
        result["timed_out"] = True
    except BaseException:   # anything main let through is a defect of the CLI
        result["escaped"] = traceback.format_exc()
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    result.update(stdout=out.getvalue(), stderr=err.getvalue(),
                  seconds=time.perf_counter() - started)
    return result


def _main(fmu_dir, out_dir):
    os.chdir(CORPUS)   # CSV paths in the corpus scenarios are relative to it
    for index, case in enumerate(load_cases()):
        argv = case_arguments(case, fmu_dir, Path(out_dir) / f"case{index}")
        print(json.dumps({"index": index, **run_case(argv)}), flush=True)


if __name__ == "__main__":
    _main(*sys.argv[1:3])
