"""A slave object behind the master's instance interface, stepped in this process (no FMI).

:class:`SlaveHandle` offers what :class:`~components.system.master.Master` asks of an instance
(``variables``, ``instantiate``, ``port_group``, ``read``, ``write``, ``do_step``,
``terminate``, ``last_error``), the interface of the FMI handle
(``orchestrator/fmu/handle.py``), around a pythonfmu slave object. The whole-system FMU steps
its inner slaves through it; ``sonotrack run --backend in-process`` does the same from the
host side (``orchestrator/fmu/inprocess.py``). Values travel as the FMI calls would carry
them: a Real as a float, an Integer as an int, a Boolean as a bool.
"""

import importlib
from dataclasses import dataclass
from types import SimpleNamespace

__all__ = ["SlaveHandle", "StepRefused", "slave_class"]

_CAST = {"Real": float, "Integer": int, "Boolean": bool, "String": str}


class StepRefused(Exception):
    """``do_step`` returned False: what an FMU host sees as fmi2Discard (``status`` 2)."""

    status = 2


def slave_class(model, package):
    """The slave class ``model`` defined in the sibling sub-package ``package``'s ``fmu.py``.

    The import is relative to this package's parent, so it finds ``components.<package>`` in
    the repository and the private copy ``_sonotrack_..._<tag>.<package>`` inside a built FMU.
    """
    parent = __package__.rpartition(".")[0]
    module = importlib.import_module(f"{parent}.{package}.fmu")
    return getattr(module, model)


@dataclass
class _Group:
    type: str
    names: tuple
    references: list
    values: list

    def __len__(self):
        return len(self.names)


class SlaveHandle:
    """One slave object with the interface of an FMU instance handle.

    Parameters
    ----------
    slave : pythonfmu.Fmi2Slave
        The slave, constructed (``instance_name`` is the instance's name).
    """

    def __init__(self, slave):
        self.slave = slave
        self.name = slave.instance_name
        self.variables = {}
        for variable in slave.vars.values():
            self.variables[variable.name] = SimpleNamespace(
                name=variable.name, valueReference=variable.value_reference,
                causality=variable.causality.name, type=type(variable).__name__)
        self._get = {"Real": slave.get_real, "Integer": slave.get_integer,
                     "Boolean": slave.get_boolean}
        self._set = {"Real": slave.set_real, "Integer": slave.set_integer,
                     "Boolean": slave.set_boolean, "String": slave.set_string}

    def instantiate(self, start_time=0.0, stop_time=None, parameters=None):
        """Set up, set ``parameters`` in initialisation mode and leave it, as an FMU would."""
        self.slave.setup_experiment(start_time, stop_time, None)
        self.slave.enter_initialization_mode()
        for name, value in (parameters or {}).items():
            variable = self.variables[name]
            self._set[variable.type]([variable.valueReference], [_CAST[variable.type](value)])
        self.slave.exit_initialization_mode()

    def port_group(self, type_name, names):
        """Resolve ports of one type; return a group with a plain list buffer."""
        references = [self.variables[n].valueReference for n in names]
        return _Group(type_name, tuple(names), references, [0] * len(names))

    def read(self, group):
        """Read the group's ports into its buffer; return the buffer."""
        if group.names:
            group.values[:] = self._get[group.type](group.references)
        return group.values

    def write(self, group):
        """Set the group's ports from its buffer."""
        if group.names:
            self._set[group.type](group.references, list(group.values))

    def do_step(self, time, step):
        """Step the slave; raise :class:`StepRefused` if it refuses (returns False)."""
        if not self.slave.do_step(time, step):
            raise StepRefused(f"{self.name}: do_step refused")

    def terminate(self):
        self.slave.terminate()

    def last_error(self):
        """The slave's latest logged line with an error status, or ``""``."""
        for message in reversed(self.slave.log_queue):
            if message.status.value >= 2:
                return message.msg
        return ""
