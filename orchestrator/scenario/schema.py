"""The scenario schema: every field's type, default and allowed values, and their checks.

:data:`SCHEMA` is a table written as data (field -> :class:`Field`); :class:`FieldChecker`
checks one value of each kind and collects every problem as one line naming the source, the
field, the bad value and the valid choices. Nothing here reads a file or knows the system:
:mod:`orchestrator.scenario.validation` applies the schema,
:mod:`orchestrator.scenario.system_checks` checks the values against the ``.ssd`` and the FMUs'
valid ranges.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass

from components.common.errors import ConfigError
from components.common.ranges import show

__all__ = [
    "DEFAULT_MAX_STEPS",
    "MASTERS",
    "STEP_TOLERANCE",
    "SEED_MAX",
    "MAX_STEPS_LIMIT",
    "Field",
    "SCHEMA",
    "KIND_TEXT",
    "FieldChecker",
    "type_name",
    "is_number",
    "is_qualified",
    "is_multiple",
    "check_step_multiples",
    "suggestion",
    "parse_seconds",
]

MASTERS = ("gauss-seidel", "jacobi")
# Relative tolerance when checking that a step is an integer multiple of the base step; float
# steps such as 0.01 / 0.005 are not exact, but an error of 1e-9 is far below any real step.
STEP_TOLERANCE = 1e-9
SEED_MAX = 2**31 - 1   # seeds travel through fmi2Integer (32-bit signed)
# Longest run accepted without saying so: 1e7 base steps (28 h at 10 ms, about an hour of wall
# time at the measured real-time factor). A scenario raises it with `max_steps = N`.
DEFAULT_MAX_STEPS = 10_000_000
MAX_STEPS_LIMIT = 2**53   # integers above this are not exact as a float step count


@dataclass(frozen=True)
class Field:
    """Schema entry of one scenario field.

    Attributes
    ----------
    kind : str
        ``"number"``, ``"integer"``, ``"string"``, ``"choice"``, ``"steps"`` (table of
        instance -> number), ``"parameters"`` (table of ``instance.parameter`` -> scalar) or
        ``"ports"`` (list of ``instance.port`` strings).
    required : bool
        Whether the field must be given.
    default : object
        Value when absent (ignored when required).
    choices : tuple or None
        Allowed values of a ``"choice"``.
    minimum : float or None
        Lower bound; exclusive for numbers (> 0), inclusive for integers.
    maximum : float or None
        Upper bound, inclusive (integers: default the largest seed).
    help : str
        What the field means; quoted in the "required" message.
    """

    kind: str
    required: bool = False
    default: object = None
    choices: tuple | None = None
    minimum: float | None = None
    maximum: float | None = None
    help: str = ""


SCHEMA = {
    "name": Field("string", help="scenario name; default: the file name without .toml"),
    "description": Field("string", default="", help="one paragraph for humans"),
    "system": Field("string", help="path of the .ssd, relative to the scenario file; "
                                   "default ../fmus/SystemStructure.ssd"),
    "stop_time": Field("number", required=True, minimum=0.0, help="end time in s, > 0"),
    "base_step": Field("number", default=0.01, minimum=0.0, maximum=1.0,
                       help="master step in s, in (0, 1]; every step is a multiple of it"),
    "steps": Field("steps", default={},
                   help="communication step per instance in s; default base_step"),
    "seed": Field("integer", default=1, minimum=0,
                  help=f"integer seed 0..{SEED_MAX}, given to every instance with a seed"),
    "parameters": Field("parameters", default={},
                        help="'instance.parameter' = value overrides"),
    "outputs": Field("ports", default=[], help="'instance.port' to record; empty = all outputs"),
    "master": Field("choice", default="gauss-seidel", choices=MASTERS,
                    help="co-simulation algorithm"),
    "max_steps": Field("integer", default=DEFAULT_MAX_STEPS, minimum=1, maximum=MAX_STEPS_LIMIT,
                       help="largest stop_time / base_step accepted (a bound on the work)"),
    "faults": Field("faults", default=(), help="[[faults]] entries: kind, target, start, "
                                               "end, magnitude (orchestrator/scenario/faults.py)"),
}

KIND_TEXT = {
    "number": "a number",
    "integer": "an integer",
    "string": "a string",
    "choice": "a string",
    "steps": "a table of instance = step in s",
    "parameters": "a table of 'instance.parameter' = value",
    "ports": "a list of 'instance.port' strings",
    "faults": "a list of [[faults]] tables",
}



def type_name(value):
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
            dict: "a table", list: "a list"}.get(type(value), type(value).__name__)


def is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def is_qualified(name):
    instance, dot, port = name.partition(".")
    return bool(dot and instance and port and "." not in port)


class FieldChecker:
    """Collects problems of one scenario source."""

    def __init__(self, source):
        self.source = source
        self.problems = []

    def add(self, field_name, message):
        self.problems.append(f"{self.source}: field '{field_name}': {message}")

    def number(self, name, value, minimum, maximum=None):
        if not is_number(value):
            self.add(name, f"{show(value)} is {type_name(value)}, expected a number")
            return None
        if not math.isfinite(value):
            self.add(name, f"{value!r} is not finite, expected a number > {minimum:g}")
            return None
        if minimum is not None and value <= minimum:
            self.add(name, f"{value!r} must be > {minimum:g}")
            return None
        if maximum is not None and value > maximum:
            self.add(name, f"{value!r} must be <= {maximum:g}")
            return None
        return float(value)

    def integer(self, name, value, minimum, maximum=None):
        maximum = SEED_MAX if maximum is None else maximum
        if not isinstance(value, int) or isinstance(value, bool):
            self.add(name, f"{show(value)} is {type_name(value)}, expected an integer")
            return None
        if (minimum is not None and value < minimum) or value > maximum:
            self.add(name, f"{value!r} is outside {minimum}..{maximum}")
            return None
        return value

    def string(self, name, value):
        if not isinstance(value, str):
            self.add(name, f"{show(value)} is {type_name(value)}, expected a string")
            return None
        return value

    def choice(self, name, value, choices):
        if self.string(name, value) is None:
            return None
        if value not in choices:
            valid = ", ".join(repr(c) for c in choices)
            self.add(name, f"{value!r} is not one of {valid}")
            return None
        return value

    def steps(self, name, value):
        if not isinstance(value, dict):
            self.add(name, f"{show(value)} is {type_name(value)}, expected {KIND_TEXT['steps']}")
            return None
        steps = {}
        for instance, step in value.items():
            checked = self.number(f"{name}.{instance}", step, 0.0)
            if checked is not None:
                steps[instance] = checked
        return steps

    def parameters(self, name, value):
        if not isinstance(value, dict):
            self.add(name, f"{show(value)} is {type_name(value)}, "
                           f"expected {KIND_TEXT['parameters']}")
            return None
        flat = {}
        for key, item in value.items():
            # TOML turns `source.path = "x"` into a nested table; accept both spellings.
            entries = ([(f"{key}.{sub}", subvalue) for sub, subvalue in item.items()]
                       if isinstance(item, dict) else [(key, item)])
            for qualified, scalar in entries:
                where = f"{name}.{qualified}"
                if not is_qualified(qualified):
                    self.add(where, f"{qualified!r} is not of the form 'instance.parameter'")
                elif isinstance(scalar, (dict, list)) or not isinstance(
                        scalar, (bool, int, float, str)):
                    self.add(where, f"{show(scalar)} is {type_name(scalar)}, expected a number, "
                                    f"integer, boolean or string")
                elif isinstance(scalar, float) and not math.isfinite(scalar):
                    self.add(where, f"{scalar!r} is not finite")
                elif qualified in flat:
                    self.add(where, "is given twice (as a dotted key and in a table)")
                else:
                    flat[qualified] = scalar
        return flat

    def ports(self, name, value):
        if not isinstance(value, list):
            self.add(name, f"{show(value)} is {type_name(value)}, expected {KIND_TEXT['ports']}")
            return None
        ports = []
        for position, item in enumerate(value):
            if not isinstance(item, str) or not is_qualified(item):
                self.add(f"{name}[{position}]", f"{item!r} is not an 'instance.port' string")
            elif item in ports:
                self.add(f"{name}[{position}]", f"{item!r} is listed twice")
            else:
                ports.append(item)
        return ports


def is_multiple(step, base):
    ratio = step / base
    if not math.isfinite(ratio):   # e.g. 1e308 / 0.01: more steps than a float counts
        return False, ratio
    count = round(ratio)
    return count >= 1 and abs(ratio - count) <= STEP_TOLERANCE * ratio, ratio


def check_step_multiples(check, values):
    """Check that every step and ``stop_time`` are whole multiples of ``base_step``.

    ``stop_time / base_step`` may also not exceed ``max_steps`` (a bound on the work). Problems
    go to ``check``; ``values`` are the fields already checked one by one (None where bad).
    """
    base = values.get("base_step")
    if base is not None:
        for instance, step in sorted((values.get("steps") or {}).items()):
            ok, ratio = is_multiple(step, base)
            if not ok:
                check.add(f"steps.{instance}", f"{step!r} is not an integer multiple of "
                                               f"base_step {base!r} (ratio {ratio:.6g})")
        if values.get("stop_time") is not None:
            ok, ratio = is_multiple(values["stop_time"], base)
            limit = values.get("max_steps")
            if limit is not None and ratio > limit + 0.5:
                check.add("stop_time", f"{values['stop_time']!r} s at base_step {base!r} s is "
                                       f"{ratio:.6g} steps, more than max_steps = {limit}; "
                                       "raise max_steps in the scenario for a longer run")
            elif not ok:
                check.add("stop_time", f"{values['stop_time']!r} is not an integer multiple of "
                                       f"base_step {base!r} (ratio {ratio:.6g})")


def suggestion(name, choices):
    """`` (did you mean 'x'?)`` for the closest of ``choices`` to ``name``, or ``""``."""
    close = difflib.get_close_matches(name, list(choices), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def parse_seconds(text, field_name, maximum=3600.0):
    """Read a positive, finite number of seconds of at most ``maximum`` from a command line.

    Raises
    ------
    ConfigError
        Naming ``field_name``, the text and the valid range.
    """
    try:
        value = float(text)
    except (TypeError, ValueError):
        value = None
    if value is None or not 0.0 < value <= maximum:
        raise ConfigError(f"{field_name} {text!r}: expected a number of seconds in "
                          f"(0, {maximum:g}]")
    return value

