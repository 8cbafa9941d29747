"""Read and write SSP 1.0 system structure descriptions (``SystemStructure.ssd``).

The package knows the file format only: components with their typed connectors, connections,
inline or ``.ssv`` parameter values, units and the default experiment. Whether a description
fits its FMUs is the business of :mod:`orchestrator.system`.

Modules, one concept each:

- :mod:`~orchestrator.ssp.model`: the object model (:class:`SystemDescription` and its parts)
  and the format's namespaces and vocabularies;
- :mod:`~orchestrator.ssp.reader`: :func:`read_ssd`, which validates the file's structure and
  reports every problem at once;
- :mod:`~orchestrator.ssp.parameters`: ``ssv:ParameterSet`` values and ``.ssv`` bindings;
- :mod:`~orchestrator.ssp.writer`: :func:`write_ssd` and :func:`ssd_to_string`;
- :mod:`~orchestrator.ssp.sonotrack`: the sonotrack system as data (:func:`sonotrack_system`);
  ``python -m orchestrator.ssp [path]`` regenerates the committed ``fmus/SystemStructure.ssd``.

This ``__init__`` re-exports the public names of all five, so ``from orchestrator.ssp import
read_ssd`` is the stable import path.
"""

from .model import (CONNECTOR_KINDS, CONNECTOR_TYPES, OSP_NAMESPACE, PARAMETER_TYPES,
                    SSC_NAMESPACE, SSD_NAMESPACE, SSV_NAMESPACE, ComponentDescription, Connection,
                    Connector, ParameterValue, SystemDescription)
from .reader import read_ssd
from .sonotrack import (FMU_PORTS, SONOTRACK_CONNECTIONS, SONOTRACK_INSTANCES,
                        SONOTRACK_PARAMETERS, SONOTRACK_STEP_SIZES, sonotrack_system)
from .writer import ssd_to_string, write_ssd

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
