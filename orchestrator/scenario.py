"""Scenarios: what to run (system, parameter overrides, times, steps, seed, outputs, master).

A scenario is a TOML file (``scenarios/*.toml``) or a plain dict, validated against
:data:`SCHEMA`, a table written as data: field -> type, whether it is required, its default and
its allowed values. Every problem (unknown field, wrong type, bad choice, a step that is not a
multiple of the base step) becomes one line naming the file, the field, the bad value and the
valid choices, and all lines are raised together in one :class:`ConfigError`.

Before any FMU is loaded, the scenario is also checked against its ``.ssd`` (read as XML) and
the valid-range tables of the FMUs it names (``components/<part>/ranges.toml``, the same tables
the FMUs enforce and export as ``min``/``max``): ``[steps]`` names only instances of the system,
every instance's step lies in its FMU's step range, and every parameter value, from the
scenario or bound in the ``.ssd``, has the right type (no bool for a number, no string for a
bool, no float for an integer) and lies in its valid range. FMUs the tables do not know are
checked against their model descriptions by the system layer.

Work is bounded: ``stop_time / base_step`` may not exceed ``max_steps`` (default
:data:`DEFAULT_MAX_STEPS`; raise it in the scenario for a longer run).

Seeds: the master passes ``seed`` to every instance that has a ``seed`` parameter, unless
``parameters`` sets that instance's seed explicitly.
"""

from __future__ import annotations

import difflib
import functools
import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from components.common.errors import ConfigError
from components.common.ranges import show
from orchestrator.faults import check_faults, faults_to_dicts

__all__ = [
    "DEFAULT_MAX_STEPS",
    "MASTERS",
    "STEP_TOLERANCE",
    "Field",
    "SCHEMA",
    "Scenario",
    "load_scenario",
    "scenario_from_dict",
    "default_system_path",
    "model_ranges",
    "parse_seconds",
]

MASTERS = ("gauss-seidel", "jacobi")
# Relative tolerance when checking that a step is an integer multiple of the base step; float
# steps such as 0.01 / 0.005 are not exact, but an error of 1e-9 is far below any real step.
STEP_TOLERANCE = 1e-9
_SEED_MAX = 2**31 - 1   # seeds travel through fmi2Integer (32-bit signed)
# Longest run accepted without saying so: 1e7 base steps (28 h at 10 ms, about an hour of wall
# time at the measured real-time factor). A scenario raises it with `max_steps = N`.
DEFAULT_MAX_STEPS = 10_000_000
_MAX_STEPS_LIMIT = 2**53   # integers above this are not exact as a float step count


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
                  help=f"integer seed 0..{_SEED_MAX}, given to every instance with a seed"),
    "parameters": Field("parameters", default={},
                        help="'instance.parameter' = value overrides"),
    "outputs": Field("ports", default=[], help="'instance.port' to record; empty = all outputs"),
    "master": Field("choice", default="gauss-seidel", choices=MASTERS,
                    help="co-simulation algorithm"),
    "max_steps": Field("integer", default=DEFAULT_MAX_STEPS, minimum=1, maximum=_MAX_STEPS_LIMIT,
                       help="largest stop_time / base_step accepted (a bound on the work)"),
    "faults": Field("faults", default=(), help="[[faults]] entries: kind, target, start, "
                                               "end, magnitude (orchestrator/faults.py)"),
}

_KIND_TEXT = {
    "number": "a number",
    "integer": "an integer",
    "string": "a string",
    "choice": "a string",
    "steps": "a table of instance = step in s",
    "parameters": "a table of 'instance.parameter' = value",
    "ports": "a list of 'instance.port' strings",
    "faults": "a list of [[faults]] tables",
}


def default_system_path(base_dir=None):
    """The default ``.ssd``: ``<base_dir>/../fmus/SystemStructure.ssd`` if it exists.

    Without ``base_dir``, or when a scenario lives outside a checkout (no ``../fmus`` beside
    it), the repository's ``fmus/SystemStructure.ssd`` (this package's sibling).
    """
    repository = Path(__file__).resolve().parent.parent / "fmus" / "SystemStructure.ssd"
    if base_dir is None:
        return repository
    beside = (Path(base_dir) / ".." / "fmus" / "SystemStructure.ssd").resolve()
    return beside if beside.is_file() else repository


def _type_name(value):
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
            dict: "a table", list: "a list"}.get(type(value), type(value).__name__)


def _is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_qualified(name):
    instance, dot, port = name.partition(".")
    return bool(dot and instance and port and "." not in port)


class _Checker:
    """Collects problems of one scenario source."""

    def __init__(self, source):
        self.source = source
        self.problems = []

    def add(self, field_name, message):
        self.problems.append(f"{self.source}: field '{field_name}': {message}")

    def number(self, name, value, minimum, maximum=None):
        if not _is_number(value):
            self.add(name, f"{show(value)} is {_type_name(value)}, expected a number")
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
        maximum = _SEED_MAX if maximum is None else maximum
        if not isinstance(value, int) or isinstance(value, bool):
            self.add(name, f"{show(value)} is {_type_name(value)}, expected an integer")
            return None
        if (minimum is not None and value < minimum) or value > maximum:
            self.add(name, f"{value!r} is outside {minimum}..{maximum}")
            return None
        return value

    def string(self, name, value):
        if not isinstance(value, str):
            self.add(name, f"{show(value)} is {_type_name(value)}, expected a string")
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
            self.add(name, f"{show(value)} is {_type_name(value)}, expected {_KIND_TEXT['steps']}")
            return None
        steps = {}
        for instance, step in value.items():
            checked = self.number(f"{name}.{instance}", step, 0.0)
            if checked is not None:
                steps[instance] = checked
        return steps

    def parameters(self, name, value):
        if not isinstance(value, dict):
            self.add(name, f"{show(value)} is {_type_name(value)}, "
                           f"expected {_KIND_TEXT['parameters']}")
            return None
        flat = {}
        for key, item in value.items():
            # TOML turns `source.path = "x"` into a nested table; accept both spellings.
            entries = ([(f"{key}.{sub}", subvalue) for sub, subvalue in item.items()]
                       if isinstance(item, dict) else [(key, item)])
            for qualified, scalar in entries:
                where = f"{name}.{qualified}"
                if not _is_qualified(qualified):
                    self.add(where, f"{qualified!r} is not of the form 'instance.parameter'")
                elif isinstance(scalar, (dict, list)) or not isinstance(
                        scalar, (bool, int, float, str)):
                    self.add(where, f"{show(scalar)} is {_type_name(scalar)}, expected a number, "
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
            self.add(name, f"{show(value)} is {_type_name(value)}, expected {_KIND_TEXT['ports']}")
            return None
        ports = []
        for position, item in enumerate(value):
            if not isinstance(item, str) or not _is_qualified(item):
                self.add(f"{name}[{position}]", f"{item!r} is not an 'instance.port' string")
            elif item in ports:
                self.add(f"{name}[{position}]", f"{item!r} is listed twice")
            else:
                ports.append(item)
        return ports


def _is_multiple(step, base):
    ratio = step / base
    if not math.isfinite(ratio):   # e.g. 1e308 / 0.01: more steps than a float counts
        return False, ratio
    count = round(ratio)
    return count >= 1 and abs(ratio - count) <= STEP_TOLERANCE * ratio, ratio


@dataclass(frozen=True)
class Scenario:
    """A validated scenario.

    Attributes
    ----------
    name : str
        Scenario name.
    description : str
        Free text.
    system : pathlib.Path
        Absolute path of the ``.ssd``.
    stop_time : float
        End time in s (the run starts at 0).
    base_step : float
        Master step in s.
    steps : dict of str to float
        Communication step per instance in s, each an integer multiple of ``base_step``;
        instances not listed step every ``base_step``.
    seed : int
        Given to every instance that has a ``seed`` parameter (unless ``parameters`` sets it).
    parameters : dict of str to value
        Overrides keyed ``"instance.parameter"``.
    outputs : list of str
        ``"instance.port"`` to record; empty means every output.
    master : str
        ``"gauss-seidel"`` or ``"jacobi"``.
    max_steps : int
        Largest number of base steps accepted (a bound on the work, not a result input).
    faults : tuple of (str, Fault)
        ``(target instance, fault)`` per ``[[faults]]`` entry (:mod:`orchestrator.faults`).
    source : str
        Where the scenario came from (file path or ``"<dict>"``); not part of equality.
    """

    name: str
    description: str
    system: Path
    stop_time: float
    base_step: float
    steps: dict[str, float]
    seed: int
    parameters: dict[str, object]
    outputs: list[str]
    master: str
    max_steps: int = DEFAULT_MAX_STEPS
    faults: tuple = ()
    source: str = field(default="<dict>", compare=False)

    def __hash__(self):
        # The dict fields make the generated hash fail; the canonical JSON is hashable.
        return hash(json.dumps(self.to_dict(), sort_keys=True))

    def step(self, instance):
        """Communication step of ``instance`` in s (``base_step`` unless listed in ``steps``)."""
        return self.steps.get(instance, self.base_step)

    def step_ratio(self, instance):
        """How many base steps one step of ``instance`` spans (an integer >= 1)."""
        return round(self.step(instance) / self.base_step)

    @property
    def step_count(self):
        """Number of base steps from 0 to ``stop_time``."""
        return round(self.stop_time / self.base_step)

    def to_dict(self):
        """Return a plain, JSON-serialisable dict that :func:`scenario_from_dict` reads back."""
        return {
            "name": self.name,
            "description": self.description,
            "system": str(self.system),
            "stop_time": self.stop_time,
            "base_step": self.base_step,
            "steps": dict(sorted(self.steps.items())),
            "seed": self.seed,
            "parameters": dict(sorted(self.parameters.items())),
            "outputs": list(self.outputs),
            "master": self.master,
            "max_steps": self.max_steps,
            # only when there are faults, so a scenario without any hashes as it always did
            **({"faults": faults_to_dicts(self.faults)} if self.faults else {}),
        }

    def with_overrides(self, **changes):
        """Return a validated copy with some fields changed, e.g. for a sweep.

        ``parameters`` and ``steps`` are merged into the existing tables (so a sweep over one
        parameter keeps the others); every other field is replaced.

        Examples
        --------
        >>> fast = scenario.with_overrides(parameters={"planner.v_cruise": 0.4}, seed=7)  # doctest: +SKIP
        """
        data = self.to_dict()
        for key, value in changes.items():
            if key in ("parameters", "steps") and isinstance(value, dict):
                data[key] = {**data[key], **value}
            else:
                data[key] = value
        return scenario_from_dict(data, source=f"{self.source} with overrides")

    def input_hash(self, extra=None):
        """SHA-256 hex digest of everything in the scenario that can change a run's result.

        The name and description are left out; the ``.ssd`` enters by the SHA-256 of its
        content (its path if it is missing), so the same scenario hashes alike in any checkout.
        FMU contents are outside the scenario: pass their digests in ``extra`` (any
        JSON-serialisable value) to include them.
        """
        data = self.to_dict()
        del data["name"], data["description"], data["max_steps"]
        system = Path(data.pop("system"))
        data["system_sha256"] = (hashlib.sha256(system.read_bytes()).hexdigest()
                                 if system.is_file() else str(system))
        if extra is not None:
            data["extra"] = extra
        text = json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
        return hashlib.sha256(text.encode("utf-8")).hexdigest()


def scenario_from_dict(data, source="<dict>", base_dir=None, allow_outside=False):
    """Validate a scenario given as a dict (as TOML would give it).

    Parameters
    ----------
    data : dict
        Fields of :data:`SCHEMA`.
    source : str
        Name used in error messages (a file path, or ``"<dict>"``).
    base_dir : str or pathlib.Path, optional
        Directory that a relative ``system`` is resolved from, and whose ``../fmus`` holds the
        default system; without it, the current directory and the repository's ``fmus/``.
        File-valued parameters (``source.path = "waypoints.csv"``) resolve from it too and
        must stay inside it (:mod:`orchestrator.paths`).
    allow_outside : bool
        Accept file-valued parameters that lead outside ``base_dir``.

    Returns
    -------
    Scenario

    Raises
    ------
    ConfigError
        Listing every problem, one per line.
    """
    check = _Checker(source)
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: a scenario is a table of fields, got {_type_name(data)}")
    for key in data:
        if key not in SCHEMA:
            check.problems.append(
                f"{source}: unknown field {key!r}"
                + (f" (did you mean {close[0]!r}?)"
                   if (close := difflib.get_close_matches(key, SCHEMA, n=1)) else "")
                + f"; valid fields: {', '.join(sorted(SCHEMA))}")
    values = {}
    for name, spec in SCHEMA.items():
        if name not in data:
            if spec.required:
                check.problems.append(f"{source}: field '{name}' is required ({spec.help})")
            else:
                values[name] = spec.default
            continue
        value = data[name]
        if spec.kind == "number":
            values[name] = check.number(name, value, spec.minimum, spec.maximum)
        elif spec.kind == "integer":
            values[name] = check.integer(name, value, spec.minimum, spec.maximum)
        elif spec.kind == "string":
            values[name] = check.string(name, value)
        elif spec.kind == "choice":
            values[name] = check.choice(name, value, spec.choices)
        elif spec.kind == "steps":
            values[name] = check.steps(name, value)
        elif spec.kind == "parameters":
            values[name] = check.parameters(name, value)
        elif spec.kind == "ports":
            values[name] = check.ports(name, value)
        elif spec.kind == "faults":
            values[name] = check_faults(check, name, value)

    base = values.get("base_step")
    if base is not None:
        for instance, step in sorted((values.get("steps") or {}).items()):
            ok, ratio = _is_multiple(step, base)
            if not ok:
                check.add(f"steps.{instance}", f"{step!r} is not an integer multiple of "
                                               f"base_step {base!r} (ratio {ratio:.6g})")
        if values.get("stop_time") is not None:
            ok, ratio = _is_multiple(values["stop_time"], base)
            limit = values.get("max_steps")
            if limit is not None and ratio > limit + 0.5:
                check.add("stop_time", f"{values['stop_time']!r} s at base_step {base!r} s is "
                                       f"{ratio:.6g} steps, more than max_steps = {limit}; "
                                       "raise max_steps in the scenario for a longer run")
            elif not ok:
                check.add("stop_time", f"{values['stop_time']!r} is not an integer multiple of "
                                       f"base_step {base!r} (ratio {ratio:.6g})")

    if base_dir is not None and values.get("parameters"):
        values["parameters"] = _resolve_file_parameters(check, values["parameters"], base_dir,
                                                        allow_outside)

    system = values.get("system")
    if system is None and "system" not in data:
        system_path = default_system_path(base_dir)
    elif system is not None:
        system_path = Path(system)
        if not system_path.is_absolute():
            system_path = (Path(base_dir) if base_dir is not None else Path.cwd()) / system_path
        system_path = system_path.resolve()
    else:
        system_path = None
    if system_path is not None and not system_path.is_file():
        what = "is a directory" if system_path.is_dir() else "does not exist"
        check.add("system", f"{str(system_path)!r} {what} (a path to an .ssd file)")
    elif system_path is not None:
        _check_against_system(check, values, system_path, allow_outside)

    if len(check.problems) == 1:  # one problem, one line
        raise ConfigError(check.problems[0])
    if check.problems:
        count = len(check.problems)
        raise ConfigError(f"{source}: {count} problems in the scenario:\n"
                          + "\n".join(f"  {p}" for p in check.problems))
    name = values["name"]
    if name is None:
        name = Path(source).stem if source != "<dict>" else "scenario"
    return Scenario(name=name, description=values["description"], system=system_path,
                    stop_time=values["stop_time"], base_step=values["base_step"],
                    steps=dict(values["steps"]), seed=values["seed"],
                    parameters=dict(values["parameters"]), outputs=list(values["outputs"]),
                    master=values["master"], max_steps=values["max_steps"],
                    faults=tuple(values["faults"]), source=str(source))


@functools.lru_cache(maxsize=32)
def model_ranges(model_name):
    """The valid-range table of a sonotrack FMU by model name, or None for another FMU.

    Examples
    --------
    >>> model_ranges("RobotPlant").parameters["mass"].text()
    '[0.1, 1000.0] kg'
    """
    from components.common.ranges import load_ranges
    from components import FMU_PACKAGES

    part = FMU_PACKAGES.get(model_name)
    return load_ranges(part) if part is not None else None


@functools.lru_cache(maxsize=32)
def _read_system(path, _mtime_ns, _size, allow_outside=False):
    from orchestrator.ssp import read_ssd

    return read_ssd(path, allow_outside=allow_outside)


def _check_against_system(check, values, system_path, allow_outside=False):
    """Check instances, steps and parameter values against the .ssd and the FMUs' ranges."""
    try:
        stat = system_path.stat()
        description = _read_system(system_path, stat.st_mtime_ns, stat.st_size, allow_outside)
    except ConfigError as error:
        check.problems.append(str(error))
        return
    instances = {c.name: c for c in description.components}
    names = ", ".join(instances)
    tables = {c.name: model_ranges(Path(c.source).stem) for c in description.components}
    steps = values.get("steps") or {}
    base = values.get("base_step")
    for instance in sorted(steps):
        if instance not in instances:
            check.add(f"steps.{instance}", f"no instance {instance!r} in {system_path}"
                                           f"{_suggestion(instance, instances)}; instances: {names}")
    at_base_step = []
    for instance, table in tables.items():
        step = steps.get(instance, base)
        if table is None or step is None or not _is_number(step):
            continue
        if table.step.problem(step) is None:
            continue
        if instance in steps:
            check.add(f"steps.{instance}", f"{step!r} s is outside the step range of "
                                           f"{instance} ({table.model}): {table.step.text()}")
        else:
            at_base_step.append(f"{instance} {table.step.text()}")
    if at_base_step:
        check.add("base_step", f"{base!r} s (the step of every instance not in [steps]) is "
                               f"outside the step range of {'; '.join(at_base_step)}")
    overridden = set()
    for key, value in sorted((values.get("parameters") or {}).items()):
        instance, _, name = key.partition(".")
        where = f"parameters.{key}"
        if instance not in instances:
            check.add(where, f"no instance {instance!r} in {system_path}"
                             f"{_suggestion(instance, instances)}; instances: {names}")
            continue
        overridden.add(key)
        table = tables[instance]
        if table is None:
            continue   # not a sonotrack FMU: the system layer checks its model description
        entry = table.parameters.get(name)
        if entry is None:
            check.add(where, f"{instance} ({table.model}) has no parameter {name!r}"
                             f"{_suggestion(name, table.parameters)}; parameters: "
                             f"{', '.join(table.parameters)}")
            continue
        problem = entry.problem(value)
        if problem is not None:
            check.add(where, f"{instance}.{problem}")
    for component in description.components:
        table = tables[component.name]
        if table is None:
            continue
        for name, bound in sorted(component.parameters.items()):
            entry = table.parameters.get(name)
            if f"{component.name}.{name}" in overridden or entry is None:
                continue   # unknown names are reported by the system layer with the FMU's list
            problem = entry.problem(bound.value)
            if problem is not None:
                where = getattr(bound, "source", None) or system_path
                check.problems.append(f"{where}: parameter binding of component "
                                      f"'{component.name}': {component.name}.{problem}")


def _suggestion(name, choices):
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


def _resolve_file_parameters(check, parameters, base_dir, allow_outside):
    """File-valued parameters as absolute paths, resolved from the scenario's folder."""
    from orchestrator.paths import confine, names_a_file

    resolved = dict(parameters)
    for key, value in parameters.items():
        if names_a_file(value):
            path, problem = confine(value, base_dir, allow_outside)
            if problem is not None:
                check.add(f"parameters.{key}", problem)
            else:
                resolved[key] = str(path)
    return resolved


def load_scenario(path, allow_outside=False):
    """Read and validate a TOML scenario file.

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.toml`` file. A relative ``system`` resolves from its directory; without one, the
        system is ``<its directory>/../fmus/SystemStructure.ssd``. File-valued parameters
        resolve from its directory and must stay inside it.
    allow_outside : bool
        Accept file-valued parameters outside the scenario's directory (``--allow-outside``).

    Returns
    -------
    Scenario

    Raises
    ------
    ConfigError
        If the file cannot be read, is not valid TOML, or breaks the schema (all problems
        listed, each naming the file and field).

    Examples
    --------
    >>> scenario = load_scenario("scenarios/s_curve.toml")   # doctest: +SKIP
    >>> scenario.step("planner")                             # doctest: +SKIP
    0.02
    """
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"{path}: is a directory, expected a TOML scenario file")
    if not path.exists():
        raise ConfigError(f"{path}: scenario file does not exist")
    try:
        raw = path.read_bytes()
    except OSError as error:
        raise ConfigError(f"{path}: cannot read the scenario ({error.strerror or error})") \
            from error
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as error:
        line = raw[:error.start].count(b"\n") + 1
        raise ConfigError(f"{path}: line {line}: not UTF-8 text (byte 0x{raw[error.start]:02x} "
                          f"at position {error.start}); TOML files are UTF-8") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"{path}: not valid TOML ({error})") from None
    except RecursionError:
        raise ConfigError(f"{path}: not a scenario: tables or arrays nested too deeply "
                          "for TOML parsing") from None
    return scenario_from_dict(data, source=str(path), base_dir=path.resolve().parent,
                              allow_outside=allow_outside)
