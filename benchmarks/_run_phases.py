"""Child of benchmarks/cosim_speed.py: one whole ``sonotrack run`` command, its phases timed.

Run as ``python _run_phases.py TIMES_JSON VARIANT [sonotrack run arguments...]``. Wraps the
library functions that bound each phase of the command's own process, writes wall-clock
timestamps (``time.time()``, comparable with the parent's and the renderers') to TIMES_JSON
when the command's ``main`` returns, and ends as the ``sonotrack`` console script does. Not a
benchmark by itself (``make benchmarks`` skips files starting with ``_``).

VARIANT is ``default`` (sonotrack as shipped: one renderer process, which forks to draw its
figures on two cores), ``one-renderer`` (the same renderer drawing every figure itself), or
``in-process`` (what the command did before the renderer: import matplotlib and draw every
figure in its own process once the summary is on disk, through the same
:func:`orchestrator.run.plots.plot_run`), so that one run of the benchmark
measures what each piece buys.
"""

import time

STARTED = time.time()

import json  # noqa: E402
import sys  # noqa: E402

marks = {"child_started": STARTED, "summary_writes": []}


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


class _InProcessRenderer:
    """The plots drawn in the command's own process after the summary (the old way)."""

    def __init__(self, processes=None):
        self.timings = {}

    def render(self, results_csv, out_dir, max_rows):
        from orchestrator.run.plots import plot_run
        from orchestrator.run.results import read_results

        return plot_run(read_results(results_csv, max_rows=max_rows), out_dir)

    def close(self):
        pass


def main():
    times_path, variant, argv = sys.argv[1], sys.argv[2], sys.argv[3:]
    import orchestrator.cli as cli
    import orchestrator.run.master as master
    import orchestrator.run.folder as outputs
    import orchestrator.run.plot_renderer as plot_renderer
    import orchestrator.run.runner as run

    if variant == "in-process":
        plot_renderer.PlotRenderer = _InProcessRenderer
    elif variant == "one-renderer":
        original_init = plot_renderer.PlotRenderer.__init__
        plot_renderer.PlotRenderer.__init__ = (
            lambda self, processes=None: original_init(self, processes=1))
    elif variant != "default":
        raise SystemExit(f"unknown variant {variant!r}")
    _wrap(run, "run_scenario", before="command_started", after="run_returned")
    _wrap(master.Master, "run", before="stepping_started", after="stepping_done")
    original_write = outputs.RunFolder.write_summary

    def write_summary(self, summary):
        original_write(self, summary)
        marks["summary_writes"].append(time.time())

    outputs.RunFolder.write_summary = write_summary
    renderer_class = plot_renderer.PlotRenderer
    original_render = renderer_class.render

    def render(self, *args, **kwargs):
        marks["render_called"] = time.time()
        try:
            return original_render(self, *args, **kwargs)
        finally:
            marks["render_returned"] = time.time()
            marks["renderers"] = [self.timings]

    renderer_class.render = render
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
