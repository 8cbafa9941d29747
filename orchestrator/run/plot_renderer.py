"""A run's plots drawn by a renderer process that gets ready while the run steps.

Importing matplotlib and loading its fonts cost about half of what drawing a default run's
four figures costs, and the drawing itself about as much as the stepping. Neither needs the
run's results until its last step. So :class:`PlotRenderer`, started when a run starts,
spawns one renderer process (this module's ``_serve`` in a new interpreter) that imports
numpy and matplotlib and draws a throw-away figure (fonts, Agg, the PNG encoder) while the run
steps in the parent: the machine's second core does that work, and only one extra process
competes with the stepping. Once ``summary.json`` is on disk, :meth:`PlotRenderer.render`
sends it the results file; it reads the file once, forks (where the platform can) so that a
copy of its warmed-up self draws half of the figures (:data:`FIGURE_SHARES`) on the other
core while it draws the rest, and answers when every PNG is written (each atomically, as
:func:`orchestrator.run.plots.plot_run` does in-process). The command returns only then.

A share that fails, a renderer that exits early or does not answer in
:data:`RENDER_TIMEOUT_S` makes :meth:`~PlotRenderer.render` raise :class:`PlotError` with one
line naming the figures and the reason; the run records it in its summary (``plots_error``)
and the command says so: a PNG is never silently missing. A renderer that is not needed (an
interrupted run) is killed; one whose parent dies (SIGKILL) dies with it (Linux parent-death
signal, armed in the forked copy too) or exits at the end of its input, so a killed run never
leaves a process drawing into a folder that a newer run has taken over. Renderers ignore
SIGINT: Ctrl-C stops the run, and the run stops them.
"""

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from components.common.errors import SonotrackError

__all__ = ["FIGURE_SHARES", "PlotError", "PlotRenderer", "RENDER_TIMEOUT_S"]

# The figures of orchestrator.run.plots.PLOT_FILES in two shares of about equal drawing time
# (measured: trajectories + wheel speeds vs gains + localizer, each about half).
FIGURE_SHARES = (("trajectories.png", "wheel_speeds.png"), ("gains.png", "localizer.png"))
# Generous: a default run's figures take about 0.5 s; a loaded machine is 10x slower.
RENDER_TIMEOUT_S = 120.0
# The source tree the parent imports orchestrator from: the renderers import the same code.
_SOURCE_ROOT = str(Path(__file__).resolve().parents[2])


class PlotError(SonotrackError):
    """The plots of a run could not be drawn; the message says which and why (one line).

    Attributes
    ----------
    written : list of pathlib.Path
        The plots that were written all the same.
    """

    def __init__(self, message, written=()):
        super().__init__(message)
        self.written = list(written)


class PlotRenderer:
    """A renderer process started now, ready to draw a run's plots when it ends.

    Parameters
    ----------
    processes : int, optional
        How many processes draw once the run has ended (default: two where the machine has
        two CPUs or more and can fork, else one); the figures are split between them
        (:data:`FIGURE_SHARES`). Only one exists while the run steps.

    Attributes
    ----------
    timings : dict
        After :meth:`render`: the renderer's wall-clock timestamps (``time.time()``:
        ``started``, ``ready`` after its warm-up, ``request`` received, ``done``).
    """

    def __init__(self, processes=None):
        if processes is None:
            processes = 2 if (os.cpu_count() or 1) >= 2 and hasattr(os, "fork") else 1
        self.shares = FIGURE_SHARES if processes >= 2 else (sum(FIGURE_SHARES, ()),)
        self.timings = {}
        self._log = tempfile.TemporaryFile()   # its stderr: never a pipe that could fill up
        # the same source tree as ours first on its path, whatever the working folder holds
        # tied to us before the slow imports: a parent killed meanwhile ends it at once
        code = (f"import sys; sys.path.insert(0, {_SOURCE_ROOT!r}); "
                f"from orchestrator.processes import die_with_parent; "
                f"die_with_parent({os.getpid()}); "
                f"from orchestrator.run.plot_renderer import _serve; sys.exit(_serve({os.getpid()}))")
        self._process = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE,
                                         stdout=subprocess.PIPE, stderr=self._log)

    def render(self, results_csv, out_dir, max_rows, context=None):
        """Draw the plots of ``results_csv`` into ``out_dir``; return the written paths.

        Waits until every figure is written or has failed. Raises :class:`PlotError` (one
        line; its ``written`` lists what was drawn all the same) if any failed. ``context``
        (a :class:`~orchestrator.run.plots.PlotContext`) gives the titles and the stop
        distance.
        """
        request = {"results_csv": str(Path(results_csv).resolve()),
                   "out_dir": str(Path(out_dir).resolve()), "max_rows": max_rows,
                   "shares": [list(share) for share in self.shares],
                   "context": context.to_dict() if context is not None else None}
        everything = ", ".join(sum(self.shares, ()))
        try:
            stdin, self._process.stdin = self._process.stdin, None   # communicate() won't flush
            try:
                stdin.write((json.dumps(request) + "\n").encode())
                stdin.close()
            except OSError:   # gone already: named by its exit status below
                pass
            try:
                out, _ = self._process.communicate(timeout=RENDER_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                raise PlotError(f"plots {everything}: the renderer did not finish in "
                                f"{RENDER_TIMEOUT_S:.0f} s; stopped it") from None
            reply = _last_json_line(out)
            if self._process.returncode != 0 or reply is None:
                raise PlotError(f"plots {everything}: the renderer exited with status "
                                f"{self._process.returncode}: {self._last_log_line()}")
        finally:
            self.close()
        self.timings = reply.get("times", {})
        order = {name: i for i, name in enumerate(sum(FIGURE_SHARES, ()))}
        written = sorted((Path(p) for p in reply.get("written", [])),
                         key=lambda p: order.get(p.name, len(order)))
        if reply.get("errors"):
            raise PlotError("; ".join(reply["errors"]), written)
        return written

    def _last_log_line(self):
        self._log.seek(0)
        lines = [line for line in self._log.read().decode(errors="replace").splitlines()
                 if line.strip()]
        return " ".join(lines[-1].split()) if lines else "(no message)"

    def close(self):
        """Kill the renderer if it still runs (unused, or past its time) and reap it; safe
        to call twice."""
        if self._process.poll() is None:
            self._process.kill()
            self._process.wait()
        for stream in (self._process.stdout, self._process.stdin):
            if stream is not None:
                try:
                    stream.close()
                except OSError:
                    pass
        if not self._log.closed:
            self._log.close()


def _last_json_line(out):
    lines = out.decode(errors="replace").strip().splitlines()
    try:
        reply = json.loads(lines[-1]) if lines else None
    except ValueError:
        return None
    return reply if isinstance(reply, dict) else None


def _die_with_parent(parent_pid):
    """Be killed when the parent dies (Linux); elsewhere EOF on stdin ends the wait."""
    from orchestrator.processes import die_with_parent

    die_with_parent(parent_pid)


def _warm_up():
    """Import what drawing needs and draw one small figure (fonts, Agg, PNG encoding)."""
    import io

    from orchestrator.run.plots import _Figures

    figures = _Figures()
    fig, ax = figures.subplots(figsize=(2, 2))
    ax.plot([0.0, 1.0], [0.0, 1.0], label="x")
    ax.set_xlabel("x [m]")
    ax.legend(loc="upper left", fontsize=8)
    fig.suptitle("warm-up")
    fig.savefig(io.BytesIO(), dpi=110, format="png", pil_kwargs={"compress_level": 1})


def _draw(data, out_dir, figures, context):
    """(written paths, error text or None) of one share of the figures."""
    from orchestrator.run.plots import plot_run

    try:
        return [str(p) for p in plot_run(data, out_dir, figures=figures, context=context)], None
    except Exception as error:   # any reason, in one line, to the parent
        text = " ".join(str(error).split()) or "(no message)"
        return [], f"plots {', '.join(figures)}: {type(error).__name__}: {text}"


def _draw_shares(data, out_dir, shares, context=None):
    """Draw the first share here and each other one in a forked copy; collect the results."""
    forks = []
    for share in shares[1:]:
        read_end, write_end = os.pipe()
        pid = os.fork()
        if pid == 0:   # the copy: draw, report through the pipe, leave without clean-up
            status = 1
            try:
                os.close(read_end)
                _die_with_parent(os.getppid())
                written, error = _draw(data, out_dir, share, context)
                os.write(write_end, json.dumps([written, error]).encode())
                status = 0
            finally:
                os._exit(status)
        os.close(write_end)
        forks.append((pid, read_end, share))
    written, error = _draw(data, out_dir, shares[0], context)
    errors = [error] if error else []
    for pid, read_end, share in forks:
        chunks = []
        while chunk := os.read(read_end, 1 << 16):
            chunks.append(chunk)
        os.close(read_end)
        _, status = os.waitpid(pid, 0)
        try:
            their_written, their_error = json.loads(b"".join(chunks))
        except ValueError:
            their_written, their_error = [], (f"plots {', '.join(share)}: the drawing process "
                                              f"ended with wait status {status}")
        written += their_written
        errors += [their_error] if their_error else []
    return written, errors


def _serve(parent_pid):
    import signal

    times = {"started": time.time()}
    _die_with_parent(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # Ctrl-C stops the run; the run stops us
    _warm_up()
    from orchestrator.run.results import read_results

    times["ready"] = time.time()
    line = sys.stdin.readline()
    if not line.strip():
        return 0   # not needed (the run was interrupted, or its parent died)
    times["request"] = time.time()
    try:
        request = json.loads(line)
        data = read_results(request["results_csv"], max_rows=request["max_rows"])
    except Exception as error:
        text = " ".join(str(error).split()) or "(no message)"
        figures = ", ".join(sum(map(tuple, request.get("shares", [])), ()))
        print(json.dumps({"written": [], "errors": [f"plots {figures}: reading the results: "
                                                    f"{type(error).__name__}: {text}"]}))
        return 0
    written, errors = _draw_shares(data, request["out_dir"], request["shares"],
                                   request.get("context"))
    times["done"] = time.time()
    print(json.dumps({"written": written, "errors": errors, "times": times}), flush=True)
    return 0
