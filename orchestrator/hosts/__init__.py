"""Other hosts of our FMUs and systems, used as independent cross-checks of our master.

- :mod:`~orchestrator.hosts.libcosim`: libcosim (libcosimpy) runs an ``.ssd`` in a child
  process and returns chosen outputs;
- :mod:`~orchestrator.hosts.ecos`: ecos (the ``ecospy`` wheel's C++ engine) runs FMUs and
  ``.ssd`` files.

Imports only :mod:`orchestrator.ssp` of the orchestrator.
"""

from .ecos import ecos_binary, ecos_environment, read_ecos_csv, run_ecos
from .libcosim import OBSERVERS, run_libcosim_ssd

__all__ = ["OBSERVERS", "ecos_binary", "ecos_environment", "read_ecos_csv", "run_ecos",
           "run_libcosim_ssd"]
