"""The orchestrator's JSON policy: plain JSON types, non-finite numbers written as ``null``.

JSON has no NaN or infinity; Python's :mod:`json` writes them as the tokens ``NaN`` and
``Infinity`` that strict readers refuse. Every JSON file the orchestrator writes (a run's
``summary.json``, ``verification.json``, ``reproduction.json``) therefore goes through
:func:`json_ready`, which writes a non-finite float as ``None``, and :func:`dumps`, which then
serialises with ``allow_nan=False``: a NaN that escaped the conversion is an error, never an
invalid token in a file.

:func:`json_ready` also makes plain types of what the reports hold: numpy scalars and arrays
(through their ``tolist``), tuples (lists), paths (POSIX text) and objects that know their JSON
form (a ``to_dict()`` method). Finite values are left as they are, so for them :func:`dumps`
gives the same text as :func:`json.dumps` with the same arguments.

Examples
--------
>>> dumps({"gap_m": 0.5, "settling_s": float("nan"), "margin": [float("inf"), 2]})
'{"gap_m": 0.5, "settling_s": null, "margin": [null, 2]}'
"""

import json
import math
from pathlib import PurePath

__all__ = ["dumps", "json_ready"]

_PLAIN_KEYS = (str, int, float, bool, type(None))


def json_ready(value):
    """A copy of ``value`` in plain JSON types, non-finite floats as None.

    Parameters
    ----------
    value : object
        Dicts, lists, tuples, numbers (Python or numpy), strings, None, paths, or objects
        with a ``to_dict()`` method, nested in any way.

    Returns
    -------
    object
        Dict keys that JSON cannot hold are written with :class:`str`; a type JSON does not
        know is left as it is (:func:`dumps` then raises ``TypeError``).
    """
    if isinstance(value, dict):
        return {(k if isinstance(k, _PLAIN_KEYS) else str(k)): json_ready(v)
                for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, (str, bool, int)) or value is None:
        return value
    if isinstance(value, float):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, PurePath):
        return value.as_posix()
    if hasattr(value, "to_dict"):
        return json_ready(value.to_dict())
    if hasattr(value, "tolist"):   # numpy scalars and arrays
        return json_ready(value.tolist())
    return value


def dumps(value, **options):
    """``json.dumps`` of :func:`json_ready` ``(value)`` with ``allow_nan=False``.

    Parameters
    ----------
    value : object
        See :func:`json_ready`.
    **options
        Passed to :func:`json.dumps` (``indent``, ``sort_keys``...).

    Returns
    -------
    str

    Raises
    ------
    ValueError
        Never for a NaN or infinity in ``value`` (they become null); ``allow_nan=False``
        is the guard should one get past the conversion.
    """
    return json.dumps(json_ready(value), allow_nan=False, **options)
