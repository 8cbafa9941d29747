"""libcosim as an independent second master: run an ``.ssd`` and return chosen outputs.

libcosim (libcosimpy) runs in a child process. When it releases an execution it unloads the
FMU binaries, and unloading a pythonfmu binary inside a Python process leaves that
interpreter liable to crash later; a child process keeps the caller safe. The child ends
when the caller dies, however it dies (:func:`orchestrator.processes.die_with_parent`, armed
before libcosim is imported), instead of stepping on for nobody.
"""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

from components.common.errors import ConfigError, SimulationError

__all__ = ["OBSERVERS", "run_libcosim_ssd"]

# The child's first lines: ``python -c CODE PARENT_PID`` ends with its parent; the orchestrator
# is imported from our own source tree, which then leaves the child's path.
_SOURCE_ROOT = str(Path(__file__).resolve().parents[2])
_TIE = (f"import sys; sys.path.insert(0, {_SOURCE_ROOT!r})\n"
        "from orchestrator.processes import die_with_parent\n"
        "die_with_parent(int(sys.argv[1])); sys.path.pop(0)\n")

_CHILD = _TIE + textwrap.dedent('''
    import json, sys, time
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    job = json.loads(sys.stdin.read())
    log_output_level(CosimLogLevel.ERROR)
    started = time.perf_counter()
    if job["step"] is None:
        # the .ssd's osp:FixedStepAlgorithm gives the base step
        execution = CosimExecution.from_ssp_file(job["ssd"])
    else:
        execution = CosimExecution.from_ssp_file(job["ssd"],
                                                 step_size=int(round(job["step"] * 1e9)))
    reads = []
    for column in job["columns"]:
        instance, port = column.split(".", 1)
        index = execution.slave_index_from_instance_name(instance)
        references = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
        reads.append((index, references[port]))
    if job["observer"] == "last_value":
        observer = CosimObserver.create_last_value()
        execution.add_observer(observer)
    else:
        observer = CosimObserver.create_time_series(job["steps"] + 1)
        execution.add_observer(observer)  # series started before this are silently ignored
        for index, reference in reads:
            observer.start_time_series(index, reference, CosimVariableType.REAL)
    rows = []
    stepping = time.perf_counter()
    if job["observer"] == "last_value":
        for _ in range(job["steps"]):
            execution.step(1)
            rows.append([observer.last_real_values(i, [r])[0] for i, r in reads])
    else:
        execution.step(job["steps"])
    end = time.perf_counter()
    if job["observer"] != "last_value":
        series = []
        for index, reference in reads:
            _, steps, values = observer.time_series_real_samples(index, reference, 1,
                                                                 job["steps"])
            series.append(list(values))
        rows = [list(row) for row in zip(*series)]
    print(json.dumps({"wall_s": end - started, "stepping_s": end - stepping, "rows": rows}))
''')

OBSERVERS = ("last_value", "time_series")


def run_libcosim_ssd(ssd_path, step, stop_time, columns, observer="last_value"):
    """Run ``ssd_path`` in libcosim at a fixed ``step`` and record Real outputs.

    Parameters
    ----------
    ssd_path : path-like
        The system; component sources resolve relative to its folder (libcosim's rule).
    step : float or None
        Base step in s, or None to let libcosim take it from the ``.ssd`` (its
        ``osp:FixedStepAlgorithm`` annotation, :attr:`SystemDescription.base_step`).
    stop_time : float
        End time in s.
    columns : list of str
        ``"instance.port"`` Real outputs to record after every step.
    observer : {"last_value", "time_series"}
        ``last_value``: libcosim reads every variable of every instance after each step and
        the columns are taken from it step by step; ``time_series``: libcosim observes only
        the columns and runs all steps in one call (its leanest way to record them).

    Returns
    -------
    timing : dict
        ``wall_s``: from loading the system to the last step; ``stepping_s``: the steps only.
    rows : list of list of float
        One row per step, the columns in order.
    """
    if observer not in OBSERVERS:
        raise ConfigError(f"libcosim observer {observer!r} is not one of {', '.join(OBSERVERS)}")
    base_step = step
    if step is None:
        from orchestrator.ssp import read_ssd

        base_step = read_ssd(ssd_path).base_step
        if base_step is None:
            raise ConfigError(f"{ssd_path}: no step given and the file has no "
                              f"osp:FixedStepAlgorithm baseStepSize in its DefaultExperiment")
    job = {"ssd": str(Path(ssd_path)), "step": step, "columns": list(columns),
           "steps": int(round(stop_time / base_step)), "observer": observer}
    completed = subprocess.run([sys.executable, "-c", _CHILD, str(os.getpid())],
                               input=json.dumps(job), capture_output=True, text=True)
    if completed.returncode != 0:
        tail = completed.stderr.strip().splitlines()[-3:]
        raise SimulationError(f"libcosim run of {ssd_path} failed with status "
                              f"{completed.returncode}: {' | '.join(tail)}")
    result = json.loads(completed.stdout.strip().splitlines()[-1])
    return {"wall_s": result["wall_s"], "stepping_s": result["stepping_s"]}, result["rows"]
