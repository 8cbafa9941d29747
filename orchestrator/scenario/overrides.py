"""Changes typed on a command line: ``--set instance.parameter=value`` and ``--stop-time``.

A value is read the way TOML would give it for a scalar (``true``/``false`` a boolean, then an
integer, then a float, else the text), and the changed scenario is validated exactly as a file
would be (:func:`~orchestrator.scenario.validation.check_scenario`): an unknown instance or
parameter, a value of the wrong type or outside its valid range is one line naming it and the
valid choices. A word without ``=`` gets a hint with the spelling that works, because the
usual slip, ``--set planner.v_cruise 0.2``, leaves the value to be read as something else.

Examples
--------
>>> parse_value("0.3"), parse_value("7"), parse_value("TRUE"), parse_value("straight")
(0.3, 7, True, 'straight')
>>> parse_override("planner.v_cruise=0.25")
('planner.v_cruise', 0.25)
>>> assignment_hint("planner.v_cruise", stray="0.2")
"--set 'planner.v_cruise': no '='; write it as one word: --set planner.v_cruise=0.2"
"""

from pathlib import Path

from components.common.errors import ConfigError

from .model import scenario_from_dict

__all__ = ["apply_overrides", "assignment_hint", "parse_override", "parse_value"]

EXAMPLE = "planner.v_cruise=0.2"


def parse_value(text):
    """A value typed on the command line: boolean, integer, float, or the text itself."""
    lowered = text.strip().lower()
    if lowered in ("true", "false"):
        return lowered == "true"
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return text


def assignment_hint(text, stray=None, example_values="0.2"):
    """The one line for a ``--set`` word that has no ``=`` in it.

    Parameters
    ----------
    text : str
        The word given after ``--set``.
    stray : str, optional
        The next word on the command line, if it was taken for something else (the scenario):
        most likely the value the user meant.
    example_values : str
        Values shown in the hint when there is no stray word.

    Returns
    -------
    str
    """
    key = text.strip()
    values = stray if stray is not None else example_values
    if "." not in key or not key.partition(".")[2]:
        return (f"--set {text!r}: expected instance.parameter=value with no spaces, "
                f"e.g. --set {EXAMPLE}")
    return f"--set {text!r}: no '='; write it as one word: --set {key}={values}"


def parse_override(text, stray=None):
    """``instance.parameter=value`` into ``(key, value)``.

    Parameters
    ----------
    text : str
        The word after ``--set``.
    stray : str, optional
        The next word on the command line (see :func:`assignment_hint`).

    Raises
    ------
    ConfigError
        Without ``=``, an instance, a parameter or a value; or with a list of values (a run
        takes one value; a sweep takes several).
    """
    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep:
        raise ConfigError(assignment_hint(text, stray))
    instance, dot, name = key.partition(".")
    if not (instance and dot and name) or not value.strip():
        raise ConfigError(f"--set {text!r}: expected instance.parameter=value, e.g. "
                          f"--set {EXAMPLE}")
    if "," in value:
        raise ConfigError(f"--set {text!r}: a run takes one value per parameter; to run "
                          f"several, use `sonotrack sweep --set {key}={value.strip()}`")
    return key, parse_value(value.strip())


def apply_overrides(scenario, stop_time=None, settings=(), stray=None):
    """The scenario with a new stop time and parameter values, validated as a file would be.

    Parameters
    ----------
    scenario : Scenario
        The loaded scenario.
    stop_time : float, optional
        New ``stop_time`` in s (checked like the field: > 0, a multiple of ``base_step``,
        within ``max_steps``).
    settings : sequence of str
        ``instance.parameter=value`` words; a parameter given twice is refused. A relative
        file-valued value (a waypoint CSV) is a file in the working folder.
    stray : str, optional
        The word the command line read as the scenario, for the hint of a ``--set`` without
        ``=``.

    Returns
    -------
    Scenario
        ``scenario`` itself when nothing changes.

    Raises
    ------
    ConfigError
        Every problem at once, each naming the field or the ``--set`` word.
    """
    from orchestrator.files.paths import names_a_file

    parameters = {}
    for text in settings:
        key, value = parse_override(text, stray)
        if key in parameters:
            raise ConfigError(f"--set {key} is given twice; give it once")
        parameters[key] = str(Path(value).resolve()) if names_a_file(value) else value
    if stop_time is None and not parameters:
        return scenario
    data = scenario.to_dict()
    data["parameters"] = {**data["parameters"], **parameters}
    if stop_time is not None:
        data["stop_time"] = stop_time
    given = " and ".join(part for part, used in (("--stop-time", stop_time is not None),
                                                 ("--set", bool(parameters))) if used)
    return scenario_from_dict(data, source=f"{scenario.source} with {given}")
