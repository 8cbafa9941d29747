"""ecos as a third host: run FMUs and .ssd files in the C++ engine of the ``ecospy`` wheel.

Used by the tests (tests/integration/orchestrator/hosts/test_ecos.py) and benchmarks/ssd_hosts.py, as
:mod:`orchestrator.hosts.libcosim` is for libcosim.

ecos is a non-Python host: its command line ``ecos simulate`` loads the FMUs' shared libraries
itself and writes every variable of every instance to a CSV file (values printed by
``std::to_string``, so six decimals). The wheel installs the binary without its executable bit,
so it is copied to a temporary folder first. It needs Debian's ``libtbb12`` (``make tbb``).
"""

import csv
import os
import shutil
import subprocess
from pathlib import Path

from orchestrator.processes import tied_command

__all__ = ["ecos_binary", "ecos_environment", "run_ecos", "read_ecos_csv"]


def ecos_binary(folder):
    """Copy ecospy's ``ecos`` binary into ``folder`` and check it starts.

    Returns
    -------
    (path, None) when it runs, (None, reason) when it cannot (not installed, library missing).
    """
    try:
        import ecospy
    except ImportError as error:
        return None, f"ecospy is not installed ({error})"
    source = Path(ecospy.__file__).parent / "binaries" / "ecos"
    if not source.is_file():
        return None, f"ecospy ships no Linux ecos binary at {source}"
    target = Path(folder) / "ecos"
    shutil.copy2(source, target)
    target.chmod(0o755)
    completed = subprocess.run([str(target), "--version"], capture_output=True, text=True)
    if completed.returncode != 0:
        return None, (f"ecos does not start (status {completed.returncode}): "
                      f"{(completed.stderr or completed.stdout).strip()[-300:]}")
    return target, None


def ecos_environment():
    """Environment for the ecos child process: the caller's, with nothing added.

    sonotrack's FMI binary loads the libpython and the Python recorded at build time when the
    host has none, so a non-Python host needs no ``LD_PRELOAD`` or ``PYTHONPATH``; both are
    removed here so that the test cannot pass because of them.
    """
    environment = dict(os.environ)
    environment.pop("LD_PRELOAD", None)
    environment.pop("PYTHONPATH", None)
    return environment


def run_ecos(binary, path, stop_time, step, out_dir, parameter_set=None, timeout=600):
    """Run ``ecos simulate`` on an FMU or a folder holding ``SystemStructure.ssd``.

    Returns
    -------
    completed : subprocess.CompletedProcess
    csv_path : pathlib.Path or None
        The CSV ecos wrote (named after the FMU or folder), None if none.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    command = [str(binary), "simulate", "--path", str(path), "--stopTime", repr(stop_time),
               "--stepSize", repr(step), "--noParallel"]
    if parameter_set is not None:
        command += ["--parameterSet", parameter_set]
    # tied: ecos ends with this process, however it dies (docs/process_lifetime.md)
    completed = subprocess.run(tied_command(command), cwd=out_dir, capture_output=True,
                               text=True, env=ecos_environment(), timeout=timeout)
    found = sorted(out_dir.glob("*.csv"))
    return completed, (found[0] if found else None)


def read_ecos_csv(path):
    """Read an ecos CSV: ``{"time": [...], "instance.variable": [...]}`` with typed values."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f, skipinitialspace=True))
    header, data = rows[0], rows[1:]
    columns = {}
    for i, title in enumerate(header):
        if title in ("iterations", "time"):
            columns[title] = [float(row[i]) for row in data]
            continue
        name, kind = title.rsplit("[", 1)
        instance, variable = name.split("::", 1)
        kind = kind.rstrip("]")
        convert = {"REAL": float, "INT": int, "BOOL": lambda text: text.strip() == "1",
                   "STR": str}[kind]
        columns[f"{instance}.{variable}"] = [convert(row[i]) for row in data]
    return columns
