"""Check a scenario against its system before any FMU is loaded.

The ``.ssd`` (read as XML, cached by path, mtime and size) names the instances; the valid-range
tables of the FMUs it uses (``components/<part>/ranges.toml``, the same tables the FMUs enforce
and export as ``min``/``max``) give the step ranges and parameter ranges. ``[steps]`` may name
only instances of the system, every instance's step must lie in its FMU's step range, and every
parameter value, from the scenario or bound in the ``.ssd`` or an ``.ssv``, must have the right
type and lie in its valid range. FMUs the tables do not know are checked against their model
descriptions by the system layer (:mod:`orchestrator.system`).
"""

from __future__ import annotations

import functools
from pathlib import Path

from components.common.errors import ConfigError

from .schema import suggestion, is_number

__all__ = ["model_ranges", "check_against_system"]


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


def check_against_system(check, values, system_path, allow_outside=False):
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
                                           f"{suggestion(instance, instances)}; instances: {names}")
    at_base_step = []
    for instance, table in tables.items():
        step = steps.get(instance, base)
        if table is None or step is None or not is_number(step):
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
                             f"{suggestion(instance, instances)}; instances: {names}")
            continue
        overridden.add(key)
        table = tables[instance]
        if table is None:
            continue   # not a sonotrack FMU: the system layer checks its model description
        entry = table.parameters.get(name)
        if entry is None:
            check.add(where, f"{instance} ({table.model}) has no parameter {name!r}"
                             f"{suggestion(name, table.parameters)}; parameters: "
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
