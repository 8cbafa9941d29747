"""A loaded system: components with their FMUs, connections resolved to value references.

:func:`load_system` reads the ``.ssd`` and the model descriptions of its FMUs, runs
:func:`~orchestrator.system.checks.check_system` and either raises one
:class:`~orchestrator.system.checks.SystemDescriptionError` listing all problems or returns a
:class:`System`, so that the master never looks a name up again.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from components.common.errors import ConfigError

from ..ssp import ParameterValue, SystemDescription, read_ssd
from .checks import SystemDescriptionError, find_problems
from .graph import gauss_seidel_order, valid_connections
from .variables import ResolvedConnection, resolve_variable, suggest

__all__ = ["SystemComponent", "System", "load_system"]


@dataclass
class SystemComponent:
    """A component instance with its FMU.

    Attributes
    ----------
    name : str
        Instance name.
    fmu_path : pathlib.Path
        The ``.fmu`` file (shared by instances of the same FMU).
    model_description : fmpy.model_description.ModelDescription
        Its model description, read once.
    parameters : dict of str to ParameterValue
        Values bound in the ``.ssd``, by variable name.
    step_size_hint : float or None
        The ``.ssd``'s suggested communication step, in s.
    """

    name: str
    fmu_path: Path
    model_description: object
    parameters: dict[str, ParameterValue] = field(default_factory=dict)
    step_size_hint: float | None = None

    def variable(self, name):
        """Return the :class:`Variable` called ``name``; raise ConfigError naming the choices."""
        for v in self.model_description.modelVariables:
            if v.name == name:
                return resolve_variable(self.name, v)
        names = [v.name for v in self.model_description.modelVariables]
        raise ConfigError(f"{self.name}.{name}: no such variable in {self.fmu_path.name}"
                          f"{suggest(name, names)}; variables are: {', '.join(names)}")


@dataclass
class System:
    """A checked system, ready to instantiate.

    Attributes
    ----------
    description : SystemDescription
        What the ``.ssd`` says.
    components : list of SystemComponent
        In ``.ssd`` order.
    connections : list of ResolvedConnection
        In ``.ssd`` order, each from an output to an input.
    """

    description: SystemDescription
    components: list[SystemComponent]
    connections: list[ResolvedConnection]

    def component(self, name):
        """Return the component called ``name``; raise ConfigError naming the choices."""
        for component in self.components:
            if component.name == name:
                return component
        names = [c.name for c in self.components]
        raise ConfigError(f"{self.description.path}: no component '{name}'"
                          f"{suggest(name, names)}; components are: {', '.join(names)}")

    def variable(self, qualified_name):
        """Return the variable ``"instance.port"``; raise ConfigError naming the choices."""
        instance, dot, port = qualified_name.partition(".")
        if not dot or not port:
            raise ConfigError(f"{qualified_name!r} is not of the form 'instance.port'")
        return self.component(instance).variable(port)

    @property
    def parameter_values(self):
        """All bound parameter values, keyed ``"instance.parameter"``."""
        return {f"{c.name}.{name}": value
                for c in self.components for name, value in c.parameters.items()}

    def stepping_order(self):
        """Component names in Gauss-Seidel stepping order (see :func:`gauss_seidel_order`)."""
        model_descriptions = {c.name: c.model_description for c in self.components}
        return gauss_seidel_order(self.description, model_descriptions)


def load_system(ssd_path, fmu_dir=None, allow_unconnected=(), allow_outside=False):
    """Read an ``.ssd`` and its FMUs' model descriptions, check them and resolve the system.

    Parameters
    ----------
    ssd_path : str or pathlib.Path
        The ``SystemStructure.ssd`` file.
    fmu_dir : str or pathlib.Path, optional
        Directory against which component sources resolve; default: the ``.ssd``'s directory
        (as libcosim does).
    allow_unconnected : iterable of str
        ``"instance.port"`` inputs that may stay unconnected.
    allow_outside : bool
        Accept parameter files and waypoint CSVs outside their file's folder (see
        :func:`orchestrator.ssp.read_ssd`).

    Returns
    -------
    System
        Components with their FMU paths and model descriptions, connections resolved to value
        references, and bound parameter values.

    Raises
    ------
    ConfigError
        If the ``.ssd`` cannot be parsed.
    SystemDescriptionError
        Listing every problem :func:`check_system` finds, plus FMUs that are missing or cannot
        be read.
    """
    from orchestrator.fmu.handle import model_description

    description = read_ssd(ssd_path, allow_outside=allow_outside)
    base = Path(fmu_dir) if fmu_dir is not None else description.directory
    model_descriptions, unavailable, fmu_paths, cache = {}, {}, {}, {}
    for component in description.components:
        fmu_path = (base / component.source).resolve()
        fmu_paths[component.name] = fmu_path
        if fmu_path not in cache:
            if not fmu_path.is_file():
                cache[fmu_path] = f"not found at {fmu_path}"
            else:
                try:
                    cache[fmu_path] = model_description(fmu_path)
                except Exception as error:  # fmpy raises bare Exceptions for invalid XML
                    cache[fmu_path] = f"cannot be read ({fmu_path}: {error})"
        entry = cache[fmu_path]
        if isinstance(entry, str):
            unavailable[component.name] = entry
        else:
            model_descriptions[component.name] = entry
    problems = find_problems(description, model_descriptions, allow_unconnected, unavailable)
    if problems:
        raise SystemDescriptionError(problems, description.path)
    components = [SystemComponent(c.name, fmu_paths[c.name], model_descriptions[c.name],
                                  dict(c.parameters), c.step_size_hint)
                  for c in description.components]
    connections = [ResolvedConnection(resolve_variable(connection.start_element, start),
                                      resolve_variable(connection.end_element, end))
                   for connection, start, end in
                   valid_connections(description, model_descriptions)]
    return System(description, components, connections)
