"""Build a :class:`~orchestrator.scenario.Scenario` from a dict or a TOML file.

:func:`scenario_from_dict` applies the schema field by field, checks the steps against the base
step, resolves the ``.ssd`` and file-valued parameters, checks everything against the system and
the FMUs' valid ranges, and raises one :class:`ConfigError` listing every problem.
:func:`load_scenario` reads the TOML file first (UTF-8, valid TOML) with the same one-line
errors.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from components.common.errors import ConfigError
from orchestrator.scenario.faults import check_faults

from .locations import resolve_file_parameters, resolve_system_path
from .model import Scenario
from .schema import SCHEMA, FieldChecker, check_step_multiples, suggestion, type_name
from .system_checks import check_against_system

__all__ = ["scenario_from_dict", "load_scenario"]


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
        must stay inside it (:mod:`orchestrator.files.paths`).
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
    check = FieldChecker(source)
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: a scenario is a table of fields, got {type_name(data)}")
    for key in data:
        if key not in SCHEMA:
            check.problems.append(f"{source}: unknown field {key!r}{suggestion(key, SCHEMA)}; "
                                  f"valid fields: {', '.join(sorted(SCHEMA))}")
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

    check_step_multiples(check, values)

    if base_dir is not None and values.get("parameters"):
        values["parameters"] = resolve_file_parameters(check, values["parameters"], base_dir,
                                                        allow_outside)

    system_path = resolve_system_path(check, values.get("system"), "system" in data, base_dir)
    if system_path is not None:
        check_against_system(check, values, system_path, allow_outside)

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
