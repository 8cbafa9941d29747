"""The host side of one FMU: unpack it once, drive one instance through one handle.

- :mod:`~orchestrator.fmu.cache`: FMUs unpacked safely, once, into a cache keyed by content;
- :mod:`~orchestrator.fmu.handle`: :class:`FmuInstance`, one instance behind one handle
  (value references resolved once, batched get/set);
- :mod:`~orchestrator.fmu.inprocess`: :class:`SlaveInstance`, a slave class run in-process
  behind the same interface, without FMI;
- :mod:`~orchestrator.fmu.info`: what an FMU declares, as ``sonotrack info`` shows it.

Imports only :mod:`orchestrator.files` of the orchestrator.
"""

from .cache import (MAX_CACHED_BYTES, MAX_CACHED_FMUS, MAX_UNPACKED_BYTES, cache_dir, cache_limits,
                    check_archive, extract_fmu, max_unpacked_bytes, prune_cache)
from .handle import FmuInstance, PortGroup, extract_once, model_description
from .info import VariableInfo, find_fmu, fmu_info, format_info
from .inprocess import SlaveInstance, slave_class

__all__ = ["MAX_CACHED_BYTES", "MAX_CACHED_FMUS", "MAX_UNPACKED_BYTES", "FmuInstance", "PortGroup",
           "SlaveInstance", "VariableInfo", "cache_dir", "cache_limits", "check_archive",
           "extract_fmu", "extract_once", "find_fmu", "fmu_info", "format_info",
           "max_unpacked_bytes", "model_description", "prune_cache", "slave_class"]
