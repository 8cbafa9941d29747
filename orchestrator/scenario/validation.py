"""A scenario given as a dict, checked: :func:`check_scenario` returns its fields or raises.

It applies the schema field by field, checks the steps against the base step, resolves the
``.ssd`` and file-valued parameters, checks everything against the system and the FMUs' valid
ranges, and raises one :class:`ConfigError` listing every problem. It returns plain fields, not
a :class:`~orchestrator.scenario.Scenario`, so that the model, which re-validates in
:meth:`~orchestrator.scenario.Scenario.with_overrides`, can import it without a cycle.
"""

from __future__ import annotations

from pathlib import Path

from components.common.errors import ConfigError

from .faults import check_faults
from .locations import resolve_file_parameters, resolve_system_path
from .schema import SCHEMA, FieldChecker, check_step_multiples, suggestion, type_name
from .system_checks import check_against_system

__all__ = ["check_scenario"]


def check_scenario(data, source="<dict>", base_dir=None, allow_outside=False):
    """Validate a scenario given as a dict (as TOML would give it); return its fields.

    The parameters are those of :func:`~orchestrator.scenario.scenario_from_dict`, which builds
    the :class:`~orchestrator.scenario.Scenario` from what this returns.

    Returns
    -------
    dict
        The keyword arguments of :class:`~orchestrator.scenario.Scenario`, checked.

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
    return dict(name=name, description=values["description"], system=system_path,
                stop_time=values["stop_time"], base_step=values["base_step"],
                steps=dict(values["steps"]), seed=values["seed"],
                parameters=dict(values["parameters"]), outputs=list(values["outputs"]),
                master=values["master"], max_steps=values["max_steps"],
                faults=tuple(values["faults"]), source=str(source))
