"""Child of benchmarks/cosim_speed.py: one whole ``sonotrack run`` command, its phases timed.

Run as ``python _run_phases.py TIMES_JSON [sonotrack run arguments...]``. Wraps the library
functions that bound each phase (nothing in sonotrack is changed), writes wall-clock
timestamps (``time.time()``, comparable with the parent's) to TIMES_JSON when the command's
``main`` returns, and ends as the ``sonotrack`` console script does. Not a benchmark by itself (``make benchmarks`` skips files starting
with ``_``).
"""

import time

STARTED = time.time()

import json  # noqa: E402
import sys  # noqa: E402

marks = {"child_started": STARTED}


def _wrap(owner, name, before=None, after=None):
    original = getattr(owner, name)

    def wrapper(*args, **kwargs):
        if before:
            marks.setdefault(before, time.time())
        try:
            return original(*args, **kwargs)
        finally:
            if after:
                marks[after] = time.time()

    setattr(owner, name, wrapper)


def main():
    times_path, argv = sys.argv[1], sys.argv[2:]
    import orchestrator.cli as cli
    import orchestrator.master as master
    import orchestrator.outputs as outputs
    import orchestrator.run as run

    _wrap(run, "run_scenario", before="command_started", after="run_returned")
    _wrap(master.Master, "run", before="stepping_started", after="stepping_done")
    # the last summary write is the final one (status ok): the summary is on disk
    _wrap(outputs.RunFolder, "write_summary", after="summary_written")
    original_main = cli.main

    def main_then_save(arguments):
        status = original_main(arguments)
        marks["main_returned"] = time.time()
        with open(times_path, "w") as stream:
            json.dump(marks, stream)
        return status

    cli.main = main_then_save
    sys.argv = ["sonotrack"] + argv
    return cli.console_main()  # as the console script ends (a fast exit after `run`)


if __name__ == "__main__":
    sys.exit(main())
