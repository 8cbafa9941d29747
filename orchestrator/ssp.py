"""Read and write SSP 1.0 system structure descriptions (``SystemStructure.ssd``).

This module knows the file format only: components with their typed connectors, connections,
inline or ``.ssv`` parameter values, units and the default experiment. Whether a description
fits its FMUs is the business of :mod:`orchestrator.system`.

The writer uses exactly the prefixes ``ssd``, ``ssc``, ``ssv`` and ``osp``, because libcosim's
parser matches element names with their prefix, not their namespace. Component ``source``
attributes are written as given; libcosim resolves them against the ``.ssd`` file's own URI, so
``source="SoundSource.fmu"`` finds the FMU next to the ``.ssd`` (our ``fmus/`` layout) and
``source="resources/SoundSource.fmu"`` finds it in an ``.ssp`` archive's ``resources/`` folder
(see :meth:`SystemDescription.with_source_prefix`).

The second half of the module is the sonotrack system as data (:func:`sonotrack_system`): the
port table follows DESIGN.md, and ``python -m orchestrator.ssp [path]`` regenerates the
committed ``fmus/SystemStructure.ssd`` from it when ports change.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path

from lxml import etree

from components.common.errors import ConfigError

__all__ = [
    "SSD_NAMESPACE",
    "SSC_NAMESPACE",
    "SSV_NAMESPACE",
    "OSP_NAMESPACE",
    "CONNECTOR_KINDS",
    "CONNECTOR_TYPES",
    "PARAMETER_TYPES",
    "ParameterValue",
    "Connector",
    "Connection",
    "ComponentDescription",
    "SystemDescription",
    "read_ssd",
    "write_ssd",
    "ssd_to_string",
    "FMU_PORTS",
    "SONOTRACK_INSTANCES",
    "SONOTRACK_CONNECTIONS",
    "SONOTRACK_PARAMETERS",
    "SONOTRACK_STEP_SIZES",
    "sonotrack_system",
]

SSD_NAMESPACE = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC_NAMESPACE = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV_NAMESPACE = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
OSP_NAMESPACE = "http://opensimulationplatform.com/SSP/OSPAnnotations"
_OSP_ANNOTATION_TYPE = "com.opensimulationplatform"
_NSMAP = {"ssd": SSD_NAMESPACE, "ssc": SSC_NAMESPACE, "ssv": SSV_NAMESPACE, "osp": OSP_NAMESPACE}

CONNECTOR_KINDS = ("input", "output", "parameter", "calculatedParameter", "inout")
CONNECTOR_TYPES = ("Real", "Integer", "Boolean", "String", "Enumeration", "Binary")
PARAMETER_TYPES = ("Real", "Integer", "Boolean", "String")
_BASE_UNIT_ATTRIBUTES = ("kg", "m", "s", "A", "K", "mol", "cd", "rad", "factor", "offset")
_FMU_TYPE = "application/x-fmu-sharedlibrary"
# Largest accepted osp:StepSizeHint [s]; every sonotrack FMU's step range ends at 1 s.
STEP_SIZE_HINT_MAX = 1.0


def _ssd(tag):
    return f"{{{SSD_NAMESPACE}}}{tag}"


def _ssc(tag):
    return f"{{{SSC_NAMESPACE}}}{tag}"


def _ssv(tag):
    return f"{{{SSV_NAMESPACE}}}{tag}"


# ----- object model ---------------------------------------------------------------------------

@dataclass(frozen=True)
class ParameterValue:
    """One parameter value of a component.

    Attributes
    ----------
    type : str
        One of :data:`PARAMETER_TYPES` (``"Real"``, ``"Integer"``, ``"Boolean"``, ``"String"``).
    value : float or int or bool or str
        The value, already converted to the Python type that matches ``type``, as written.
    origin : pathlib.Path or None
        Folder of the file that bound it (the ``.ssd`` or ``.ssv``): a file-valued string
        (a waypoint CSV) is relative to it, see :meth:`run_value`.
    source : str or None
        The ``.ssv`` file the value was read from, for messages (None: inline in the ``.ssd``).
    """

    type: str
    value: float | int | bool | str
    origin: Path | None = field(default=None, compare=False)
    source: str | None = field(default=None, compare=False)

    def run_value(self):
        """The value a run passes to the FMU: a relative file path resolved from ``origin``."""
        from orchestrator.paths import names_a_file

        if self.origin is not None and self.type == "String" and names_a_file(self.value):
            return str((Path(self.origin) / self.value).resolve())
        return self.value


@dataclass(frozen=True)
class Connector:
    """A typed port of a component as the ``.ssd`` declares it.

    Attributes
    ----------
    name : str
        Variable name in the FMU.
    kind : str
        One of :data:`CONNECTOR_KINDS`.
    type : str
        One of :data:`CONNECTOR_TYPES`.
    unit : str or None
        Unit of a ``Real`` connector; ``None`` when the ``.ssd`` declares none.
    """

    name: str
    kind: str
    type: str
    unit: str | None = None


@dataclass(frozen=True)
class Connection:
    """A signal from ``start_element.start_connector`` to ``end_element.end_connector``."""

    start_element: str
    start_connector: str
    end_element: str
    end_connector: str

    def __str__(self):
        return (f"{self.start_element}.{self.start_connector} -> "
                f"{self.end_element}.{self.end_connector}")


@dataclass
class ComponentDescription:
    """One FMU instance of the system.

    Attributes
    ----------
    name : str
        Instance name, unique in the system (``controller_left``).
    source : str
        FMU location relative to the ``.ssd`` file's directory (``SoundSource.fmu``).
    connectors : list of Connector
        The ports the ``.ssd`` declares, in file order.
    parameters : dict of str to ParameterValue
        Parameter values bound to this instance, by variable name.
    step_size_hint : float or None
        Communication step suggested to libcosim (``osp:StepSizeHint``), in s.
    type : str
        MIME type of the component; always an FMU here.
    """

    name: str
    source: str
    connectors: list[Connector] = field(default_factory=list)
    parameters: dict[str, ParameterValue] = field(default_factory=dict)
    step_size_hint: float | None = None
    type: str = _FMU_TYPE

    def connector(self, name):
        """Return the connector called ``name``, or None."""
        for connector in self.connectors:
            if connector.name == name:
                return connector
        return None


@dataclass
class SystemDescription:
    """The contents of one ``.ssd`` file.

    Attributes
    ----------
    name : str
        Name of the ``ssd:SystemStructureDescription`` (also used for its ``ssd:System``).
    components : list of ComponentDescription
        Components in file order (the order breaks ties in the stepping order).
    connections : list of Connection
        Connections in file order.
    path : pathlib.Path or None
        The file it was read from; relative component sources resolve against its directory.
    units : dict of str to dict of str to float
        ``ssc:Unit`` definitions: unit name to its ``ssc:BaseUnit`` attributes.
    start_time, stop_time : float or None
        ``ssd:DefaultExperiment``, in s.
    base_step : float or None
        Base step of libcosim's fixed-step algorithm (``osp:FixedStepAlgorithm baseStepSize``
        in the ``ssd:DefaultExperiment``), in s: with it libcosim needs no step size argument.
    parameter_set_name : str or None
        Name of every ``ssv:ParameterSet``. One name for all components, because ecos applies
        exactly one named set (``--parameterSet``); ``None`` if the file binds no parameters.
    """

    name: str
    components: list[ComponentDescription] = field(default_factory=list)
    connections: list[Connection] = field(default_factory=list)
    path: Path | None = None
    units: dict[str, dict[str, float]] = field(default_factory=dict)
    start_time: float | None = None
    stop_time: float | None = None
    base_step: float | None = None
    parameter_set_name: str | None = "default"

    def component(self, name):
        """Return the component called ``name``, or None."""
        for component in self.components:
            if component.name == name:
                return component
        return None

    @property
    def directory(self):
        """Directory against which component sources resolve (cwd if the path is unknown)."""
        return self.path.parent if self.path is not None else Path.cwd()

    def without_step_hints(self):
        """Return a copy whose components carry no step-size hint (a single-rate system).

        libcosim runs every component at its own hinted step; without hints, all step at the
        execution's step, which is what a single-rate comparison needs.
        """
        return replace(self, components=[replace(c, step_size_hint=None)
                                         for c in self.components])

    def with_source_prefix(self, prefix):
        """Return a copy whose component sources are prefixed, e.g. with ``"resources/"``.

        An ``.ssp`` archive keeps its FMUs in ``resources/`` beside ``SystemStructure.ssd``.
        """
        components = [replace(c, source=prefix + c.source) for c in self.components]
        return replace(self, components=components)


# ----- reading --------------------------------------------------------------------------------

class _Problems:
    """Collects parse problems so that one error names all of them."""

    def __init__(self, path):
        self.path = path
        self.lines = []

    def add(self, node, message):
        line = getattr(node, "sourceline", None)
        where = f"{self.path}:{line}" if line else f"{self.path}"
        self.lines.append(f"{where}: {message}")

    def raise_if_any(self):
        if len(self.lines) == 1:
            raise ConfigError(self.lines[0])
        if self.lines:
            count = len(self.lines)
            noun = "problem" if count == 1 else "problems"
            raise ConfigError(f"{self.path}: {count} {noun} in the system structure description:\n"
                              + "\n".join(f"  {line}" for line in self.lines))


def _describe(node):
    qname = etree.QName(node)
    prefix = {v: k for k, v in _NSMAP.items()}.get(qname.namespace, "?")
    name = node.get("name")
    return f"<{prefix}:{qname.localname}" + (f' name="{name}">' if name is not None else ">")


def _required(node, attribute, problems):
    value = node.get(attribute)
    if value is None or value == "":
        problems.add(node, f"{_describe(node)}: attribute '{attribute}' is missing")
    return value


def _children(node, tag):
    return [child for child in node if isinstance(child.tag, str) and child.tag == tag]


def _child(node, tag):
    found = _children(node, tag)
    return found[0] if found else None


def _float_attribute(node, attribute, problems):
    text = node.get(attribute)
    if text is None:
        return None
    try:
        return float(text)
    except ValueError:
        problems.add(node, f"{_describe(node)}: {attribute}={text!r} is not a number")
        return None


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


def _read_parameter_set(parameter_set, problems, directory=None, allow_outside=False):
    from orchestrator.paths import confine, names_a_file

    parameters = {}
    values = _child(parameter_set, _ssv("Parameters"))
    if values is None:
        return parameters
    for parameter in _children(values, _ssv("Parameter")):
        name = _required(parameter, "name", problems)
        typed = [child for child in parameter if isinstance(child.tag, str)]
        typed = [child for child in typed if etree.QName(child).namespace == SSV_NAMESPACE]
        if len(typed) != 1 or etree.QName(typed[0]).localname not in PARAMETER_TYPES:
            problems.add(parameter, f"{_describe(parameter)}: needs exactly one value element, "
                                    f"one of {', '.join('ssv:' + t for t in PARAMETER_TYPES)}")
            continue
        type_name = etree.QName(typed[0]).localname
        text = _required(typed[0], "value", problems)
        if name is None or text is None:
            continue
        if directory is not None and type_name == "String" and names_a_file(text):
            problem = confine(text, directory, allow_outside)[1]
            if problem is not None:
                problems.add(typed[0], f"{_describe(parameter)}: {problem}")
                continue
        try:
            parameters[name] = ParameterValue(type_name, _convert(type_name, text), directory)
        except ValueError as error:
            reason = f" ({error})" if isinstance(error, _OutOfRange) else ""
            problems.add(typed[0], f"{_describe(parameter)}: value {text!r} is not a valid "
                                   f"ssv:{type_name}{reason}")
    return parameters


def _read_parameter_bindings(component, bindings, directory, problems, allow_outside=False):
    from orchestrator.paths import confine

    parameters = {}
    for binding in _children(bindings, _ssd("ParameterBinding")):
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
            if ssv_root.tag != _ssv("ParameterSet"):
                problems.add(binding, f"component '{component}': '{source}' is not an "
                                      f"ssv:ParameterSet")
                continue
            sub_problems = _Problems(ssv_path)
            parameters.update({name: replace(value, source=str(ssv_path)) for name, value in
                               _read_parameter_set(ssv_root, sub_problems, ssv_path.parent,
                                                   allow_outside).items()})
            problems.lines.extend(sub_problems.lines)
            continue
        values = _child(binding, _ssd("ParameterValues"))
        parameter_set = _child(values, _ssv("ParameterSet")) if values is not None else None
        if parameter_set is None:
            problems.add(binding, f"component '{component}': <ssd:ParameterBinding> has neither "
                                  f"a 'source' nor inline <ssd:ParameterValues><ssv:ParameterSet>")
            continue
        parameters.update(_read_parameter_set(parameter_set, problems, directory,
                                              allow_outside))
    return parameters


def _read_connector(connector, problems):
    name = _required(connector, "name", problems)
    kind = _required(connector, "kind", problems)
    if kind is not None and kind not in CONNECTOR_KINDS:
        problems.add(connector, f"{_describe(connector)}: kind {kind!r} is not one of "
                                f"{', '.join(CONNECTOR_KINDS)}")
    typed = [child for child in connector if isinstance(child.tag, str)
             and etree.QName(child).namespace == SSC_NAMESPACE
             and etree.QName(child).localname in CONNECTOR_TYPES]
    if len(typed) != 1:
        problems.add(connector, f"{_describe(connector)}: needs exactly one type element, one of "
                                f"{', '.join('ssc:' + t for t in CONNECTOR_TYPES)}")
        return None
    if name is None or kind is None:
        return None
    type_name = etree.QName(typed[0]).localname
    return Connector(name, kind, type_name, typed[0].get("unit"))


def _read_step_size_hint(annotations, problems):
    for annotation in _children(annotations, _ssc("Annotation")):
        if annotation.get("type") != _OSP_ANNOTATION_TYPE:
            continue
        hint = _child(annotation, f"{{{OSP_NAMESPACE}}}StepSizeHint")
        if hint is not None:
            value = _float_attribute(hint, "value", problems)
            if value is not None and not 0.0 < value <= STEP_SIZE_HINT_MAX:
                problems.add(hint, f"{_describe(hint)}: value={hint.get('value')!r} is not a "
                                   f"step size in (0, {STEP_SIZE_HINT_MAX!r}] s")
                return None
            return value
    return None


def _read_base_step(annotations, problems):
    for annotation in _children(annotations, _ssc("Annotation")):
        if annotation.get("type") != _OSP_ANNOTATION_TYPE:
            continue
        algorithm = _child(annotation, f"{{{OSP_NAMESPACE}}}Algorithm")
        fixed = (_child(algorithm, f"{{{OSP_NAMESPACE}}}FixedStepAlgorithm")
                 if algorithm is not None else None)
        if fixed is not None:
            return _float_attribute(fixed, "baseStepSize", problems)
    return None


def _read_component(node, directory, problems, allow_outside=False):
    name = _required(node, "name", problems)
    source = _required(node, "source", problems)
    kind = node.get("type", _FMU_TYPE)
    if kind != _FMU_TYPE:
        problems.add(node, f"{_describe(node)}: type {kind!r} is not supported; only {_FMU_TYPE}")
    connectors = []
    connectors_node = _child(node, _ssd("Connectors"))
    if connectors_node is not None:
        for connector_node in _children(connectors_node, _ssd("Connector")):
            connector = _read_connector(connector_node, problems)
            if connector is None:
                continue
            if any(c.name == connector.name for c in connectors):
                problems.add(connector_node, f"component '{name}': connector "
                                             f"'{connector.name}' is declared twice")
                continue
            connectors.append(connector)
    parameters = {}
    bindings = _child(node, _ssd("ParameterBindings"))
    if bindings is not None:
        parameters = _read_parameter_bindings(name, bindings, directory, problems,
                                              allow_outside)
    annotations = _child(node, _ssd("Annotations"))
    hint = _read_step_size_hint(annotations, problems) if annotations is not None else None
    if name is None or source is None:
        return None
    return ComponentDescription(name, source, connectors, parameters, hint)


def _read_units(units_node, problems):
    units = {}
    for unit in _children(units_node, _ssc("Unit")):
        name = _required(unit, "name", problems)
        base = _child(unit, _ssc("BaseUnit"))
        exponents = {}
        if base is not None:
            for attribute in _BASE_UNIT_ATTRIBUTES:
                value = _float_attribute(base, attribute, problems)
                if value is not None:
                    exponents[attribute] = value
        if name is not None:
            units[name] = exponents
    return units


def read_ssd(path, allow_outside=False):
    """Read an SSP 1.0 ``.ssd`` file.

    Parameters
    ----------
    path : str or pathlib.Path
        The ``SystemStructure.ssd`` file.
    allow_outside : bool
        Accept ``.ssv`` files and waypoint CSVs outside the folder of the file that names them
        (``.ssv`` files resolve from the ``.ssd``'s folder, CSVs from their own file's folder;
        see :mod:`orchestrator.paths`).

    Returns
    -------
    SystemDescription
        Components, connectors, connections, parameter values, units and default experiment.

    Raises
    ------
    ConfigError
        If the file cannot be read or parsed, or elements lack required attributes; the message
        lists every problem with its file, line and element. Hierarchical systems (a
        ``ssd:System`` inside ``ssd:Elements``) and system-level connectors are reported as
        unsupported.

    Examples
    --------
    >>> system = read_ssd("fmus/SystemStructure.ssd")       # doctest: +SKIP
    >>> [c.name for c in system.components][:2]              # doctest: +SKIP
    ['source', 'localizer']
    """
    path = Path(path)
    try:
        root = etree.parse(str(path)).getroot()
    except OSError as error:
        raise ConfigError(f"{path}: cannot read the system structure description ({error})") \
            from error
    except etree.XMLSyntaxError as error:
        raise ConfigError(f"{path}: not well-formed XML ({error})") from error
    problems = _Problems(path)
    if root.tag != _ssd("SystemStructureDescription"):
        problems.add(root, f"root element is <{root.tag}>, expected "
                           f"<ssd:SystemStructureDescription> in namespace {SSD_NAMESPACE}")
        problems.raise_if_any()
    name = _required(root, "name", problems)
    system = _child(root, _ssd("System"))
    if system is None:
        problems.add(root, "<ssd:System> is missing")
        problems.raise_if_any()
    if _child(system, _ssd("Connectors")) is not None:
        problems.add(system, "system-level <ssd:Connectors> are not supported; connect "
                             "component connectors directly")

    components = []
    elements = _child(system, _ssd("Elements"))
    for element in (elements if elements is not None else []):
        if not isinstance(element.tag, str):
            continue
        if element.tag != _ssd("Component"):
            problems.add(element, f"{_describe(element)}: only <ssd:Component> elements are "
                                  f"supported (no nested systems or signal dictionaries)")
            continue
        component = _read_component(element, path.parent, problems, allow_outside)
        if component is None:
            continue
        if any(c.name == component.name for c in components):
            problems.add(element, f"component name '{component.name}' is used twice")
            continue
        components.append(component)

    connections = []
    connections_node = _child(system, _ssd("Connections"))
    for node in (connections_node if connections_node is not None else []):
        if not isinstance(node.tag, str):
            continue
        values = [node.get(a) for a in ("startElement", "startConnector",
                                        "endElement", "endConnector")]
        missing = [a for a, v in zip(("startElement", "startConnector",
                                      "endElement", "endConnector"), values) if not v]
        if missing:
            problems.add(node, f"<ssd:Connection>: attribute(s) {', '.join(missing)} missing "
                               f"(system-level connectors are not supported)")
            continue
        connections.append(Connection(*values))

    units = {}
    units_node = _child(root, _ssd("Units"))
    if units_node is not None:
        units = _read_units(units_node, problems)

    start_time = stop_time = base_step = None
    experiment = _child(root, _ssd("DefaultExperiment"))
    if experiment is not None:
        start_time = _float_attribute(experiment, "startTime", problems)
        stop_time = _float_attribute(experiment, "stopTime", problems)
        annotations = _child(experiment, _ssd("Annotations"))
        if annotations is not None:
            base_step = _read_base_step(annotations, problems)
    # Our loader applies every binding whatever its set's name; the name is kept for writing.
    set_names = [node.get("name") for node in root.iter(_ssv("ParameterSet"))]
    parameter_set_name = set_names[0] if set_names else None

    problems.raise_if_any()
    return SystemDescription(name=name, components=components, connections=connections,
                             path=path, units=units, start_time=start_time, stop_time=stop_time,
                             base_step=base_step, parameter_set_name=parameter_set_name)


# ----- writing --------------------------------------------------------------------------------

def _format_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        # repr round-trips a double exactly; SSP (xs:double) reads it back to the same bits.
        return repr(value)
    return str(value)


def _format_number(value):
    if float(value).is_integer():
        return str(int(value))
    return repr(float(value))


def _build_tree(system):
    root = etree.Element(_ssd("SystemStructureDescription"), nsmap=_NSMAP,
                         version="1.0", name=system.name)
    system_node = etree.SubElement(root, _ssd("System"), name=system.name)
    elements = etree.SubElement(system_node, _ssd("Elements"))
    for component in system.components:
        node = etree.SubElement(elements, _ssd("Component"), name=component.name,
                                type=component.type, source=component.source)
        if component.connectors:
            connectors = etree.SubElement(node, _ssd("Connectors"))
            for connector in component.connectors:
                connector_node = etree.SubElement(connectors, _ssd("Connector"),
                                                  name=connector.name, kind=connector.kind)
                type_node = etree.SubElement(connector_node, _ssc(connector.type))
                if connector.unit is not None:
                    type_node.set("unit", connector.unit)
        if component.parameters:
            bindings = etree.SubElement(node, _ssd("ParameterBindings"))
            binding = etree.SubElement(bindings, _ssd("ParameterBinding"))
            values = etree.SubElement(binding, _ssd("ParameterValues"))
            set_name = system.parameter_set_name or "default"
            parameter_set = etree.SubElement(values, _ssv("ParameterSet"), version="1.0",
                                             name=set_name)
            parameters = etree.SubElement(parameter_set, _ssv("Parameters"))
            for name, parameter in component.parameters.items():
                parameter_node = etree.SubElement(parameters, _ssv("Parameter"), name=name)
                etree.SubElement(parameter_node, _ssv(parameter.type),
                                 value=_format_value(parameter.value))
        if component.step_size_hint is not None:
            annotations = etree.SubElement(node, _ssd("Annotations"))
            annotation = etree.SubElement(annotations, _ssc("Annotation"),
                                          type=_OSP_ANNOTATION_TYPE)
            etree.SubElement(annotation, f"{{{OSP_NAMESPACE}}}StepSizeHint",
                             value=_format_value(float(component.step_size_hint)))
    if system.connections:
        connections = etree.SubElement(system_node, _ssd("Connections"))
        for connection in system.connections:
            etree.SubElement(connections, _ssd("Connection"),
                             startElement=connection.start_element,
                             startConnector=connection.start_connector,
                             endElement=connection.end_element,
                             endConnector=connection.end_connector)
    if system.units:
        units = etree.SubElement(root, _ssd("Units"))
        for name, exponents in system.units.items():
            unit = etree.SubElement(units, _ssc("Unit"), name=name)
            attributes = {k: _format_number(v) for k, v in exponents.items()
                          if k in _BASE_UNIT_ATTRIBUTES}
            etree.SubElement(unit, _ssc("BaseUnit"), attributes)
    if system.start_time is not None or system.stop_time is not None or system.base_step:
        experiment = etree.SubElement(root, _ssd("DefaultExperiment"))
        if system.start_time is not None:
            experiment.set("startTime", _format_value(float(system.start_time)))
        if system.stop_time is not None:
            experiment.set("stopTime", _format_value(float(system.stop_time)))
        if system.base_step is not None:
            # libcosim's fixed-step master reads its base step here (ssp_parser.cpp); without
            # it, from_ssp_file needs a step size argument.
            annotations = etree.SubElement(experiment, _ssd("Annotations"))
            annotation = etree.SubElement(annotations, _ssc("Annotation"),
                                          type=_OSP_ANNOTATION_TYPE)
            algorithm = etree.SubElement(annotation, f"{{{OSP_NAMESPACE}}}Algorithm")
            etree.SubElement(algorithm, f"{{{OSP_NAMESPACE}}}FixedStepAlgorithm",
                             baseStepSize=_format_value(float(system.base_step)))
    return root


def ssd_to_string(system, header=None):
    """Return the ``.ssd`` XML text of ``system``, with an optional leading comment."""
    root = _build_tree(system)
    etree.indent(root, space="  ")
    body = etree.tostring(root, encoding="unicode")
    comment = f"<!-- {header} -->\n" if header else ""
    return f'<?xml version="1.0" encoding="UTF-8"?>\n{comment}{body}\n'


def write_ssd(path, system, header=None):
    """Write ``system`` as an SSP 1.0 ``.ssd`` file.

    Parameters
    ----------
    path : str or pathlib.Path
        Destination file.
    system : SystemDescription
        What to write; component sources are written unchanged.
    header : str, optional
        Text of an XML comment placed before the root element (e.g. "generated by ...").

    Returns
    -------
    pathlib.Path
        The written file.
    """
    path = Path(path)
    path.write_text(ssd_to_string(system, header), encoding="utf-8")
    return path


# ----- the sonotrack system as data -----------------------------------------------------------

# Ports per FMU model, after DESIGN.md: (name, kind, type, unit). Only ports whose unit the design
# fixes are listed; extra outputs of an FMU need no connector to be recorded by our master.
FMU_PORTS = {
    "SoundSource": [
        ("x", "output", "Real", "m"),
        ("y", "output", "Real", "m"),
        ("vx", "output", "Real", "m/s"),
        ("vy", "output", "Real", "m/s"),
        ("emitting", "output", "Boolean", None),
        ("path", "parameter", "String", None),
    ],
    "AcousticLocalizer": [
        ("source_x", "input", "Real", "m"),
        ("source_y", "input", "Real", "m"),
        ("emitting", "input", "Boolean", None),
        ("robot_x", "input", "Real", "m"),
        ("robot_y", "input", "Real", "m"),
        ("robot_heading", "input", "Real", "rad"),
        ("distance", "output", "Real", "m"),
        ("bearing", "output", "Real", "rad"),
        ("valid", "output", "Boolean", None),
        ("tdoa_12", "output", "Real", "s"),
        ("tdoa_23", "output", "Real", "s"),
        ("measurement_id", "output", "Integer", None),
        ("seed", "parameter", "Integer", None),
    ],
    "CurvaturePlanner": [
        ("distance", "input", "Real", "m"),
        ("bearing", "input", "Real", "rad"),
        ("valid", "input", "Boolean", None),
        ("measurement_id", "input", "Integer", None),
        ("wheel_speed_left", "input", "Real", "m/s"),
        ("wheel_speed_right", "input", "Real", "m/s"),
        ("v_ref_left", "output", "Real", "m/s"),
        ("v_ref_right", "output", "Real", "m/s"),
        ("radius", "output", "Real", "m"),
        ("curvature", "output", "Real", "1/m"),
        ("arc_remaining", "output", "Real", "m"),
    ],
    "WheelController": [
        ("v_ref", "input", "Real", "m/s"),
        ("v_meas", "input", "Real", "m/s"),
        ("voltage", "output", "Real", "V"),
    ],
    "RobotPlant": [
        ("voltage_left", "input", "Real", "V"),
        ("voltage_right", "input", "Real", "V"),
        ("x", "output", "Real", "m"),
        ("y", "output", "Real", "m"),
        ("heading", "output", "Real", "rad"),
        ("encoder_left", "output", "Integer", None),
        ("encoder_right", "output", "Integer", None),
        ("wheel_speed_left", "output", "Real", "m/s"),
        ("wheel_speed_right", "output", "Real", "m/s"),
        ("odom_x", "output", "Real", "m"),
        ("odom_y", "output", "Real", "m"),
        ("odom_heading", "output", "Real", "rad"),
    ],
}

# Instance name -> FMU model name, in stepping-tie-break order. No FMU has direct feedthrough,
# so this is the Gauss-Seidel order: the plant steps before the controllers, which then sample
# v_meas at the same instant as the v_ref the planner has just produced (docs/system.md).
SONOTRACK_INSTANCES = {
    "source": "SoundSource",
    "localizer": "AcousticLocalizer",
    "planner": "CurvaturePlanner",
    "plant": "RobotPlant",
    "controller_left": "WheelController",
    "controller_right": "WheelController",
}

SONOTRACK_CONNECTIONS = [
    ("source.x", "localizer.source_x"),
    ("source.y", "localizer.source_y"),
    ("source.emitting", "localizer.emitting"),
    ("plant.x", "localizer.robot_x"),
    ("plant.y", "localizer.robot_y"),
    ("plant.heading", "localizer.robot_heading"),
    ("localizer.distance", "planner.distance"),
    ("localizer.bearing", "planner.bearing"),
    ("localizer.valid", "planner.valid"),
    ("localizer.measurement_id", "planner.measurement_id"),
    ("plant.wheel_speed_left", "planner.wheel_speed_left"),
    ("plant.wheel_speed_right", "planner.wheel_speed_right"),
    ("planner.v_ref_left", "controller_left.v_ref"),
    ("plant.wheel_speed_left", "controller_left.v_meas"),
    ("planner.v_ref_right", "controller_right.v_ref"),
    ("plant.wheel_speed_right", "controller_right.v_meas"),
    ("controller_left.voltage", "plant.voltage_left"),
    ("controller_right.voltage", "plant.voltage_right"),
]

# Only the values that define the default run; everything else keeps the FMU's default and is
# overridden per scenario.
SONOTRACK_PARAMETERS = {
    "source": {"path": ParameterValue("String", "s_curve")},
    "localizer": {"seed": ParameterValue("Integer", 1)},
}

# Communication steps in s (docs/system.md and scenarios/s_curve.toml give the reasoning).
SONOTRACK_STEP_SIZES = {
    "source": 0.01,
    "localizer": 0.01,
    "planner": 0.02,
    "controller_left": 0.02,
    "controller_right": 0.02,
    "plant": 0.02,
}


def _unit_bases():
    # Import lazily: the slave base pulls in pythonfmu, which reading an .ssd does not need.
    from components.common.slave import UNIT_BASES

    bases = {}
    for unit, exponents in UNIT_BASES.items():
        attributes = dict(exponents)
        if unit == "deg":
            attributes["factor"] = math.pi / 180.0
        bases[unit] = attributes
    return bases


def sonotrack_system(stop_time=30.0, fmu_prefix=""):
    """Return the sonotrack system (six FMU instances, 18 connections) as a description.

    Parameters
    ----------
    stop_time : float
        ``stopTime`` of the ``ssd:DefaultExperiment``, in s.
    fmu_prefix : str
        Prefix of every component source: ``""`` for FMUs next to the ``.ssd`` (``fmus/``),
        ``"resources/"`` inside an ``.ssp`` archive.

    Returns
    -------
    SystemDescription
        With ``path=None``; pass it to :func:`write_ssd`.
    """
    components = []
    used_units = set()
    for instance, model in SONOTRACK_INSTANCES.items():
        connectors = [Connector(name, kind, type_name, unit)
                      for name, kind, type_name, unit in FMU_PORTS[model]]
        used_units.update(c.unit for c in connectors if c.unit is not None)
        components.append(ComponentDescription(
            name=instance,
            source=f"{fmu_prefix}{model}.fmu",
            connectors=connectors,
            parameters=dict(SONOTRACK_PARAMETERS.get(instance, {})),
            step_size_hint=SONOTRACK_STEP_SIZES.get(instance),
        ))
    connections = []
    for start, end in SONOTRACK_CONNECTIONS:
        start_element, start_connector = start.split(".")
        end_element, end_connector = end.split(".")
        connections.append(Connection(start_element, start_connector, end_element, end_connector))
    bases = _unit_bases()
    units = {unit: bases[unit] for unit in sorted(used_units)}
    return SystemDescription(name="sonotrack", components=components, connections=connections,
                             units=units, start_time=0.0, stop_time=float(stop_time),
                             base_step=min(SONOTRACK_STEP_SIZES.values()),
                             parameter_set_name="default")


_GENERATED_HEADER = ("Generated by orchestrator/ssp.py (sonotrack_system); regenerate with "
                     "`python -m orchestrator.ssp fmus/SystemStructure.ssd` after port changes.")


def main(argv=None):
    """Write the sonotrack ``.ssd`` (default ``fmus/SystemStructure.ssd`` of this checkout)."""
    argv = sys.argv[1:] if argv is None else argv
    default = Path(__file__).resolve().parent.parent / "fmus" / "SystemStructure.ssd"
    target = Path(argv[0]) if argv else default
    write_ssd(target, sonotrack_system(), header=_GENERATED_HEADER)
    print(target)
    return 0


if __name__ == "__main__":
    sys.exit(main())
