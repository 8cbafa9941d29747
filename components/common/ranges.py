"""Valid ranges of an FMU's parameters, inputs and communication step, read from data.

Each FMU's sub-package holds one ``ranges.toml``: for every parameter and input its FMI type,
unit and inclusive ``min``/``max`` (Real, Integer), or its ``choices`` (String); plus the
communication step's range. The same table is used three times, so it is the one source of
truth: the slave refuses values outside it (:class:`~components.common.slave.SonotrackSlave`),
the modelDescription carries it as ``min``/``max`` attributes, and the scenario schema checks
a run's parameter values against it before any FMU is loaded (``orchestrator.scenario``).

Values are checked strictly: no clamping and no coercion. A Real takes an int or a float (never
a bool), an Integer only an int, a Boolean only a bool, a String only a str; NaN and inf are
outside every range.
"""

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

from .errors import ConfigError

__all__ = ["ValidRange", "RangeTable", "load_ranges", "show", "TYPES", "INT32_MIN", "INT32_MAX"]

TYPES = ("Real", "Integer", "Boolean", "String")
INT32_MIN, INT32_MAX = -2**31, 2**31 - 1   # an fmi2Integer is a 32-bit signed int


def _number_text(value):
    return repr(value) if isinstance(value, float) else str(value)


@dataclass(frozen=True)
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
    """

    name: str
    type: str
    unit: str | None = None
    minimum: float | int | None = None
    maximum: float | int | None = None
    choices: tuple = ()
    file_suffix: str | None = None
    why: str = ""

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


@dataclass(frozen=True)
class RangeTable:
    """Every valid range of one FMU: ``parameters`` and ``inputs`` by name, and ``step``."""

    model: str
    parameters: dict
    inputs: dict
    step: ValidRange
    source: str = ""

    def entry(self, name):
        """The range of parameter or input ``name``, or None."""
        return self.parameters.get(name) or self.inputs.get(name)


def _read_entry(name, spec, where):
    if not isinstance(spec, dict):
        raise ConfigError(f"{where}: {name} must be an inline table, got {spec!r}")
    unknown = set(spec) - {"type", "unit", "min", "max", "choices", "file_suffix", "why"}
    if unknown:
        raise ConfigError(f"{where}: {name} has unknown keys {sorted(unknown)}")
    kind = spec.get("type")
    if kind not in TYPES:
        raise ConfigError(f"{where}: {name}: type {kind!r} is not one of {', '.join(TYPES)}")
    minimum, maximum = spec.get("min"), spec.get("max")
    if kind in ("Real", "Integer"):
        number = int if kind == "Integer" else (int, float)
        for bound in (minimum, maximum):
            if not isinstance(bound, number) or isinstance(bound, bool) or \
                    not math.isfinite(bound):
                raise ConfigError(f"{where}: {name} needs finite min and max of its type, got "
                                  f"min = {minimum!r}, max = {maximum!r}")
        if minimum > maximum:
            raise ConfigError(f"{where}: {name}: min {minimum!r} > max {maximum!r}")
        if kind == "Integer" and not INT32_MIN <= minimum <= maximum <= INT32_MAX:
            raise ConfigError(f"{where}: {name}: an fmi2Integer range must lie in "
                              f"[{INT32_MIN}, {INT32_MAX}]")
        if kind == "Real":
            minimum, maximum = float(minimum), float(maximum)
    elif minimum is not None or maximum is not None:
        raise ConfigError(f"{where}: {name}: min/max apply to Real and Integer only")
    if kind == "Real" and not spec.get("unit"):
        raise ConfigError(f"{where}: {name}: a Real needs its unit")
    choices = tuple(spec.get("choices", ()))
    if (choices or spec.get("file_suffix")) and kind != "String":
        raise ConfigError(f"{where}: {name}: choices/file_suffix apply to String only")
    return ValidRange(name, kind, spec.get("unit"), minimum, maximum, choices,
                      spec.get("file_suffix"), spec.get("why", ""))


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
        If the table is missing or malformed.
    """
    path = Path(__file__).resolve().parent.parent / part / "ranges.toml"
    where = str(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise ConfigError(f"{where}: cannot read the valid-range table ({error})") from error
    tables = {}
    for section in ("parameters", "inputs"):
        entries = data.get(section, {})
        tables[section] = {name: _read_entry(name, spec, where) for name, spec in entries.items()}
    step = data.get("step", {}).get("step_size")
    if step is None:
        raise ConfigError(f"{where}: [step] step_size (the communication step range) is missing")
    step_range = _read_entry("step_size", step, where)
    if step_range.type != "Real" or step_range.minimum <= 0.0:
        raise ConfigError(f"{where}: step_size must be a Real with min > 0")
    return RangeTable(data.get("model", part), tables["parameters"], tables["inputs"],
                      step_range, where)
