"""A scenario's ``[[faults]]`` section: checked before t0, then parameters of the FMUs it targets.

Each entry names a ``kind`` (:data:`components.common.faults.KINDS`), the ``target`` instance,
``start`` and ``end`` in s (no ``end``: permanent), a ``magnitude`` and, for some kinds, a
``channel`` (microphone or wheel) or a floor ``region``. The scenario layer checks the entries'
own rules (:func:`check_faults`); the run layer checks that each target exists and is a model
of the right kind and sets its ``fault_schedule`` String parameter (:func:`fault_parameters`).
Nothing else happens in the master: the FMU applies its schedule itself.

Examples
--------
A TOML scenario::

    [[faults]]
    kind = "mic_dead"
    target = "localizer"
    channel = "M2"
    start = 4.0
    end = 8.0
"""

from components.common.faults import KINDS, check_entry, encode_schedule
from components.common.errors import ConfigError

__all__ = ["check_faults", "fault_parameters", "faults_to_dicts", "SCHEDULE_PARAMETER"]

SCHEDULE_PARAMETER = "fault_schedule"


def check_faults(check, name, value):
    """Check a scenario's ``faults`` list; add every problem to ``check``.

    Parameters
    ----------
    check : orchestrator.scenario.schema.FieldChecker
        Collects ``(field, message)`` problems of the scenario source.
    name : str
        The field name (``"faults"``).
    value : object
        What the scenario gave.

    Returns
    -------
    tuple of (str, Fault) or None
        ``(target, fault)`` per entry, or None if any entry is bad.
    """
    if not isinstance(value, list):
        check.add(name, f"{value!r} is not a list of fault tables ([[faults]] entries with "
                        f"kind, target, start, end, magnitude); kinds: {', '.join(KINDS)}")
        return None
    faults, ok = [], True
    for index, entry in enumerate(value):
        fault, target, problems = check_entry(entry)
        for field, message in problems:
            check.add(f"{name}[{index}].{field}" if field else f"{name}[{index}]", message)
        ok = ok and not problems
        if fault is not None:
            faults.append((target, fault))
    return tuple(faults) if ok else None


def faults_to_dicts(faults):
    """The scenario's faults as plain dicts that :func:`check_faults` reads back."""
    out = []
    for target, fault in faults:
        data = {"target": target, **fault.to_json()}
        if data["end"] is None:
            del data["end"]
        out.append(data)
    return out


def fault_parameters(system, faults, source="scenario"):
    """Return ``{instance: fault_schedule text}`` for the instances the faults target.

    Parameters
    ----------
    system : orchestrator.system.System
        The loaded system (instances and their model descriptions).
    faults : sequence of (str, Fault)
        As in :attr:`orchestrator.scenario.Scenario.faults`.
    source : str
        Scenario name for messages.

    Raises
    ------
    ConfigError
        One line per fault whose target is not an instance of the kind's model, naming the
        valid targets.
    """
    by_target, problems = {}, []
    models = {c.name: c.model_description.modelName for c in system.components}
    for index, (target, fault) in enumerate(faults):
        model = KINDS[fault.kind].model
        valid = [name for name, m in models.items() if m == model]
        if models.get(target) != model:
            problems.append(f"{source}: field 'faults[{index}].target': {target!r} is not an "
                            f"instance of {model} (which applies {fault.kind}); "
                            f"valid targets: {', '.join(valid) or 'none in this system'}")
            continue
        by_target.setdefault(target, []).append(fault)
    if problems:
        raise ConfigError("\n".join(problems))
    return {target: encode_schedule(items) for target, items in by_target.items()}
