"""The shared pythonfmu base class of every sonotrack FMU.

pythonfmu 0.7.0 declares no units, no InitialUnknowns, gives Integer and Boolean variables an
illegal continuous variability and saves only registered variables in the FMU state. This
module closes those gaps once for every FMU: slaves declare their parameters and inputs from
the part's port table (``ranges.toml``, :mod:`.ranges`) and their outputs with a unit, a
description and their direct dependencies through :class:`SonotrackSlave`, whose
:meth:`to_xml` writes a compliant modelDescription.xml, and whose state hooks save the model
core in full.
"""

import functools
import json
import math
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Boolean, DefaultExperiment, Fmi2Slave, Integer, Real, String
from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability

from .errors import InputError, ParameterError, SonotrackError
from .ranges import load_ranges
from .state import restore, snapshot
from .units import UNIT_BASES

__all__ = ["SonotrackSlave", "DefaultExperiment", "Fmi2Status", "UNIT_BASES", "load_ranges"]

_VARIABLE = {"Real": Real, "Integer": Integer, "Boolean": Boolean, "String": String}
_VALUE = {"Real": float, "Integer": int, "Boolean": bool, "String": str}


class SonotrackSlave(Fmi2Slave):
    """Base of every sonotrack slave: typed, unit-annotated ports, valid ranges, complete state.

    A slave declares its inputs and parameters from its port table with
    :meth:`declare_inputs` and :meth:`declare_parameters` (which set each to its start value),
    sets and declares its outputs with the ``output_*`` methods, builds its core from
    :meth:`parameter_values` in :meth:`exit_initialization_mode` and calls it in ``do_step``.
    Attributes named in ``hidden_state`` (default: ``core``) are saved and restored with the
    FMU state, in full.

    ``valid_ranges`` (a :class:`~components.common.ranges.RangeTable`, read from the part's
    ``ranges.toml``) holds every parameter and input: its description, type, unit, start value
    and valid range. :meth:`check_parameters` refuses parameters outside it (raising
    :class:`ParameterError`), :meth:`inputs_refused` and :meth:`step_refused` refuse inputs
    and steps (``do_step`` then returns False), and :meth:`to_xml` writes it as ``min``/``max``
    (and refuses a table entry the slave did not declare).

    Error contract with sonotrack's FMU binary (docs/fmi_binary.md): ``exit_initialization_mode``
    raises the project's exceptions (:class:`ParameterError` for a refused parameter, the
    message naming the instance, parameter, value and valid range), which the binary logs and
    maps to fmi2Error; ``do_step`` refuses a bad input or step with a logged line and False
    (fmi2Discard: the instance stays intact, the host may restore a state and go on).
    """

    hidden_state = ("core",)
    valid_ranges = None

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "exit_initialization_mode" in cls.__dict__:
            cls.exit_initialization_mode = _checked_initialization(
                cls.__dict__["exit_initialization_mode"])

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._units = {}
        self._dependencies = {}
        self._logged_once = set()
        # value reference -> attribute name, per type: the hot get/set path (below) looks the
        # attribute up directly instead of pythonfmu's per-call isinstance and getter lambdas.
        self._names_by_type = {Real: {}, Integer: {}, Boolean: {}, String: {}}
        # (name, min, max) of every Real or Integer input: the per-step range test.
        self._input_bounds = []
        self._step_bounds = ((self.valid_ranges.step.minimum, self.valid_ranges.step.maximum)
                             if self.valid_ranges is not None else (0.0, math.inf))

    # ----- port declarations -------------------------------------------------------------
    def _declare(self, kind, name, causality, description, unit=None, depends_on=None):
        if causality == Fmi2Causality.parameter:
            variability = Fmi2Variability.fixed
            initial = Fmi2Initial.exact
        elif kind in (Integer, Boolean, String):
            variability = Fmi2Variability.discrete
            initial = Fmi2Initial.calculated if causality == Fmi2Causality.output else None
        else:
            variability = Fmi2Variability.continuous
            initial = Fmi2Initial.calculated if causality == Fmi2Causality.output else None
        if kind is Real:
            if unit not in UNIT_BASES:
                raise ValueError(f"port {name!r}: unit {unit!r} is not one of {sorted(UNIT_BASES)}")
            self._units[name] = unit
        variable = kind(name, causality=causality, description=description,
                        variability=variability, initial=initial)
        self.register_variable(variable)
        self._names_by_type[kind][variable.value_reference] = name
        if causality == Fmi2Causality.output:
            self._dependencies[name] = tuple(depends_on or ())

    def _declare_from_table(self, causality, entries, names):
        """Set each port of ``entries`` to its start value and declare it (see declare_inputs)."""
        declared = {v.name for v in self.vars.values()}
        for name in names or [name for name in entries if name not in declared]:
            if name not in entries or name in declared:
                state = "is declared already" if name in declared else "has no entry"
                raise ValueError(f"{causality.name} {name!r} {state} in "
                                 f"{self.valid_ranges.source}; {causality.name}s of the "
                                 f"table: {', '.join(entries)}")
            entry = entries[name]
            setattr(self, name, entry.start)
            self._declare(_VARIABLE[entry.type], name, causality, entry.description, entry.unit)
            declared.add(name)
            if causality == Fmi2Causality.input and entry.type in ("Real", "Integer"):
                self._input_bounds.append((name, entry.minimum, entry.maximum))

    def declare_inputs(self, *names):
        """Declare inputs of ``valid_ranges``, each set to its start value first.

        With ``names``, those inputs in that order; without, every input of the table not yet
        declared, in table order (which fixes the value references).
        """
        self._declare_from_table(Fmi2Causality.input, self.valid_ranges.inputs, names)

    def declare_parameters(self, *names):
        """Declare parameters of ``valid_ranges``, each set to its start value first.

        With ``names``, those parameters in that order; without, every parameter of the table
        not yet declared, in table order (which fixes the value references).
        """
        self._declare_from_table(Fmi2Causality.parameter, self.valid_ranges.parameters, names)

    def parameter_values(self):
        """Every parameter of ``valid_ranges`` by name, as its type: a core's keyword arguments."""
        return {name: _VALUE[entry.type](getattr(self, name))
                for name, entry in self.valid_ranges.parameters.items()}

    def output_real(self, name, unit, description, depends_on=()):
        """Declare a Real output; ``depends_on`` names the inputs it feeds through directly.

        An input feeds through directly only when setting it changes what ``fmi2GetReal``
        returns *before* the next ``fmi2DoStep``. Ports here are plain attributes written in
        ``do_step`` (or ``exit_initialization_mode``), so no sonotrack output does: a false
        declaration makes masters see algebraic loops that do not exist.
        """
        self._declare(Real, name, Fmi2Causality.output, description, unit, depends_on)

    def output_integer(self, name, description, depends_on=()):
        """Declare a discrete Integer output."""
        self._declare(Integer, name, Fmi2Causality.output, description, None, depends_on)

    def output_boolean(self, name, description, depends_on=()):
        """Declare a discrete Boolean output."""
        self._declare(Boolean, name, Fmi2Causality.output, description, None, depends_on)

    # ----- batched get/set without per-variable indirection ---------------------------------
    def _names(self, kind, vrs):
        names = self._names_by_type[kind]
        try:
            return [names[vr] for vr in vrs]
        except KeyError as exc:
            raise TypeError(f"variable with valueReference={exc.args[0]} is not of type "
                            f"{kind.__name__}") from None

    def get_real(self, vrs):
        return [float(getattr(self, name)) for name in self._names(Real, vrs)]

    def get_integer(self, vrs):
        return [int(getattr(self, name)) for name in self._names(Integer, vrs)]

    def get_boolean(self, vrs):
        return [bool(getattr(self, name)) for name in self._names(Boolean, vrs)]

    def set_real(self, vrs, values):
        for name, value in zip(self._names(Real, vrs), values):
            setattr(self, name, value)

    def set_integer(self, vrs, values):
        for name, value in zip(self._names(Integer, vrs), values):
            setattr(self, name, value)

    def set_boolean(self, vrs, values):
        for name, value in zip(self._names(Boolean, vrs), values):
            setattr(self, name, bool(value))  # an fmi2Boolean is an int: 0 false, else true

    # ----- valid ranges -----------------------------------------------------------------------
    def check_parameters(self):
        """Raise :class:`ParameterError` naming every parameter outside its valid range.

        Call first in ``exit_initialization_mode``; the message names the instance, each
        parameter, its value and its valid range or choices.
        """
        problems = [problem for name, entry in self.valid_ranges.parameters.items()
                    if (problem := entry.problem(getattr(self, name))) is not None]
        if problems:
            raise ParameterError(f"{self.instance_name}: parameter " + "; parameter ".join(problems))

    def inputs_refused(self, bounds=None):
        """Log the first input outside its valid range and return True; False if all are valid.

        ``bounds`` is a subset of ``self._input_bounds`` (default: every Real and Integer input);
        NaN and inf are outside every range.
        """
        for name, low, high in self._input_bounds if bounds is None else bounds:
            value = getattr(self, name)
            if not low <= value <= high:
                entry = self.valid_ranges.inputs[name]
                self.refuse(name, value, f"outside its valid range {entry.text()}")
                return True
        return False

    def input_bounds(self, names):
        """The ``(name, min, max)`` entries of some inputs, for :meth:`inputs_refused`."""
        return tuple(b for b in self._input_bounds if b[0] in names)

    def step_refused(self, step_size):
        """Log and return True if ``step_size`` is outside the table's communication step range."""
        low, high = self._step_bounds
        if low <= step_size <= high:
            return False
        self.refuse("step_size", step_size,
                    f"the communication step must be in {self.valid_ranges.step.text()}")
        return True

    # ----- refusing bad input ----------------------------------------------------------------
    def refuse(self, port, value, reason):
        """Log why an input is refused with an error status; ``do_step`` then returns False.

        Returning False from ``do_step`` gives the host fmi2Discard (a refused step) and the
        logged line names the port and value; raising :class:`InputError` instead gives
        fmi2Error (docs/fmi_binary.md lists how sonotrack's FMU binary maps each outcome).
        """
        self.log(f"{self.instance_name}: input {port} = {value!r} refused: {reason}",
                 Fmi2Status.error)
        return False

    def first_non_finite(self, ports):
        """Return the name of the first port among ``ports`` whose value is NaN or inf, or None."""
        for port in ports:
            value = getattr(self, port)
            if not math.isfinite(value):
                return port
        return None

    def log_once(self, key, message, status=Fmi2Status.warning):
        """Log ``message`` the first time ``key`` is seen in this instance."""
        if key not in self._logged_once:
            self._logged_once.add(key)
            self.log(f"{self.instance_name}: {message}", status)

    # ----- complete FMU state ----------------------------------------------------------------
    def _get_fmu_state(self):
        state = super()._get_fmu_state()
        state["__hidden__"] = {name: snapshot(getattr(self, name, None))
                               for name in self.hidden_state}
        state["__logged_once__"] = sorted(self._logged_once)
        return state

    def _set_fmu_state(self, state):
        problem = self._state_problem(state)
        if problem is not None:
            raise InputError(f"{self.instance_name}: FMU state refused: {problem}")
        state = dict(state)
        hidden = state.pop("__hidden__", {})
        self._logged_once = set(state.pop("__logged_once__", []))
        super()._set_fmu_state(state)
        for name, saved in hidden.items():
            current = getattr(self, name, None)
            if isinstance(saved, dict) and "__object__" in saved and current is not None:
                restore(current, saved)
            elif isinstance(saved, dict) and "__object__" in saved:
                raise RuntimeError(f"{self.instance_name}: cannot restore {name} before it exists")
            else:
                setattr(self, name, saved)

    def _state_problem(self, state):
        """Why ``state`` is not a complete state of this slave, or None."""
        if not isinstance(state, dict):
            return f"expected a table of saved values, got {type(state).__name__}"
        expected = {v.name for v in self.vars.values()} | {"__hidden__", "__logged_once__"}
        missing = sorted(expected - set(state))
        unknown = sorted(set(state) - expected)
        if missing or unknown:
            return (f"not a state of {type(self).__name__}"
                    + (f"; missing {', '.join(missing[:5])}" if missing else "")
                    + (f"; unknown {', '.join(unknown[:5])}" if unknown else ""))
        hidden = state["__hidden__"]
        if not isinstance(hidden, dict) or set(hidden) != set(self.hidden_state):
            return f"its hidden state does not hold exactly {', '.join(self.hidden_state)}"
        return None

    @staticmethod
    def _fmu_state_from_bytes(state):
        try:
            return json.loads(bytes(state).decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as error:
            raise InputError(f"FMU state refused: the serialized state is not valid "
                             f"({error})") from None

    # ----- compliant modelDescription.xml ------------------------------------------------------
    def to_xml(self, model_options=dict()):
        """Return pythonfmu's model description with units, variabilities and ModelStructure fixed."""
        root = super().to_xml(model_options)
        self._add_unit_definitions(root)
        variables = list(self.vars.values())
        index = {v.name: i + 1 for i, v in enumerate(variables)}
        self._check_table_declared(variables)
        for node, variable in zip(root.find("ModelVariables"), variables):
            unit = self._units.get(variable.name)
            if unit is not None:
                node.find("Real").set("unit", unit)
            entry = (self.valid_ranges.entry(variable.name)
                     if variable.causality in (Fmi2Causality.parameter, Fmi2Causality.input)
                     else None)
            if entry is not None and entry.type in ("Real", "Integer"):
                typed = node.find(entry.type)
                typed.set("min", repr(entry.minimum) if entry.type == "Real" else str(entry.minimum))
                typed.set("max", repr(entry.maximum) if entry.type == "Real" else str(entry.maximum))
        self._write_model_structure(root, variables, index)
        return root

    def _check_table_declared(self, variables):
        """Every entry of the range table must be a declared parameter or input of that name."""
        declared = {v.name: v.causality for v in variables}
        table = self.valid_ranges
        for causality, entries in ((Fmi2Causality.parameter, table.parameters),
                                   (Fmi2Causality.input, table.inputs)):
            for name in entries:
                if declared.get(name) != causality:
                    raise ValueError(f"{table.source}: {name} is not a declared "
                                     f"{causality.name} of {type(self).__name__}")

    def _add_unit_definitions(self, root):
        used = sorted(set(self._units.values()))
        if not used:
            return
        definitions = Element("UnitDefinitions")
        for unit in used:
            unit_node = SubElement(definitions, "Unit", {"name": unit})
            bases = UNIT_BASES[unit]
            attributes = {k: str(v) for k, v in bases.items()}
            if unit == "deg":
                attributes["factor"] = repr(math.pi / 180.0)
            SubElement(unit_node, "BaseUnit", attributes)
        position = list(root).index(root.find("CoSimulation")) + 1
        root.insert(position, definitions)

    def _write_model_structure(self, root, variables, index):
        old = root.find("ModelStructure")
        root.remove(old)
        structure = SubElement(root, "ModelStructure")
        outputs = [v for v in variables if v.causality == Fmi2Causality.output]
        if not outputs:
            return
        parameters = [v.name for v in variables if v.causality == Fmi2Causality.parameter]
        outputs_node = SubElement(structure, "Outputs")
        initial_node = SubElement(structure, "InitialUnknowns")
        for variable in outputs:
            inputs = self._dependencies[variable.name]
            unknown = [name for name in inputs if name not in index]
            if unknown:
                raise ValueError(f"output {variable.name!r} depends on unknown ports {unknown}")
            direct = sorted(index[name] for name in inputs)
            SubElement(outputs_node, "Unknown", _unknown(index[variable.name], direct))
            # At initialisation an output depends on its direct inputs (no slave reads an input
            # in exit_initialization_mode) and, conservatively, on every parameter.
            at_init = sorted(set(direct) | {index[name] for name in parameters})
            SubElement(initial_node, "Unknown", _unknown(index[variable.name], at_init))


def _unknown(index, dependencies):
    """Attributes of a ModelStructure ``Unknown`` with ascending dependency indices."""
    return {
        "index": str(index),
        "dependencies": " ".join(str(i) for i in dependencies),
        "dependenciesKind": " ".join("dependent" for _ in dependencies),
    }


def _checked_initialization(exit_initialization_mode):
    """Wrap ``exit_initialization_mode`` so the parameters are range-checked before the core."""

    @functools.wraps(exit_initialization_mode)
    def checked(self):
        if self.valid_ranges is not None:
            self.check_parameters()
        try:
            return exit_initialization_mode(self)
        except SonotrackError as exc:   # a core's refusal: name the instance too
            if str(exc).startswith(f"{self.instance_name}: "):
                raise
            raise type(exc)(f"{self.instance_name}: {exc}") from exc

    return checked
