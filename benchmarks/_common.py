"""Helpers shared by the benchmark scripts: fresh FMU builds, medians, JSON output."""

import json
import platform
import statistics
import tempfile
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def build_fresh(names):
    """Build the named FMUs from this checkout into a temporary folder; return {name: path}."""
    from orchestrator.builder.fmus import build_fmu

    out = Path(tempfile.mkdtemp(prefix="sonotrack_bench_"))
    return {name: build_fmu(name, out) for name in names}


def median(values):
    return float(statistics.median(values))


def write_result(name, record):
    """Write ``record`` (plus machine info) to benchmarks/results/<name>.json and return the path."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    record = dict(record)
    record.setdefault("machine", {"python": platform.python_version(),
                                  "processor": platform.machine(),
                                  "cpus": __import__("os").cpu_count()})
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps(record, indent=2) + "\n")
    return path
