"""The scenarios shipped in the repository's ``scenarios/`` folder, found by name from anywhere.

``sonotrack run s_curve`` works from any working folder: a name that is not a file there is
looked up among the shipped scenarios (``s_curve``, ``faults/low_snr``; with or without
``.toml``). A name that is neither gets one line with the closest shipped name and the list.

Examples
--------
>>> "s_curve" in shipped_scenarios() and "faults/low_snr" in shipped_scenarios()
True
>>> find_scenario("s_curve").name
's_curve.toml'
"""

import difflib
from pathlib import Path

from components.common.errors import ConfigError

__all__ = ["SCENARIO_DIR", "find_scenario", "shipped_scenarios"]

# the repository's scenarios/, beside the orchestrator package
SCENARIO_DIR = Path(__file__).resolve().parents[2] / "scenarios"


def shipped_scenarios():
    """``name -> path`` of every shipped scenario, names relative to ``scenarios/`` without
    ``.toml`` (``faults/low_snr``), top-level ones first."""
    paths = sorted(SCENARIO_DIR.rglob("*.toml"),
                   key=lambda p: (len(p.relative_to(SCENARIO_DIR).parts), str(p)))
    return {p.relative_to(SCENARIO_DIR).with_suffix("").as_posix(): p for p in paths}


def find_scenario(text):
    """The scenario file ``text`` names: a path, else a shipped scenario's name.

    Parameters
    ----------
    text : str or path-like
        A path (relative to the working folder), or a shipped name such as ``s_curve``,
        ``s_curve.toml`` or ``faults/low_snr``.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ConfigError
        One line naming ``text``, the closest shipped name and every shipped name.
    """
    path = Path(text)
    if path.is_file():
        return path
    shipped = shipped_scenarios()
    name = path.as_posix().removeprefix("scenarios/").removesuffix(".toml")
    if name in shipped:   # also when a folder of that name is here (a run's output, say)
        return shipped[name]
    if path.exists():   # a folder: the loader says why it is not a scenario
        return path
    close = difflib.get_close_matches(name, list(shipped), n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    listed = ", ".join(shipped) if shipped else f"none (no .toml in {SCENARIO_DIR})"
    raise ConfigError(f"scenario {str(text)!r} is neither a file nor a shipped scenario{hint}; "
                      f"shipped scenarios: {listed}")
