"""One FMU instance behind one handle: value references resolved once, batched get/set.

:class:`FmuInstance` wraps fmpy's :class:`~fmpy.fmi2.FMU2Slave`. Ports are resolved to value
references once (:meth:`FmuInstance.port_group`); the hot path then reads and writes
preallocated ctypes arrays through the raw FMI functions, so a step allocates nothing.
Every FMI call that fails raises fmpy's ``FMICallException``; log lines the FMU sends are
kept in :attr:`FmuInstance.messages` so an error can name what the FMU said.

Logging: fmpy's printf-formatting proxy (``fmpy.logging.addLoggerProxy``) keeps *one* logger
per process, the last one registered. So every handle registers the same module-level
dispatcher, and each handle's callbacks carry its own ``componentEnvironment`` (a key into
:data:`_ROUTES`), which the FMU passes back with every message: each line lands in the handle
that owns the instance, however many FMUs the process holds.
"""

import ctypes
import itertools
import numbers
import re
import weakref
from collections import deque
from dataclasses import dataclass
from pathlib import Path

from components.common.errors import ConfigError

__all__ = ["FmuInstance", "PortGroup", "extract_once", "model_description"]

_EXTRACTED = {}
# sha256 of an FMU's bytes -> its parsed, validated model description (see model_description)
_DESCRIPTIONS = {}
_DESCRIPTIONS_KEPT = 64
# componentEnvironment key -> weak reference to the FmuInstance that owns it.
_ROUTES = {}
_KEYS = itertools.count(1)
# Lines whose componentEnvironment names no live handle (e.g. an FMU instantiated elsewhere).
UNROUTED = deque(maxlen=200)
_MESSAGES_KEPT = 1000   # per handle; a model that logs every step must not grow memory
# pythonfmu 0.7.0 adds this line (status fatal) after any Python exception; it explains nothing.
_INTERPRETER_TRAILER = "Fatal py exception encountered"
# sonotrack's binary reports a Python exception as "<fmi2 function>: <method>: <message>".
_BINARY_PREFIX = re.compile(r"fmi2\w+: [\w ]+: ")
_STATUS = ["ok", "warning", "discard", "error", "fatal", "pending"]
_CTYPE = {"Real": ctypes.c_double, "Integer": ctypes.c_int, "Boolean": ctypes.c_int}


def extract_once(path):
    """Return (model description, unpacked folder) of an FMU, unpacked safely into the
    content-addressed cache (:func:`orchestrator.fmu.cache.extract_fmu`); once per process and
    file version (a file rewritten in place is unpacked again).

    The folder is named by the digest of the FMU's bytes, so the description parsed for that
    digest (by :func:`model_description`, e.g. when the system was loaded) is reused.
    """
    import fmpy

    from orchestrator.fmu.cache import extract_fmu

    path = Path(path).resolve()
    try:
        stat = path.stat()
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such FMU file") from None
    # a file rebuilt in place (another size, mtime or inode) is unpacked again: reusing the
    # first folder would run the earlier build's code
    signature = (stat.st_size, stat.st_mtime_ns, stat.st_ino)
    cached = _EXTRACTED.get(path)
    if cached is None or cached[0] != signature:
        unzip_dir = extract_fmu(path)
        description = _DESCRIPTIONS.get(unzip_dir.name)
        if description is None:
            description = fmpy.read_model_description(str(unzip_dir))
            _remember(unzip_dir.name, description)
        cached = _EXTRACTED[path] = (signature, (description, str(unzip_dir)))
    return cached[1]


def model_description(path):
    """The model description of an ``.fmu`` file, parsed and validated once per content.

    The file is read once and its bytes are both hashed and parsed, so a description is
    always cached under the digest of the very bytes it came from: a rebuilt FMU has another
    digest and is parsed anew. fmpy's validation loads the FMI schema on every call (about
    as long as the parse itself); a run used to pay it twice per FMU (loading the system,
    then instantiating).

    Raises
    ------
    Exception
        Whatever :func:`fmpy.read_model_description` raises for an unreadable FMU (fmpy
        raises bare exceptions for invalid XML).
    """
    import hashlib
    import io

    import fmpy

    data = Path(path).read_bytes()
    digest = hashlib.sha256(data).hexdigest()
    description = _DESCRIPTIONS.get(digest)
    if description is None:
        description = fmpy.read_model_description(io.BytesIO(data))
        _remember(digest, description)
    return description


def _remember(digest, description):
    if len(_DESCRIPTIONS) >= _DESCRIPTIONS_KEPT:
        del _DESCRIPTIONS[next(iter(_DESCRIPTIONS))]   # the oldest
    _DESCRIPTIONS[digest] = description


@dataclass
class PortGroup:
    """Ports of one FMU of one type, with value references and a preallocated buffer."""

    type: str
    names: tuple
    references: object  # ctypes array of fmi2ValueReference
    values: object      # ctypes array of the port type
    get_function: object = None  # raw fmi2Get<type>
    set_function: object = None  # raw fmi2Set<type>

    def __len__(self):
        return len(self.names)


class FmuInstance:
    """An instantiated FMI 2.0 co-simulation slave.

    Parameters
    ----------
    path : path-like
        The ``.fmu`` file.
    instance_name : str
        Name of this instance (appears in the FMU's log lines and in errors).
    reusable : bool
        Keep the instance after :meth:`terminate` so that the next :meth:`instantiate`
        resets it (``fmi2Reset``) instead of instantiating anew; :meth:`release` frees it.
    """

    def __init__(self, path, instance_name, reusable=False):
        from fmpy.fmi2 import FMU2Slave

        self.path = Path(path)
        self.name = instance_name
        self.description, unzip_dir = extract_once(path)
        self.variables = {v.name: v for v in self.description.modelVariables}
        self.messages = deque(maxlen=_MESSAGES_KEPT)
        self._route_key = next(_KEYS)
        if len(_ROUTES) > 256:
            for key in [k for k, ref in _ROUTES.items() if ref() is None]:
                del _ROUTES[key]
        _ROUTES[self._route_key] = weakref.ref(self)
        self._slave = FMU2Slave(guid=self.description.guid, unzipDirectory=unzip_dir,
                                modelIdentifier=self.description.coSimulation.modelIdentifier,
                                instanceName=instance_name)
        self._callbacks = self._make_callbacks()
        self._instantiated = False
        self._fatal = False
        self._can_terminate = False  # FMI 2.0: only from stepComplete or stepFailed
        self.reusable = reusable
        self._resettable = False  # allocated, terminated, and may be reset for another run
        self._do_step = self._raw("fmi2DoStep")

    # ----- life cycle ------------------------------------------------------------------------
    def _make_callbacks(self):
        from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions)
        from fmpy import calloc, free

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = _dispatcher()
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        callbacks.componentEnvironment = ctypes.c_void_p(self._route_key)
        _install_proxy(callbacks)
        return callbacks

    def _receive(self, status, text):
        self.messages.append((status, text))

    def instantiate(self, start_time=0.0, stop_time=None, parameters=None):
        """Instantiate, set parameters in initialisation mode and leave it.

        Parameters
        ----------
        start_time, stop_time : float
            Passed to ``fmi2SetupExperiment``.
        parameters : dict, optional
            Variable name to value; types follow the model description.
        """
        if self._resettable:
            # A terminated instance goes back to "instantiated" (FMI 2.0, 4.2.4): cheaper
            # than a new instance, and it must leave nothing of the last run behind.
            self._resettable = False
            self._can_terminate = False
            self.messages.clear()
            try:
                self._slave.reset()
            except Exception as exc:
                self._note_failure(exc)
                raise
        else:
            _install_proxy(self._callbacks)  # another fmpy user may have taken the one proxy
            self._slave.instantiate(callbacks=self._callbacks, loggingOn=True)
        self._instantiated = True
        try:
            self._slave.setupExperiment(startTime=start_time, stopTime=stop_time)
            self._slave.enterInitializationMode()
            if parameters:
                self.set_values(parameters)
            self._slave.exitInitializationMode()
            self._can_terminate = True
        except Exception as exc:
            self._note_failure(exc)
            raise

    def _note_failure(self, exc):
        """Remember an fmi2Fatal: after it the FMU may not be called again, not even freed.

        (pythonfmu 0.7.0's binary, still the one in our win64 FMUs, releases the Python objects
        of an instance when it reports fmi2Fatal and again when the instance is freed; freeing
        it anyway corrupts the interpreter. Our linux64 binary reports fmi2Fatal only when the
        interpreter itself failed.)
        """
        if getattr(exc, "status", None) == 4:
            self._fatal = True
        if getattr(exc, "status", 3) >= 3:
            self._can_terminate = False

    def terminate(self):
        """Terminate and free the instance, or keep it for a reset if reusable (safe twice).

        The shared library stays loaded: unloading a pythonfmu binary and loading it again
        in the same process makes the next instantiation fail (seen with pythonfmu 0.7.0),
        and fmpy's ``freeInstance`` would unload it.
        """
        if self._instantiated and not self._fatal:
            self._instantiated = False
            terminated = False
            try:
                if self._can_terminate:  # after fmi2Error an instance is only freed
                    self._slave.terminate()
                    terminated = True
            finally:
                if self.reusable and terminated:
                    self._resettable = True
                else:
                    self._slave.fmi2FreeInstance(self._slave.component)
        self._instantiated = False

    def release(self):
        """Free a terminated reusable instance (after :meth:`terminate`; safe to call twice)."""
        if self._instantiated:
            self.terminate()
        if self._resettable and not self._fatal:
            self._resettable = False
            self._slave.fmi2FreeInstance(self._slave.component)
        self._resettable = False

    # ----- access by name (set-up and tests; not for the hot loop) ----------------------------
    def variable(self, name):
        """Return the model variable ``name`` or raise a ConfigError listing valid names."""
        try:
            return self.variables[name]
        except KeyError:
            raise ConfigError(f"{self.name}: no variable {name!r} in {self.path.name}; valid: "
                              f"{', '.join(sorted(self.variables))}") from None

    def set_values(self, values):
        """Set variables by name, each with the setter of its declared type.

        Values are not coerced: a Real takes an int or float (not a bool), an Integer an int
        that fits 32 bits, a Boolean a bool, a String a str; anything else is a ConfigError
        naming the variable (``int(10.7)`` would silently set 10, ctypes would wrap 2**32 + 10
        to 10).
        """
        for name, value in values.items():
            variable = self.variable(name)
            problem = _type_problem(variable.type, value)
            if problem:
                raise ConfigError(f"{self.name}.{name} = {value!r}: {problem}")
            reference = [variable.valueReference]
            if variable.type == "Real":
                self._slave.setReal(reference, [float(value)])
            elif variable.type == "Integer":
                self._slave.setInteger(reference, [int(value)])
            elif variable.type == "Boolean":
                self._slave.setBoolean(reference, [bool(value)])
            else:
                self._slave.setString(reference, [value])

    def get_values(self, names):
        """Return ``{name: value}`` for the given variables."""
        result = {}
        for name in names:
            variable = self.variable(name)
            reference = [variable.valueReference]
            getter = {"Real": self._slave.getReal, "Integer": self._slave.getInteger,
                      "Boolean": self._slave.getBoolean}.get(variable.type, self._slave.getString)
            result[name] = getter(reference)[0]
        return result

    # ----- hot path ------------------------------------------------------------------------
    # The raw ctypes functions, called without fmpy's per-call wrapper (which looks up the
    # function by name and checks for a call logger on every call); statuses are checked here.
    def _raw(self, name):
        return self._slave._functions[name]

    def _check(self, status, function):
        if status > 1:  # above fmi2Warning
            from fmpy.fmi1 import FMICallException

            if status == 4:
                self._fatal = True
            if status >= 3:
                self._can_terminate = False
            raise FMICallException(function=function, status=status)

    def port_group(self, type_name, names):
        """Resolve ports of one type once; return a :class:`PortGroup` for batched access."""
        from fmpy.fmi2 import fmi2ValueReference

        for name in names:
            if self.variable(name).type != type_name:
                raise ConfigError(f"{self.name}.{name} is {self.variable(name).type}, "
                                  f"not {type_name}")
        references = (fmi2ValueReference * len(names))(
            *[self.variables[n].valueReference for n in names])
        values = (_CTYPE[type_name] * len(names))()
        return PortGroup(type_name, tuple(names), references, values,
                         self._raw(f"fmi2Get{type_name}"), self._raw(f"fmi2Set{type_name}"))

    def read(self, group):
        """Fill ``group.values`` from the FMU with one get call."""
        if group.names:
            status = group.get_function(self._slave.component, group.references,
                                        len(group.names), group.values)
            if status > 1:
                self._check(status, f"fmi2Get{group.type}")
        return group.values

    def write(self, group):
        """Send ``group.values`` to the FMU with one set call."""
        if group.names:
            status = group.set_function(self._slave.component, group.references,
                                        len(group.names), group.values)
            if status > 1:
                self._check(status, f"fmi2Set{group.type}")

    def do_step(self, time, step):
        """Advance the slave from ``time`` by ``step``; raises FMICallException on failure."""
        status = self._do_step(self._slave.component, time, step, 1)
        if status > 1:
            self._check(status, "fmi2DoStep")

    # ----- state ---------------------------------------------------------------------------
    def get_state(self):
        """Return an opaque FMU state (free it with :meth:`free_state`)."""
        return self._slave.getFMUstate()

    def set_state(self, state):
        """Restore a state from :meth:`get_state` or :meth:`deserialize_state`."""
        self._slave.setFMUstate(state)

    def free_state(self, state):
        """Release an FMU state."""
        self._slave.freeFMUstate(state)

    def serialize_state(self, state):
        """Return the FMU state as bytes."""
        return self._slave.serializeFMUstate(state)

    def deserialize_state(self, data):
        """Return an FMU state from bytes made by :meth:`serialize_state`."""
        return self._slave.deSerializeFMUstate(data)

    def last_error(self):
        """The model's explanation of the last failure, on one line, or ''.

        The last line with status discard or error; failing that, the last fatal line other
        than pythonfmu's trailer (which says only "unknown error"); failing that, the trailer.
        """
        fatal = trailer = ""
        for status, text in reversed(self.messages):
            if status in (2, 3):
                return _one_line(self._model_line(text))
            if status >= 4 and not fatal:
                if text.startswith(_INTERPRETER_TRAILER):
                    trailer = trailer or text
                else:
                    fatal = text
        return _one_line(fatal or trailer)

    def _model_line(self, text):
        """``text`` without sonotrack's binary's ``fmi2Function: method:`` prefix when the rest
        is the model's own message (it starts with this instance's name)."""
        match = _BINARY_PREFIX.match(text)
        if match is not None and text[match.end():].startswith(f"{self.name}: "):
            return text[match.end():]
        return text

    @staticmethod
    def status_label(status):
        """Name of an FMI status code."""
        return _STATUS[status] if 0 <= status < len(_STATUS) else f"status {status}"


def _type_problem(type_name, value):
    """Why ``value`` cannot be set as an FMI ``type_name`` without coercion, or ''."""
    is_bool = type(value).__name__ in ("bool", "bool_")   # Python's or numpy's
    if type_name == "Real":
        ok = isinstance(value, numbers.Real) and not is_bool
    elif type_name == "Integer":
        ok = isinstance(value, numbers.Integral) and not is_bool
        if ok and not -2**31 <= value <= 2**31 - 1:
            return "does not fit a 32-bit fmi2Integer"
    elif type_name == "Boolean":
        ok = is_bool
    else:
        ok = isinstance(value, str)
    return "" if ok else f"is {type(value).__name__}, expected an fmi2{type_name} value"


def _one_line(text):
    return " ".join(text.split())


_DISPATCHER = None


def _dispatcher():
    """The one ctypes logger every handle registers (created once, kept alive here)."""
    global _DISPATCHER
    if _DISPATCHER is None:
        from fmpy.fmi2 import fmi2CallbackLoggerTYPE

        def dispatch(environment, instance_name, status, category, message):
            text = message.decode("utf-8", errors="replace") if message else ""
            reference = _ROUTES.get(environment or 0)
            handle = reference() if reference is not None else None
            if handle is None:
                name = instance_name.decode("utf-8", errors="replace") if instance_name else ""
                UNROUTED.append((name, int(status), text))
            else:
                handle._receive(int(status), text)

        _DISPATCHER = fmi2CallbackLoggerTYPE(dispatch)
    return _DISPATCHER


def _install_proxy(callbacks):
    """Route fmpy's single printf proxy to :func:`_dispatcher` (a no-op if already so)."""
    try:
        from fmpy.logging import addLoggerProxy
    except Exception:  # no proxy library: messages arrive unformatted, still per instance
        return
    # addLoggerProxy(f) makes f's logger the proxy's target and f's logger the proxy, unless
    # f's logger already is the proxy. The probe re-targets the proxy at the dispatcher;
    # the second call turns this handle's logger into the proxy (once).
    probe = type(callbacks)()
    probe.logger = _dispatcher()
    addLoggerProxy(ctypes.byref(probe))
    addLoggerProxy(ctypes.byref(callbacks))
