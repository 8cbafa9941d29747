"""Read a TOML scenario file into a :class:`~orchestrator.scenario.Scenario`.

:func:`load_scenario` reads the file (UTF-8, valid TOML) with one-line errors naming it, then
validates its table with :func:`~orchestrator.scenario.scenario_from_dict`.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from components.common.errors import ConfigError

from .model import scenario_from_dict

__all__ = ["load_scenario"]


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
