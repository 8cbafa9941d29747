"""The SSP 1.0 object model: what one ``SystemStructure.ssd`` holds, as plain data.

Components with their typed connectors, connections, parameter values, units and the default
experiment, plus the namespaces and vocabularies (connector kinds, types) of the format. This
module knows neither XML nor the sonotrack system: :mod:`orchestrator.ssp.reader` and
:mod:`orchestrator.ssp.writer` translate it to and from a file, and
:mod:`orchestrator.ssp.sonotrack` fills it with our six FMU instances.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

__all__ = [
    "SSD_NAMESPACE",
    "SSC_NAMESPACE",
    "SSV_NAMESPACE",
    "OSP_NAMESPACE",
    "OSP_ANNOTATION_TYPE",
    "CONNECTOR_KINDS",
    "CONNECTOR_TYPES",
    "PARAMETER_TYPES",
    "BASE_UNIT_ATTRIBUTES",
    "FMU_TYPE",
    "STEP_SIZE_HINT_MAX",
    "ParameterValue",
    "Connector",
    "Connection",
    "ComponentDescription",
    "SystemDescription",
]

SSD_NAMESPACE = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC_NAMESPACE = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV_NAMESPACE = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
OSP_NAMESPACE = "http://opensimulationplatform.com/SSP/OSPAnnotations"
# ssc:Annotation type of libcosim's (Open Simulation Platform's) annotations.
OSP_ANNOTATION_TYPE = "com.opensimulationplatform"

CONNECTOR_KINDS = ("input", "output", "parameter", "calculatedParameter", "inout")
CONNECTOR_TYPES = ("Real", "Integer", "Boolean", "String", "Enumeration", "Binary")
PARAMETER_TYPES = ("Real", "Integer", "Boolean", "String")
# Attributes of ssc:BaseUnit: SI exponents, then factor and offset to the base unit.
BASE_UNIT_ATTRIBUTES = ("kg", "m", "s", "A", "K", "mol", "cd", "rad", "factor", "offset")
FMU_TYPE = "application/x-fmu-sharedlibrary"
# Largest accepted osp:StepSizeHint [s]; every sonotrack FMU's step range ends at 1 s.
STEP_SIZE_HINT_MAX = 1.0


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
        from orchestrator.files.paths import names_a_file

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
    type: str = FMU_TYPE

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
