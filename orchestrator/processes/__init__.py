"""The processes the orchestrator starts and records: who they are, and that they end with
their parent.

- :mod:`~orchestrator.processes.identity`: a record of a process (id, host, start time) and
  whether the process a record names still runs (pid reuse and reboots included);
- :mod:`~orchestrator.processes.lifetime`: a child ends when its parent dies, however it dies
  (Linux's parent-death signal, a lifeline pipe only the parent holds, a command line that
  arms the signal before ``exec``);
- :mod:`~orchestrator.processes.beside`: a function run in a forked child while the parent goes
  on, its value returned through a pipe (or a list of them over a few children).

This layer imports nothing else of the orchestrator; every other layer may import it.
"""

from .beside import Beside, BesideEach
from .identity import ALIVE, GONE, UNKNOWN, describe, process_record, process_state
from .lifetime import (Lifeline, arm_parent_death_signal, die_with_parent, end_this_process,
                       tied_command, watch_lifeline)

__all__ = ["ALIVE", "GONE", "UNKNOWN", "Beside", "BesideEach", "Lifeline",
           "arm_parent_death_signal", "describe", "die_with_parent", "end_this_process",
           "process_record", "process_state", "tied_command", "watch_lifeline"]
