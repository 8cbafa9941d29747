"""Write the object model as an SSP 1.0 ``.ssd`` file.

The writer uses exactly the prefixes ``ssd``, ``ssc``, ``ssv`` and ``osp``, because libcosim's
parser matches element names with their prefix, not their namespace. Component ``source``
attributes are written as given; libcosim resolves them against the ``.ssd`` file's own URI, so
``source="SoundSource.fmu"`` finds the FMU next to the ``.ssd`` (our ``fmus/`` layout) and
``source="resources/SoundSource.fmu"`` finds it in an ``.ssp`` archive's ``resources/`` folder
(see :meth:`~orchestrator.ssp.SystemDescription.with_source_prefix`). Reals are written with
``repr`` so that reading the file back gives the same bits.
"""

from __future__ import annotations

from pathlib import Path

from lxml import etree

from ._xml import NSMAP, osp_tag, ssc_tag, ssd_tag, ssv_tag
from .model import BASE_UNIT_ATTRIBUTES, OSP_ANNOTATION_TYPE

__all__ = ["ssd_to_string", "write_ssd"]


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
    root = etree.Element(ssd_tag("SystemStructureDescription"), nsmap=NSMAP,
                         version="1.0", name=system.name)
    system_node = etree.SubElement(root, ssd_tag("System"), name=system.name)
    elements = etree.SubElement(system_node, ssd_tag("Elements"))
    for component in system.components:
        node = etree.SubElement(elements, ssd_tag("Component"), name=component.name,
                                type=component.type, source=component.source)
        if component.connectors:
            connectors = etree.SubElement(node, ssd_tag("Connectors"))
            for connector in component.connectors:
                connector_node = etree.SubElement(connectors, ssd_tag("Connector"),
                                                  name=connector.name, kind=connector.kind)
                type_node = etree.SubElement(connector_node, ssc_tag(connector.type))
                if connector.unit is not None:
                    type_node.set("unit", connector.unit)
        if component.parameters:
            bindings = etree.SubElement(node, ssd_tag("ParameterBindings"))
            binding = etree.SubElement(bindings, ssd_tag("ParameterBinding"))
            values = etree.SubElement(binding, ssd_tag("ParameterValues"))
            set_name = system.parameter_set_name or "default"
            parameter_set = etree.SubElement(values, ssv_tag("ParameterSet"), version="1.0",
                                             name=set_name)
            parameters = etree.SubElement(parameter_set, ssv_tag("Parameters"))
            for name, parameter in component.parameters.items():
                parameter_node = etree.SubElement(parameters, ssv_tag("Parameter"), name=name)
                etree.SubElement(parameter_node, ssv_tag(parameter.type),
                                 value=_format_value(parameter.value))
        if component.step_size_hint is not None:
            annotations = etree.SubElement(node, ssd_tag("Annotations"))
            annotation = etree.SubElement(annotations, ssc_tag("Annotation"),
                                          type=OSP_ANNOTATION_TYPE)
            etree.SubElement(annotation, osp_tag("StepSizeHint"),
                             value=_format_value(float(component.step_size_hint)))
    if system.connections:
        connections = etree.SubElement(system_node, ssd_tag("Connections"))
        for connection in system.connections:
            etree.SubElement(connections, ssd_tag("Connection"),
                             startElement=connection.start_element,
                             startConnector=connection.start_connector,
                             endElement=connection.end_element,
                             endConnector=connection.end_connector)
    if system.units:
        units = etree.SubElement(root, ssd_tag("Units"))
        for name, exponents in system.units.items():
            unit = etree.SubElement(units, ssc_tag("Unit"), name=name)
            attributes = {k: _format_number(v) for k, v in exponents.items()
                          if k in BASE_UNIT_ATTRIBUTES}
            etree.SubElement(unit, ssc_tag("BaseUnit"), attributes)
    if system.start_time is not None or system.stop_time is not None or system.base_step:
        experiment = etree.SubElement(root, ssd_tag("DefaultExperiment"))
        if system.start_time is not None:
            experiment.set("startTime", _format_value(float(system.start_time)))
        if system.stop_time is not None:
            experiment.set("stopTime", _format_value(float(system.stop_time)))
        if system.base_step is not None:
            # libcosim's fixed-step master reads its base step here (ssp_parser.cpp); without
            # it, from_ssp_file needs a step size argument.
            annotations = etree.SubElement(experiment, ssd_tag("Annotations"))
            annotation = etree.SubElement(annotations, ssc_tag("Annotation"),
                                          type=OSP_ANNOTATION_TYPE)
            algorithm = etree.SubElement(annotation, osp_tag("Algorithm"))
            etree.SubElement(algorithm, osp_tag("FixedStepAlgorithm"),
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
