"""Stop a test's child Python process at a chosen moment, so that the test can kill its parent
there (the kill tests of sweeps, runs and renderers).

Python imports ``sitecustomize`` at start-up from its path, so every Python process started
with this folder on ``PYTHONPATH`` loads it, and every process forked from one keeps it.
``SONOTRACK_TEST_PAUSE`` names the moment as ``EVENT GLOB NTH``: at the NTH audit event EVENT
(``open``, ``os.rename``, ``import``, see the table of audit events in the Python docs) whose
first argument matches GLOB (:mod:`fnmatch`, ``*`` also crosses ``/``), the process stops
itself with SIGSTOP before the call goes on. The test sees it in state ``T`` in ``/proc``,
kills what it means to kill and sends SIGCONT. Events are counted per process (a forked child
goes on from its parent's count at the fork). Without the variable nothing is installed.

Example: ``open */runs/*/results.csv 2`` stops a sweep's worker as it starts its second run.
"""

import os


def _install(spec):
    import fnmatch
    import re
    import signal
    import sys

    event, rest = spec.split(" ", 1)
    pattern, nth = rest.rsplit(" ", 1)
    matches = re.compile(fnmatch.translate(pattern)).match
    nth = int(nth)
    seen = 0

    def hook(name, args):
        nonlocal seen
        if name != event or not args:
            return
        target = args[0]
        if isinstance(target, bytes):
            target = os.fsdecode(target)
        elif isinstance(target, os.PathLike):
            target = os.fspath(target)
        if not isinstance(target, str) or not matches(target):
            return
        seen += 1
        if seen == nth:
            os.kill(os.getpid(), signal.SIGSTOP)

    sys.addaudithook(hook)


if os.environ.get("SONOTRACK_TEST_PAUSE"):
    _install(os.environ["SONOTRACK_TEST_PAUSE"])
