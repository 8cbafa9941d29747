"""How the orchestrator names files: paths written inside scenario and system files.

- :mod:`~orchestrator.files.paths`: a path named in a file is relative to that file and kept in
  its folder unless the user allows otherwise.

This layer imports nothing else of the orchestrator; every other layer may import it.
"""

from .paths import ALLOW_OUTSIDE_HINT, FILE_SUFFIXES, confine, names_a_file

__all__ = ["ALLOW_OUTSIDE_HINT", "FILE_SUFFIXES", "confine", "names_a_file"]
