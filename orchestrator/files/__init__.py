"""How the orchestrator names and writes files: paths in scenario files, atomic writes, JSON.

- :mod:`~orchestrator.files.paths`: a path named in a file is relative to that file and kept in
  its folder unless the user allows otherwise;
- :mod:`~orchestrator.files.atomic`: the one atomic writer (a temporary file in the same
  folder, fsync'ed on request, renamed over the target);
- :mod:`~orchestrator.files.json_policy`: the one JSON policy (non-finite numbers as ``null``,
  never an invalid ``NaN`` token).

This layer imports nothing else of the orchestrator; every other layer may import it.
"""

from .atomic import (TEMPORARY_PREFIX, TEMPORARY_SUFFIX, atomic_open, atomic_write_bytes,
                     atomic_write_json, atomic_write_text)
from .json_policy import dumps, json_ready
from .paths import ALLOW_OUTSIDE_HINT, FILE_SUFFIXES, confine, names_a_file

__all__ = ["ALLOW_OUTSIDE_HINT", "FILE_SUFFIXES", "TEMPORARY_PREFIX", "TEMPORARY_SUFFIX",
           "atomic_open", "atomic_write_bytes", "atomic_write_json", "atomic_write_text",
           "confine", "dumps", "json_ready", "names_a_file"]
