"""Run a slave class in-process, without FMI, behind the same interface as an FMU instance.

:class:`SlaveInstance` instantiates the pythonfmu slave class of an FMU directly from
``components/`` and offers :class:`orchestrator.fmu.handle.FmuInstance`'s interface, so the master
can step the same model code with and without the FMI layer. Used to measure what FMI costs.
"""

from components.common.errors import ConfigError
from components.system.instances import SlaveHandle

__all__ = ["SlaveInstance", "slave_class"]


def slave_class(model_name):
    """Import and return the slave class of the FMU ``model_name`` from ``components``."""
    import importlib

    from components import FMU_PACKAGES

    if model_name not in FMU_PACKAGES:
        raise ConfigError(f"no slave for model {model_name!r}; valid: {', '.join(FMU_PACKAGES)}")
    module = importlib.import_module(f"components.{FMU_PACKAGES[model_name]}.fmu")
    return getattr(module, model_name)


class SlaveInstance(SlaveHandle):
    """The slave class of an FMU, from ``components/``, stepped directly with
    :class:`FmuInstance`'s interface (:class:`components.system.instances.SlaveHandle`, the
    adapter the whole-system FMU steps its inner slaves through)."""

    def __init__(self, model_name, instance_name):
        super().__init__(slave_class(model_name)(instance_name=instance_name))
