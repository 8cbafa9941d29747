"""libcosim as an independent second master: run an ``.ssd`` and return chosen outputs.

libcosim (libcosimpy) runs in a child process. When it releases an execution it unloads the
FMU binaries, and unloading a pythonfmu binary inside a Python process leaves that
interpreter liable to crash later; a child process keeps the caller safe.
"""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

from components.common.errors import SimulationError

__all__ = ["run_libcosim_ssd"]

_CHILD = textwrap.dedent('''
    import json, sys, time
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    job = json.loads(sys.stdin.read())
    log_output_level(CosimLogLevel.ERROR)
    started = time.perf_counter()
    execution = CosimExecution.from_ssp_file(job["ssd"], step_size=int(round(job["step"] * 1e9)))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    reads = []
    for column in job["columns"]:
        instance, port = column.split(".", 1)
        index = execution.slave_index_from_instance_name(instance)
        references = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
        reads.append((index, references[port]))
    rows = []
    stepping = time.perf_counter()
    for _ in range(job["steps"]):
        execution.step(1)
        rows.append([observer.last_real_values(i, [r])[0] for i, r in reads])
    end = time.perf_counter()
    print(json.dumps({"wall_s": end - started, "stepping_s": end - stepping, "rows": rows}))
''')


def run_libcosim_ssd(ssd_path, step, stop_time, columns):
    """Run ``ssd_path`` in libcosim at a fixed ``step`` and record Real outputs.

    Parameters
    ----------
    ssd_path : path-like
        The system; component sources resolve relative to its folder (libcosim's rule).
    step, stop_time : float
        Base step and end time in s.
    columns : list of str
        ``"instance.port"`` Real outputs to read after every step.

    Returns
    -------
    timing : dict
        ``wall_s``: from loading the system to the last step; ``stepping_s``: the steps only.
    rows : list of list of float
        One row per step, the columns in order.
    """
    job = {"ssd": str(Path(ssd_path)), "step": step, "columns": list(columns),
           "steps": int(round(stop_time / step))}
    completed = subprocess.run([sys.executable, "-c", _CHILD], input=json.dumps(job),
                               capture_output=True, text=True)
    if completed.returncode != 0:
        tail = completed.stderr.strip().splitlines()[-3:]
        raise SimulationError(f"libcosim run of {ssd_path} failed with status "
                              f"{completed.returncode}: {' | '.join(tail)}")
    result = json.loads(completed.stdout.strip().splitlines()[-1])
    return {"wall_s": result["wall_s"], "stepping_s": result["stepping_s"]}, result["rows"]
