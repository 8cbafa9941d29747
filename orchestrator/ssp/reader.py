"""Read and validate an SSP 1.0 ``SystemStructure.ssd`` into the object model.

:func:`read_ssd` checks the file's structure only (required attributes, connector kinds and
types, step-size hints, duplicate names, unsupported hierarchical systems) and reports every
problem at once, each with file and line. Whether the description fits its FMUs is the business
of :mod:`orchestrator.system`.
"""

from __future__ import annotations

from pathlib import Path

from lxml import etree

from components.common.errors import ConfigError

from ._xml import (Problems, child_elements, describe, first_child, float_attribute,
                   osp_tag, required_attribute, ssc_tag, ssd_tag, ssv_tag)
from .model import (BASE_UNIT_ATTRIBUTES, CONNECTOR_KINDS, CONNECTOR_TYPES, FMU_TYPE,
                    OSP_ANNOTATION_TYPE, SSC_NAMESPACE, SSD_NAMESPACE, STEP_SIZE_HINT_MAX,
                    ComponentDescription, Connection, Connector, SystemDescription)
from .parameters import read_parameter_bindings

__all__ = ["read_ssd"]


def _read_connector(connector, problems):
    name = required_attribute(connector, "name", problems)
    kind = required_attribute(connector, "kind", problems)
    if kind is not None and kind not in CONNECTOR_KINDS:
        problems.add(connector, f"{describe(connector)}: kind {kind!r} is not one of "
                                f"{', '.join(CONNECTOR_KINDS)}")
    typed = [child for child in connector if isinstance(child.tag, str)
             and etree.QName(child).namespace == SSC_NAMESPACE
             and etree.QName(child).localname in CONNECTOR_TYPES]
    if len(typed) != 1:
        problems.add(connector, f"{describe(connector)}: needs exactly one type element, one of "
                                f"{', '.join('ssc:' + t for t in CONNECTOR_TYPES)}")
        return None
    if name is None or kind is None:
        return None
    type_name = etree.QName(typed[0]).localname
    return Connector(name, kind, type_name, typed[0].get("unit"))


def _read_step_size_hint(annotations, problems):
    for annotation in child_elements(annotations, ssc_tag("Annotation")):
        if annotation.get("type") != OSP_ANNOTATION_TYPE:
            continue
        hint = first_child(annotation, osp_tag("StepSizeHint"))
        if hint is not None:
            value = float_attribute(hint, "value", problems)
            if value is not None and not 0.0 < value <= STEP_SIZE_HINT_MAX:
                problems.add(hint, f"{describe(hint)}: value={hint.get('value')!r} is not a "
                                   f"step size in (0, {STEP_SIZE_HINT_MAX!r}] s")
                return None
            return value
    return None


def _read_base_step(annotations, problems):
    for annotation in child_elements(annotations, ssc_tag("Annotation")):
        if annotation.get("type") != OSP_ANNOTATION_TYPE:
            continue
        algorithm = first_child(annotation, osp_tag("Algorithm"))
        fixed = (first_child(algorithm, osp_tag("FixedStepAlgorithm"))
                 if algorithm is not None else None)
        if fixed is not None:
            return float_attribute(fixed, "baseStepSize", problems)
    return None


def _read_component(node, directory, problems, allow_outside=False):
    name = required_attribute(node, "name", problems)
    source = required_attribute(node, "source", problems)
    kind = node.get("type", FMU_TYPE)
    if kind != FMU_TYPE:
        problems.add(node, f"{describe(node)}: type {kind!r} is not supported; only {FMU_TYPE}")
    connectors = []
    connectors_node = first_child(node, ssd_tag("Connectors"))
    if connectors_node is not None:
        for connector_node in child_elements(connectors_node, ssd_tag("Connector")):
            connector = _read_connector(connector_node, problems)
            if connector is None:
                continue
            if any(c.name == connector.name for c in connectors):
                problems.add(connector_node, f"component '{name}': connector "
                                             f"'{connector.name}' is declared twice")
                continue
            connectors.append(connector)
    parameters = {}
    bindings = first_child(node, ssd_tag("ParameterBindings"))
    if bindings is not None:
        parameters = read_parameter_bindings(name, bindings, directory, problems,
                                              allow_outside)
    annotations = first_child(node, ssd_tag("Annotations"))
    hint = _read_step_size_hint(annotations, problems) if annotations is not None else None
    if name is None or source is None:
        return None
    return ComponentDescription(name, source, connectors, parameters, hint)


def _read_units(units_node, problems):
    units = {}
    for unit in child_elements(units_node, ssc_tag("Unit")):
        name = required_attribute(unit, "name", problems)
        base = first_child(unit, ssc_tag("BaseUnit"))
        exponents = {}
        if base is not None:
            for attribute in BASE_UNIT_ATTRIBUTES:
                value = float_attribute(base, attribute, problems)
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
        see :mod:`orchestrator.files.paths`).

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
    problems = Problems(path)
    if root.tag != ssd_tag("SystemStructureDescription"):
        problems.add(root, f"root element is <{root.tag}>, expected "
                           f"<ssd:SystemStructureDescription> in namespace {SSD_NAMESPACE}")
        problems.raise_if_any()
    name = required_attribute(root, "name", problems)
    system = first_child(root, ssd_tag("System"))
    if system is None:
        problems.add(root, "<ssd:System> is missing")
        problems.raise_if_any()
    if first_child(system, ssd_tag("Connectors")) is not None:
        problems.add(system, "system-level <ssd:Connectors> are not supported; connect "
                             "component connectors directly")

    components = []
    elements = first_child(system, ssd_tag("Elements"))
    for element in (elements if elements is not None else []):
        if not isinstance(element.tag, str):
            continue
        if element.tag != ssd_tag("Component"):
            problems.add(element, f"{describe(element)}: only <ssd:Component> elements are "
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
    connections_node = first_child(system, ssd_tag("Connections"))
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
    units_node = first_child(root, ssd_tag("Units"))
    if units_node is not None:
        units = _read_units(units_node, problems)

    start_time = stop_time = base_step = None
    experiment = first_child(root, ssd_tag("DefaultExperiment"))
    if experiment is not None:
        start_time = float_attribute(experiment, "startTime", problems)
        stop_time = float_attribute(experiment, "stopTime", problems)
        annotations = first_child(experiment, ssd_tag("Annotations"))
        if annotations is not None:
            base_step = _read_base_step(annotations, problems)
    # Our loader applies every binding whatever its set's name; the name is kept for writing.
    set_names = [node.get("name") for node in root.iter(ssv_tag("ParameterSet"))]
    parameter_set_name = set_names[0] if set_names else None

    problems.raise_if_any()
    return SystemDescription(name=name, components=components, connections=connections,
                             path=path, units=units, start_time=start_time, stop_time=stop_time,
                             base_step=base_step, parameter_set_name=parameter_set_name)
