"""Parameter values of an ``.ssd``: ``ssv:ParameterSet`` reading and ``.ssv`` binding.

A component's ``ssd:ParameterBindings`` hold either an inline ``ssv:ParameterSet`` or a
``source`` naming an ``.ssv`` file (resolved from the ``.ssd``'s folder and, unless
``allow_outside``, confined to it; see :mod:`orchestrator.files.paths`). Each value is converted to
the Python type of its SSP type and refused when it can never be a parameter (a NaN Real, an
Integer that does not fit an fmi2Integer); whether it fits the FMU is checked later by
:mod:`orchestrator.system`.
"""

from __future__ import annotations

import math
from dataclasses import replace

from lxml import etree

from ._xml import (Problems, child_elements, describe, first_child, required_attribute,
                   ssd_tag, ssv_tag)
from .model import PARAMETER_TYPES, SSV_NAMESPACE, ParameterValue

__all__ = ["read_parameter_set", "read_parameter_bindings"]


class _OutOfRange(ValueError):
    """A value that parses but is never a valid parameter."""


def _convert(type_name, text):
    """Convert an XML attribute text to the Python value of an SSP type; raises ValueError.

    A Real must be finite and an Integer must fit an fmi2Integer (32-bit signed): neither NaN
    nor a silently wrapped integer is ever a parameter value.
    """
    if type_name == "Real":
        value = float(text)
        if not math.isfinite(value):
            raise _OutOfRange("not finite")
        return value
    if type_name == "Integer":
        value = int(text)
        if not -2**31 <= value <= 2**31 - 1:
            raise _OutOfRange("does not fit a 32-bit fmi2Integer")
        return value
    if type_name == "Boolean":
        lowered = text.strip().lower()
        if lowered in ("true", "1"):
            return True
        if lowered in ("false", "0"):
            return False
        raise ValueError(f"{text!r} is not a boolean (true, false, 1, 0)")
    return text


def read_parameter_set(parameter_set, problems, directory=None, allow_outside=False):
    from orchestrator.files.paths import confine, names_a_file

    parameters = {}
    values = first_child(parameter_set, ssv_tag("Parameters"))
    if values is None:
        return parameters
    for parameter in child_elements(values, ssv_tag("Parameter")):
        name = required_attribute(parameter, "name", problems)
        typed = [child for child in parameter if isinstance(child.tag, str)]
        typed = [child for child in typed if etree.QName(child).namespace == SSV_NAMESPACE]
        if len(typed) != 1 or etree.QName(typed[0]).localname not in PARAMETER_TYPES:
            problems.add(parameter, f"{describe(parameter)}: needs exactly one value element, "
                                    f"one of {', '.join('ssv:' + t for t in PARAMETER_TYPES)}")
            continue
        type_name = etree.QName(typed[0]).localname
        text = required_attribute(typed[0], "value", problems)
        if name is None or text is None:
            continue
        if directory is not None and type_name == "String" and names_a_file(text):
            problem = confine(text, directory, allow_outside)[1]
            if problem is not None:
                problems.add(typed[0], f"{describe(parameter)}: {problem}")
                continue
        try:
            parameters[name] = ParameterValue(type_name, _convert(type_name, text), directory)
        except ValueError as error:
            reason = f" ({error})" if isinstance(error, _OutOfRange) else ""
            problems.add(typed[0], f"{describe(parameter)}: value {text!r} is not a valid "
                                   f"ssv:{type_name}{reason}")
    return parameters


def read_parameter_bindings(component, bindings, directory, problems, allow_outside=False):
    from orchestrator.files.paths import confine

    parameters = {}
    for binding in child_elements(bindings, ssd_tag("ParameterBinding")):
        source = binding.get("source")
        if source is not None:
            ssv_path, outside = confine(source, directory, allow_outside, must_exist=False)
            if outside is not None:
                problems.add(binding, f"component '{component}': parameter file {outside}")
                continue
            try:
                ssv_root = etree.parse(str(ssv_path)).getroot()
            except (OSError, etree.XMLSyntaxError) as error:
                problems.add(binding, f"component '{component}': parameter file '{source}' "
                                      f"cannot be read ({error})")
                continue
            if ssv_root.tag != ssv_tag("ParameterSet"):
                problems.add(binding, f"component '{component}': '{source}' is not an "
                                      f"ssv:ParameterSet")
                continue
            sub_problems = Problems(ssv_path)
            parameters.update({name: replace(value, source=str(ssv_path)) for name, value in
                               read_parameter_set(ssv_root, sub_problems, ssv_path.parent,
                                                   allow_outside).items()})
            problems.lines.extend(sub_problems.lines)
            continue
        values = first_child(binding, ssd_tag("ParameterValues"))
        parameter_set = first_child(values, ssv_tag("ParameterSet")) if values is not None else None
        if parameter_set is None:
            problems.add(binding, f"component '{component}': <ssd:ParameterBinding> has neither "
                                  f"a 'source' nor inline <ssd:ParameterValues><ssv:ParameterSet>")
            continue
        parameters.update(read_parameter_set(parameter_set, problems, directory,
                                              allow_outside))
    return parameters
