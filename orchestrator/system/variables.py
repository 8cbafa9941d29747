"""Variables of a system's FMUs: resolved once, with their units, found by name.

The small vocabulary the rest of :mod:`orchestrator.system` shares: a :class:`Variable` is one
FMU variable of one component instance resolved to its value reference before t0, and the
helpers look variables up in fmpy model descriptions and suggest a close name when one is
misspelt.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass

__all__ = ["Variable", "ResolvedConnection", "variable_unit", "resolve_variable",
           "find_variable", "names_by_causality", "suggest", "unit_text"]


@dataclass(frozen=True)
class Variable:
    """One FMU variable of one component instance, resolved once before t0.

    Attributes
    ----------
    component : str
        Instance name.
    name : str
        Variable name in the FMU.
    value_reference : int
        FMI value reference.
    type : str
        ``"Real"``, ``"Integer"``, ``"Boolean"``, ``"String"`` or ``"Enumeration"``.
    causality : str
        FMI causality (``"input"``, ``"output"``, ``"parameter"``, ...).
    unit : str or None
        The variable's unit (its own or its declared type's).
    """

    component: str
    name: str
    value_reference: int
    type: str
    causality: str
    unit: str | None

    def __str__(self):
        return f"{self.component}.{self.name}"


@dataclass(frozen=True)
class ResolvedConnection:
    """A connection whose two ends are resolved to FMU variables."""

    start: Variable
    end: Variable

    def __str__(self):
        return f"{self.start} -> {self.end}"


def variable_unit(variable):
    """Return the unit of an fmpy variable: its own, else its declared type's, else None."""
    if variable.unit is not None:
        return variable.unit
    declared = getattr(variable, "declaredType", None)
    return getattr(declared, "unit", None) if declared is not None else None


def resolve_variable(component, variable):
    """The :class:`Variable` of fmpy ``variable`` in instance ``component``."""
    return Variable(component, variable.name, variable.valueReference, variable.type,
                    variable.causality, variable_unit(variable))


def find_variable(model_description, name):
    """The fmpy variable called ``name`` of a model description, or None."""
    for variable in model_description.modelVariables:
        if variable.name == name:
            return variable
    return None


def names_by_causality(model_description, causality):
    """Names of a model description's variables of one causality, in their order."""
    return [v.name for v in model_description.modelVariables if v.causality == causality]


def suggest(name, choices):
    """`` (did you mean 'x'?)`` for the closest of ``choices``, or an empty string."""
    close = difflib.get_close_matches(name, choices, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def unit_text(unit):
    """``unit 'm'`` or ``no unit``, for messages."""
    return "no unit" if unit is None else f"unit '{unit}'"
