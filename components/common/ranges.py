"""The port table of an FMU: its parameters and inputs, their valid ranges, read from data.

Each FMU's sub-package holds one ``ranges.toml``. For every parameter and input it gives the
``description``, the FMI ``type``, the ``unit`` (Real), the ``start`` value, the inclusive
``min``/``max`` (Real, Integer) or the ``choices`` (String), and optionally ``why`` the bounds
are what they are; plus the communication step's range::

    [parameters.mic_spacing]
    description = "distance l between adjacent microphones"
    type = "Real"
    unit = "m"
    start = 0.4
    min = 0.01
    max = 5.0
    why = "paper: 0.4"

Entries are in declaration order, which fixes the FMU's value references. The same table is
used four times, so it is the one source of truth: the slave declares its parameters and inputs
from it (:class:`~components.common.slave.SonotrackSlave`), refuses values outside it, the
modelDescription carries it as ``min``/``max`` attributes, and the scenario schema checks a
run's parameter values against it before any FMU is loaded (``orchestrator.scenario``).

Values are checked strictly: no clamping and no coercion. A Real takes an int or a float (never
a bool), an Integer only an int, a Boolean only a bool, a String only a str; NaN and inf are
outside every range.
"""

import dataclasses
import math
import tomllib
from pathlib import Path

from .errors import ConfigError
from .units import UNIT_BASES

__all__ = ["ValidRange", "RangeTable", "load_ranges", "show", "TYPES", "INT32_MIN", "INT32_MAX"]

TYPES = ("Real", "Integer", "Boolean", "String")
INT32_MIN, INT32_MAX = -2**31, 2**31 - 1   # an fmi2Integer is a 32-bit signed int


def _number_text(value):
    return repr(value) if isinstance(value, float) else str(value)


@dataclasses.dataclass(frozen=True)
class ValidRange:
    """The valid values of one parameter, input or the communication step.

    Attributes
    ----------
    name : str
        Variable name (``"step_size"`` for the communication step).
    type : str
        FMI type: ``"Real"``, ``"Integer"``, ``"Boolean"`` or ``"String"``.
    unit : str or None
        SI unit of a Real.
    minimum, maximum : float or int or None
        Inclusive bounds of a Real or Integer (both finite).
    choices : tuple of str
        Allowed values of a String (empty: any string, or see ``file_suffix``).
    file_suffix : str or None
        A String may also be a file name with this suffix (e.g. a CSV path).
    why : str
        Where the bounds come from (shown in the FMU documentation).
    start : float or int or bool or str or None
        Start value of a parameter or input, of its type (None for the communication step).
    description : str
        What the port is, as the modelDescription says it.
    """

    name: str
    type: str
    unit: str | None = None
    minimum: float | int | None = None
    maximum: float | int | None = None
    choices: tuple = ()
    file_suffix: str | None = None
    why: str = ""
    start: float | int | bool | str | None = None
    description: str = ""

    def text(self):
        """The valid values in words: ``[0.1, 1000.0] kg``, ``one of 'a', 'b'``, ``true or false``."""
        if self.type in ("Real", "Integer"):
            unit = f" {self.unit}" if self.unit and self.unit != "1" else ""
            return f"[{_number_text(self.minimum)}, {_number_text(self.maximum)}]{unit}"
        if self.type == "Boolean":
            return "true or false"
        parts = []
        if self.choices:
            parts.append("one of " + ", ".join(repr(c) for c in self.choices))
        if self.file_suffix:
            parts.append(f"a file name ending in {self.file_suffix}")
        return " or ".join(parts) or "any string"

    def problem(self, value):
        """Return why ``value`` is not valid (``"<name> = <value> ..."``), or None if it is."""
        if self.type == "Real":
            ok_type = isinstance(value, (int, float)) and not isinstance(value, bool)
        elif self.type == "Integer":
            ok_type = isinstance(value, int) and not isinstance(value, bool)
        elif self.type == "Boolean":
            ok_type = isinstance(value, bool)
        else:
            ok_type = isinstance(value, str)
        if not ok_type:
            valid = {"Real": f"a number in {self.text()}",
                     "Integer": f"an integer in {self.text()}",
                     "Boolean": "a boolean, true or false"}.get(self.type, "a string")
            return f"{self.name} = {show(value)} is {_kind_of(value)}, expected {valid}"
        if self.type in ("Real", "Integer"):
            if not self.minimum <= value <= self.maximum:
                finite = "" if math.isfinite(value) else " (not finite)"
                return f"{self.name} = {value!r}{finite} is outside its valid range {self.text()}"
        elif self.type == "String" and (self.choices or self.file_suffix):
            if value in self.choices:
                return None
            if self.file_suffix and value.lower().endswith(self.file_suffix) and \
                    len(value) > len(self.file_suffix):
                return None
            return f"{self.name} = {value!r} is not valid; valid: {self.text()}"
        return None


def show(value):
    """A value as a scenario file writes it (``true``, not ``True``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value)


def _kind_of(value):
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
            dict: "a table", list: "a list"}.get(type(value), type(value).__name__)


@dataclasses.dataclass(frozen=True)
class RangeTable:
    """One FMU's port table: ``parameters``, ``inputs`` (by name, declaration order), ``step``."""

    model: str
    parameters: dict
    inputs: dict
    step: ValidRange
    source: str = ""

    def entry(self, name):
        """The range of parameter or input ``name``, or None."""
        return self.parameters.get(name) or self.inputs.get(name)


_STEP_KEYS = ("type", "unit", "min", "max", "choices", "file_suffix", "why")
_PORT_KEYS = ("description", "type", "unit", "start", "min", "max", "choices", "file_suffix", "why")
_START_TYPES = {"Real": float, "Integer": int, "Boolean": bool, "String": str}


def _read_entry(port, name, spec, where, problems):
    """Return the :class:`ValidRange` of one table entry, or None after adding its problems.

    ``port`` is ``"parameter"`` or ``"input"``, whose entries also need a ``description`` and
    a ``start``, or None for the communication step.
    """
    def refuse(text):
        problems.append(f"{where}: {port + ' ' if port else ''}{name}: {text}")

    if not isinstance(spec, dict):
        refuse(f"must be a table, got {spec!r}")
        return None
    keys = _PORT_KEYS if port else _STEP_KEYS
    unknown = sorted(set(spec) - set(keys))
    if unknown:
        refuse(f"unknown keys {unknown}; valid keys: {', '.join(keys)}")
    kind = spec.get("type")
    if kind not in TYPES:
        refuse(f"type {kind!r} is not one of {', '.join(TYPES)}")
        return None
    count = len(problems)
    minimum, maximum = spec.get("min"), spec.get("max")
    if kind in ("Real", "Integer"):
        number = int if kind == "Integer" else (int, float)
        if not all(isinstance(b, number) and not isinstance(b, bool) and math.isfinite(b)
                   for b in (minimum, maximum)):
            refuse(f"needs finite min and max of its type, got min = {minimum!r}, "
                   f"max = {maximum!r}")
        elif minimum > maximum:
            refuse(f"min {minimum!r} > max {maximum!r}")
        elif kind == "Integer" and not INT32_MIN <= minimum <= maximum <= INT32_MAX:
            refuse(f"an fmi2Integer range must lie in [{INT32_MIN}, {INT32_MAX}]")
        elif kind == "Real":
            minimum, maximum = float(minimum), float(maximum)
    elif minimum is not None or maximum is not None:
        refuse("min/max apply to Real and Integer only")
    unit = spec.get("unit")
    if kind == "Real" and unit not in UNIT_BASES:
        refuse(("a Real needs its unit" if unit is None else f"unit {unit!r} is not known")
               + f", one of {', '.join(UNIT_BASES)}")
    elif kind != "Real" and unit is not None:
        refuse("a unit applies to a Real only")
    choices = tuple(spec.get("choices", ()))
    if (choices or spec.get("file_suffix")) and kind != "String":
        refuse("choices/file_suffix apply to String only")
    description, start = spec.get("description", ""), spec.get("start")
    if port and (not isinstance(description, str) or not description.strip()):
        refuse("needs a description, a non-empty string (the modelDescription's)")
    if port and start is None:
        refuse(f"needs a start value of type {kind}")
    if len(problems) > count:
        return None
    entry = ValidRange(name, kind, unit, minimum, maximum, choices, spec.get("file_suffix"),
                       spec.get("why", ""), description=description)
    if port:
        problem = entry.problem(start)
        if problem is not None:
            problems.append(f"{where}: start value of {port} {problem}")
            return None
        # a Real start may be written as an integer (start = 0); the port holds a float
        entry = dataclasses.replace(entry, start=_START_TYPES[kind](start))
    return entry


def load_ranges(part):
    """Read ``components/<part>/ranges.toml`` (the FMU's private copy inside an FMU).

    Parameters
    ----------
    part : str
        Sub-package of ``components`` (``"plant"``, ``"source"``, ...), a sibling of this
        package both in the repository and inside a built FMU.

    Returns
    -------
    RangeTable

    Raises
    ------
    ConfigError
        If the table is missing or malformed: every problem, one line each, naming the file,
        the entry and the valid choices.
    """
    path = Path(__file__).resolve().parent.parent / part / "ranges.toml"
    where = str(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise ConfigError(f"{where}: cannot read the valid-range table ({error})") from error
    problems = []
    tables = {}
    for section, port in (("parameters", "parameter"), ("inputs", "input")):
        entries = data.get(section, {})
        if not isinstance(entries, dict):
            problems.append(f"{where}: [{section}] must be a table of {section}")
            entries = {}
        tables[section] = {name: _read_entry(port, name, spec, where, problems)
                           for name, spec in entries.items()}
    step = data.get("step", {}).get("step_size")
    if step is None:
        problems.append(f"{where}: [step] step_size (the communication step range) is missing")
        step_range = None
    else:
        step_range = _read_entry(None, "step_size", step, where, problems)
        if step_range is not None and (step_range.type != "Real" or step_range.minimum <= 0.0):
            problems.append(f"{where}: step_size must be a Real with min > 0")
    if problems:
        raise ConfigError("\n".join(problems))
    return RangeTable(data.get("model", part), tables["parameters"], tables["inputs"],
                      step_range, where)
