"""Run a slave class in-process, without FMI, behind the same interface as an FMU instance.

:class:`SlaveInstance` instantiates the pythonfmu slave class of an FMU directly from
``components/`` and offers :class:`orchestrator.fmu.handle.FmuInstance`'s interface, so the master
can step the same model code with and without the FMI layer. Used to measure what FMI costs.
"""

from dataclasses import dataclass
from types import SimpleNamespace

from components.common.errors import ConfigError

__all__ = ["SlaveInstance", "slave_class"]


class _Refused(Exception):
    """do_step returned False (what an FMU host sees as fmi2Discard)."""

    status = 2


def slave_class(model_name):
    """Import and return the slave class of the FMU ``model_name`` from ``components``."""
    import importlib

    from components import FMU_PACKAGES

    if model_name not in FMU_PACKAGES:
        raise ConfigError(f"no slave for model {model_name!r}; valid: {', '.join(FMU_PACKAGES)}")
    module = importlib.import_module(f"components.{FMU_PACKAGES[model_name]}.fmu")
    return getattr(module, model_name)


@dataclass
class _Group:
    type: str
    names: tuple
    references: list
    values: list

    def __len__(self):
        return len(self.names)


class SlaveInstance:
    """A slave object stepped directly, with :class:`FmuInstance`'s interface."""

    def __init__(self, model_name, instance_name):
        self.name = instance_name
        self.slave = slave_class(model_name)(instance_name=instance_name)
        self.variables = {}
        for variable in self.slave.vars.values():
            self.variables[variable.name] = SimpleNamespace(
                name=variable.name, valueReference=variable.value_reference,
                causality=variable.causality.name, type=type(variable).__name__)
        self._get = {"Real": self.slave.get_real, "Integer": self.slave.get_integer,
                     "Boolean": self.slave.get_boolean}
        self._set = {"Real": self.slave.set_real, "Integer": self.slave.set_integer,
                     "Boolean": self.slave.set_boolean, "String": self.slave.set_string}

    def instantiate(self, start_time=0.0, stop_time=None, parameters=None):
        """Set up, set parameters in initialisation mode and leave it, as an FMU would."""
        self.slave.setup_experiment(start_time, stop_time, None)
        self.slave.enter_initialization_mode()
        for name, value in (parameters or {}).items():
            variable = self.variables[name]
            cast = {"Real": float, "Integer": int, "Boolean": bool}.get(variable.type, str)
            self._set[variable.type]([variable.valueReference], [cast(value)])
        self.slave.exit_initialization_mode()

    def port_group(self, type_name, names):
        """Resolve ports of one type; return a group with a plain list buffer."""
        references = [self.variables[n].valueReference for n in names]
        return _Group(type_name, tuple(names), references, [0] * len(names))

    def read(self, group):
        if group.names:
            group.values[:] = self._get[group.type](group.references)
        return group.values

    def write(self, group):
        if group.names:
            self._set[group.type](group.references, list(group.values))

    def do_step(self, time, step):
        if not self.slave.do_step(time, step):
            raise _Refused(f"{self.name}: do_step refused")

    def terminate(self):
        self.slave.terminate()

    def last_error(self):
        for message in reversed(self.slave.log_queue):
            if message.status.value >= 2:
                return message.msg
        return ""
