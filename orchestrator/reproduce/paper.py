"""The paper's printed figures (``orchestrator/data/paper_tables.toml``)."""

import tomllib
from importlib import resources
from pathlib import Path

from components.common.errors import ConfigError

__all__ = ["load_paper_tables"]


def load_paper_tables(path=None):
    """Read the paper's printed figures.

    Parameters
    ----------
    path : path-like, optional
        A TOML file; default ``orchestrator/data/paper_tables.toml`` (package data).

    Returns
    -------
    dict
        The TOML tables (``table1_without_curvature``, ``table2_with_curvature``, ...).

    Raises
    ------
    ConfigError
        If the file cannot be read or is not valid TOML.
    """
    try:
        if path is None:
            text = resources.files("orchestrator").joinpath("data/paper_tables.toml").read_text()
            where = "orchestrator/data/paper_tables.toml"
        else:
            where = str(path)
            text = Path(path).read_text()
        return tomllib.loads(text)
    except OSError as exc:
        raise ConfigError(f"{where}: cannot read the paper tables ({exc})") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{where}: not valid TOML ({exc})") from exc
