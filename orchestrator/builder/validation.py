"""Check built FMUs: fmpy's validator, fmu-manipulation-toolbox's checker and a short run.

Every problem found is collected, as FMPy's ``validate`` does, so a user sees them all at
once; :func:`validate_fmus` returns them and ``sonotrack validate`` exits with their count.
"""

import os
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

from orchestrator.processes import tied_command

__all__ = ["FmuReport", "validate_fmu", "validate_fmus"]


@dataclass
class FmuReport:
    """The problems each checker found in one FMU."""

    path: Path
    problems: list = field(default_factory=list)

    @property
    def ok(self):
        """True when no checker found a problem."""
        return not self.problems


def validate_fmu(path, simulate=True):
    """Run every check on one FMU and return an :class:`FmuReport`.

    Parameters
    ----------
    path : path-like
        The ``.fmu`` file.
    simulate : bool, optional
        Also run a short simulation through fmpy (1 s or the default experiment, if shorter).
    """
    path = Path(path)
    report = FmuReport(path)
    if not path.is_file():
        report.problems.append(f"{path}: no such FMU file")
        return report
    from fmpy.validation import validate_fmu as fmpy_validate

    from components.common.errors import ConfigError
    from orchestrator.fmu.cache import extract_fmu

    try:
        # the same checked, size-capped unpacking a run uses; nothing else runs on a refusal
        unzip_dir = extract_fmu(path)
    except ConfigError as error:
        report.problems.append(f"unpacking: {error}")
        return report
    report.problems += [f"fmpy validate: {p}" for p in fmpy_validate(str(path))]
    report.problems += [f"fmutool -check: {p}" for p in _fmutool_check(path)]
    if simulate and not report.problems:
        report.problems += [f"fmpy simulate: {p}" for p in _short_simulation(unzip_dir)]
    return report


def validate_fmus(paths, simulate=True):
    """Validate several FMUs; return the list of :class:`FmuReport`."""
    return [validate_fmu(p, simulate) for p in paths]


def _fmutool_check(path):
    tool = Path(sys.executable).parent / "fmutool"
    command = [str(tool)] if tool.exists() else [sys.executable, "-m", "fmu_manipulation_toolbox"]
    # tied: the checker and the simulation child end with this process (docs/process_lifetime.md)
    completed = subprocess.run(tied_command(command + ["-input", str(path), "-check"]),
                               capture_output=True, text=True,
                               env={**os.environ, "PYTHONUNBUFFERED": "1"})
    lines = (completed.stdout + completed.stderr).splitlines()
    errors = [line.split("|", 1)[-1].strip() for line in lines if line.startswith("ERROR")]
    if completed.returncode != 0 and not errors:
        errors.append(f"exit status {completed.returncode}: {' '.join(lines[-3:])}")
    return [e for e in errors if not e.startswith("-check:")]


_SIMULATE = """
import json, sys
import fmpy
path, stop, step = sys.argv[1], float(sys.argv[2]), sys.argv[3]
errors = []
def logger(component, instance, status, category, message):
    if status >= 3:
        errors.append(message.decode(errors="replace"))
try:
    result = fmpy.simulate_fmu(path, stop_time=stop, logger=logger,
                               output_interval=None if step == "None" else float(step))
    if len(result) == 0:
        errors.append("the simulation produced no rows")
except Exception as exc:
    errors.insert(0, str(exc))
print(json.dumps(errors))
"""


def _short_simulation(path):
    """Simulate in a child process: a crashing FMU must not take the validator down.

    ``path`` is the unpacked FMU folder, so fmpy unpacks nothing into the temporary folder.
    """
    import json

    import fmpy

    description = fmpy.read_model_description(str(path))
    experiment = description.defaultExperiment
    stop, step = 1.0, None
    if experiment is not None:
        if experiment.stopTime is not None:
            stop = min(stop, float(experiment.stopTime))
        if experiment.stepSize is not None:
            step = float(experiment.stepSize)
    completed = subprocess.run(tied_command([sys.executable, "-c", _SIMULATE, str(path),
                                             str(stop), str(step)]),
                               capture_output=True, text=True, timeout=600)
    if completed.returncode != 0:
        return [f"the simulation process died with status {completed.returncode}: "
                f"{completed.stderr.strip().splitlines()[-1:] }"]
    return json.loads(completed.stdout.strip().splitlines()[-1])
