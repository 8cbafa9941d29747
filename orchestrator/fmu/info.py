"""What an FMU declares, for a person at a terminal: ``sonotrack info FMU``.

:func:`fmu_info` reads an ``.fmu``'s model description (nothing is unpacked or loaded) and
returns its model facts and one :class:`VariableInfo` per variable: causality, type, unit,
start, valid range (``min``/``max``, or the choices of an enumeration-like string) and
description, in declaration order. :func:`format_info` lays them out as a text table.

Examples
--------
>>> row = VariableInfo("v_cruise", "parameter", "Real", "m/s", "0.3", "[0.001, 10]",
...                    "cruise speed")
>>> print(format_info({"model": "CurvaturePlanner", "fmi": "2.0"}, [row]))
model: CurvaturePlanner
fmi: 2.0
<BLANKLINE>
name      causality  type  unit  start  range        description
v_cruise  parameter  Real  m/s   0.3    [0.001, 10]  cruise speed
"""

from dataclasses import astuple, dataclass, fields
from pathlib import Path

from components.common.errors import ConfigError

__all__ = ["VariableInfo", "find_fmu", "fmu_info", "format_info"]


@dataclass(frozen=True)
class VariableInfo:
    """One variable as ``sonotrack info`` shows it (every field text; ``""`` if undeclared)."""

    name: str
    causality: str
    type: str
    unit: str
    start: str
    range: str
    description: str


def find_fmu(text, folders=()):
    """The FMU file ``text`` names: a path, else ``<folder>/<text>.fmu`` in ``folders``.

    Raises
    ------
    ConfigError
        One line naming ``text`` and where it was looked for.
    """
    path = Path(text)
    if path.is_file():
        return path
    for folder in folders:
        candidate = Path(folder) / (path.name if path.suffix == ".fmu" else f"{path.name}.fmu")
        if candidate.is_file():
            return candidate
    where = ", ".join(str(f) for f in folders)
    raise ConfigError(f"{text}: no such FMU file" + (f" (nor {path.stem}.fmu in {where})"
                                                      if where else ""))


def _number(value):
    """A bound as short text: numbers to 6 significant digits (a table, not a data file)."""
    if value is None:
        return ""
    try:
        return f"{float(value):.6g}"
    except (TypeError, ValueError):
        return str(value)


def _range(variable):
    low, high = getattr(variable, "min", None), getattr(variable, "max", None)
    if low is None and high is None:
        return ""
    return f"[{_number(low) or '-inf'}, {_number(high) or 'inf'}]"


def fmu_info(path):
    """The model facts and variables of an ``.fmu``.

    Parameters
    ----------
    path : path-like
        The ``.fmu`` file.

    Returns
    -------
    (dict, list of VariableInfo)
        ``model``, ``fmi``, ``generation_tool``, ``author``, ``version``, ``description``,
        ``default_experiment`` (start, stop, step) and the variables in declaration order.

    Raises
    ------
    ConfigError
        One line naming the file if it is not an FMU whose model description parses.
    """
    from .handle import model_description

    path = Path(path)
    try:
        description = model_description(path)
    except OSError as error:
        raise ConfigError(f"{path}: cannot read the FMU ({error.strerror or error})") from None
    except Exception as error:   # fmpy raises bare exceptions for a bad archive or XML
        text = " ".join(str(error).split()) or type(error).__name__
        raise ConfigError(f"{path}: not an FMU with a readable modelDescription.xml "
                          f"({text})") from None
    experiment = description.defaultExperiment
    facts = {
        "model": description.modelName,
        "fmi": description.fmiVersion,
        "generation_tool": description.generationTool or "",
        "author": description.author or "",
        "version": description.version or "",
        "description": description.description or "",
        "default_experiment": ("" if experiment is None else
                               f"start {experiment.startTime}, stop {experiment.stopTime}, "
                               f"step {experiment.stepSize}"),
    }
    variables = [VariableInfo(v.name, v.causality or "", v.type, getattr(v, "unit", None) or
                              getattr(getattr(v, "declaredType", None), "unit", None) or "",
                              "" if v.start is None else str(v.start), _range(v),
                              " ".join((v.description or "").split()))
                 for v in description.modelVariables]
    return facts, variables


def format_info(facts, variables):
    """``facts`` as ``key: value`` lines, then the variables as an aligned text table."""
    lines = [f"{key}: {value}" for key, value in facts.items() if value]
    header = tuple(f.name for f in fields(VariableInfo))
    rows = [header] + [astuple(v) for v in variables]
    widths = [max(len(row[i]) for row in rows) for i in range(len(header))]
    table = ["  ".join(cell.ljust(width) for cell, width in zip(row, widths)).rstrip()
             for row in rows]
    return "\n".join(lines + [""] + table)
