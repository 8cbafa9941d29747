"""Flatten nested JSON-like values (dicts, lists) into ``(path, leaf)`` pairs for comparisons.

Shared by tests/unit/orchestrator/run/test_summary.py and tests/integration/orchestrator/run/test_summary.py, which
compare a run's summary figures with their reference key by key.
"""

__all__ = ["leaves"]


def leaves(value, prefix=""):
    """Yield ``(path, leaf)`` for every non-container value inside ``value``.

    Parameters
    ----------
    value : dict, list or scalar
        The nested value, e.g. a parsed summary.json.
    prefix : str
        The path of ``value`` itself; dict keys add ``.key``, list items ``[i]``.

    Yields
    ------
    tuple of (str, object)
        The leaf's path (``".a.b[2]"``) and the leaf.
    """
    if isinstance(value, dict):
        for key, item in value.items():
            yield from leaves(item, f"{prefix}.{key}")
    elif isinstance(value, list):
        for i, item in enumerate(value):
            yield from leaves(item, f"{prefix}[{i}]")
    else:
        yield prefix, value
