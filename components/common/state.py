"""JSON-safe snapshots of a model core's complete internal state.

pythonfmu saves only registered variables and serialises with JSON. A core keeps its state in
plain attributes (floats, ints, bools, strings, lists, dicts, numpy arrays, numpy random
generators, nested objects); :func:`snapshot` turns such an object into JSON-safe data and
:func:`restore` writes it back in place, bit for bit (floats go through ``repr``, which
round-trips exactly).

numpy is not imported here: a model whose core does not use numpy (RobotPlant,
CurvaturePlanner) then never loads it, and its portable FMU carries none (docs/fmi_binary.md,
"Which models need numpy"). A value can only be a numpy object if numpy is already loaded, so
:func:`snapshot` looks it up in ``sys.modules``; a model that holds arrays or generators imports
numpy itself when its module loads, so the import in :func:`restore` finds it loaded (a first
import of numpy inside an FMU call can crash pythonfmu's binary).
"""

import sys

__all__ = ["snapshot", "restore"]

_ARRAY = "__ndarray__"
_GENERATOR = "__generator__"
_OBJECT = "__object__"
_TUPLE = "__tuple__"
_NOT_NUMPY = object()


def snapshot(value):
    """Return a JSON-safe deep copy of ``value``.

    Parameters
    ----------
    value : object
        A scalar, container, numpy array or generator, or an object whose ``__dict__`` holds those.

    Returns
    -------
    object
        Nested dicts and lists of JSON scalars, with type tags where needed to rebuild.
    """
    if value is None or isinstance(value, (bool, str)):
        return value
    np = sys.modules.get("numpy")  # not loaded: no value is a numpy object
    if np is not None:
        numpy_value = _snapshot_numpy(value, np)
        if numpy_value is not _NOT_NUMPY:
            return numpy_value
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        return float(value)
    if isinstance(value, tuple):
        return {_TUPLE: [snapshot(v) for v in value]}
    if isinstance(value, list):
        return [snapshot(v) for v in value]
    if isinstance(value, dict):
        return {str(k): snapshot(v) for k, v in value.items()}
    if hasattr(value, "__dict__"):
        # Attributes a class lists in STATE_CONSTANTS are fixed at construction from
        # parameters (a fault schedule): the instance restored into already holds them.
        constants = getattr(type(value), "STATE_CONSTANTS", ())
        return {_OBJECT: {k: snapshot(v) for k, v in vars(value).items()
                          if not callable(v) and k not in constants}}
    raise TypeError(f"cannot snapshot a value of type {type(value).__name__}")


def _snapshot_numpy(value, np):
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    if isinstance(value, np.ndarray):
        return {_ARRAY: value.tolist(), "dtype": value.dtype.str, "shape": list(value.shape)}
    random = sys.modules.get("numpy.random")  # np.random would import it: not loaded, no generator
    if random is not None and isinstance(value, random.Generator):
        return {_GENERATOR: _plain(value.bit_generator.state, np)}
    return _NOT_NUMPY


def restore(target, saved):
    """Write a :func:`snapshot` of an object back into ``target`` in place.

    Parameters
    ----------
    target : object
        The object the snapshot was taken from (or one of the same class).
    saved : dict
        The value :func:`snapshot` returned for it.
    """
    for name, value in saved[_OBJECT].items():
        current = getattr(target, name, None)
        setattr(target, name, _rebuild(value, current))


def _rebuild(saved, current):
    if isinstance(saved, list):
        return [_rebuild(v, None) for v in saved]
    if not isinstance(saved, dict):
        return saved
    if _ARRAY in saved:
        import numpy as np  # loaded already by the model that saved an array

        return np.array(saved[_ARRAY], dtype=np.dtype(saved["dtype"])).reshape(saved["shape"])
    if _GENERATOR in saved:
        import numpy as np
        import numpy.random  # noqa: F401

        generator = current if isinstance(current, np.random.Generator) else np.random.default_rng()
        generator.bit_generator.state = saved[_GENERATOR]
        return generator
    if _TUPLE in saved:
        return tuple(_rebuild(v, None) for v in saved[_TUPLE])
    if _OBJECT in saved:
        if current is None or not hasattr(current, "__dict__"):
            raise TypeError("cannot restore a nested object without an instance to restore into")
        restore(current, saved)
        return current
    return {k: _rebuild(v, current.get(k) if isinstance(current, dict) else None)
            for k, v in saved.items()}


def _plain(value, np):
    if isinstance(value, dict):
        return {k: _plain(v, np) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.integer):
        return int(value)
    return value
