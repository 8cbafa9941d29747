"""The ``sonotrack`` command line: thin sub-commands over the library functions.

Each sub-command imports its module lazily and calls one library function with the same
argument names. Errors of ours (:class:`SonotrackError`) print one line per problem, no
traceback, and exit non-zero (2, or the error's ``exit_status``); so do command-line mistakes
(one line, not argparse's usage block). Anything else is a bug: one line naming the exception,
exit status 3, and the traceback only with ``SONOTRACK_TRACEBACK=1``.
"""

import argparse
import os
import sys
from pathlib import Path

from components.common.errors import SimulationError, SonotrackError

__all__ = ["console_main", "main"]


def _cmd_build(args):
    from orchestrator.builder.fmus import FMU_PACKAGES, build_all

    names = args.names or None
    for name in names or []:
        if name not in FMU_PACKAGES:
            raise SonotrackError(f"unknown FMU {name!r}; valid choices: "
                                 f"{', '.join(FMU_PACKAGES)}")
    paths = build_all(args.out, names)
    for path in paths:
        print(f"built {path}")
    if names is None:
        _write_ssp(Path(args.out))
    return 0


def _write_ssp(out):
    from orchestrator.builder.fmus import REPO_ROOT, write_ssp_archive

    ssd = out / "SystemStructure.ssd"
    if not ssd.is_file():
        ssd = REPO_ROOT / "fmus" / "SystemStructure.ssd"
    print(f"built {write_ssp_archive(ssd, out / 'tracking.ssp', fmu_dir=out)}")


def _cmd_validate(args):
    from orchestrator.builder.validation import validate_fmus

    paths = args.fmus or sorted(Path(args.dir).glob("*.fmu"))
    if not paths:
        raise SonotrackError(f"sonotrack validate: no FMU given and none in {args.dir}; "
                             "run `sonotrack build` first")
    total = 0
    for report in validate_fmus(paths, simulate=not args.no_simulate):
        status = "ok" if report.ok else f"{len(report.problems)} problem(s)"
        print(f"{report.path}: {status}")
        for problem in report.problems:
            print(f"  - {problem}")
        total += len(report.problems)
    print(f"{total} problem(s) in {len(paths)} FMU(s)")
    return min(total, 125)


def _cmd_run(args):
    from orchestrator.run.runner import run_scenario
    from orchestrator.scenario import load_scenario, parse_seconds

    record_interval = parse_seconds(args.record_interval, "--record-interval")
    scenario = args.scenario or DEFAULT_SCENARIO
    if not Path(scenario).exists():
        raise SonotrackError(f"scenario file {scenario} does not exist; shipped scenarios: "
                             f"{', '.join(sorted(p.name for p in Path('scenarios').glob('*.toml')))}")
    # a directory, bad TOML, a bad field: one line each, before anything is loaded
    loaded = load_scenario(scenario, allow_outside=args.allow_outside)
    out = Path(args.out) if args.out else Path("runs") / Path(scenario).stem
    try:
        result = run_scenario(loaded, out, progress=not args.quiet, algorithm=args.master,
                              plots=not args.no_plots,
                              fmu_dir=args.fmu_dir, record_interval=record_interval,
                              fsync=args.fsync, allow_outside=args.allow_outside)
    except SimulationError as exc:   # a model refused: name the scenario file too
        raise SimulationError(f"{scenario}: {exc}") from exc
    except SonotrackError as exc:
        if "not found at" in str(exc):
            raise SonotrackError(f"{exc} (build the FMUs first: `sonotrack build`, or "
                                 "point --fmu-dir at them)") from exc
        raise
    summary = result.summary
    for key in ("final_distance_to_source_m", "min_distance_to_source_m", "final_position_error_m",
                "path_rmse_m", "sim_time_s", "wall_time_s", "realtime_factor", "steps"):
        if key in summary:
            value = summary[key]
            print(f"  {key:28s} {value:.4g}" if isinstance(value, float) else
                  f"  {key:28s} {value}")
    if loaded.parameters:   # the values this run used, as the scenario gave them
        from components.common.ranges import show

        used = ", ".join(f"{k} = {show(v)}" for k, v in sorted(loaded.parameters.items()))
        print(f"  {'parameters':28s} {used}")
    print(f"results: {result.out_dir.resolve()}")
    if result.plots_error:   # results and summary are complete; the pictures are not
        print(f"sonotrack run: error: {result.plots_error} (results.csv and summary.json are "
              f"complete; the summary records this as plots_error)", file=sys.stderr)
        return 1
    return 0


DEFAULT_SCENARIO = "scenarios/s_curve.toml"


def _cmd_sweep(args):
    from orchestrator.scenario import load_scenario
    from orchestrator.sweep import parse_assignment, parse_seeds, sweep

    scenario_path = args.scenario or DEFAULT_SCENARIO
    if not Path(scenario_path).is_file():
        raise SonotrackError(f"scenario file {scenario_path} does not exist")
    grid = {}
    for text in args.set or []:
        key, values = parse_assignment(text)
        if key in grid:
            raise SonotrackError(f"--set {key} is given twice; list all its values in one "
                                 f"--set, e.g. {key}=a,b")
        grid[key] = values
    seeds = parse_seeds(args.seeds) if args.seeds is not None else None
    out = Path(args.out) if args.out else Path("runs") / f"sweep_{Path(scenario_path).stem}"
    result = sweep(load_scenario(scenario_path, allow_outside=args.allow_outside), grid, out,
                   seeds=seeds, fmu_dir=args.fmu_dir, scheduler=args.scheduler,
                   workers=_workers(args.workers), progress=not args.quiet,
                   allow_outside=args.allow_outside)
    failed = [row for row in result.rows if row.get("status") != "ok"]
    print(f"{len(result.rows)} runs ({result.computed} computed, {result.reused} reused), "
          f"{len(failed)} failed")
    for row in failed[:5]:
        print(f"  failed: {row['run_dir']}: {row.get('error', '')}", file=sys.stderr)
    print(f"table: {result.table_csv.resolve()}")
    return 1 if failed else 0


def _workers(text):
    """``--workers`` text into an int >= 1 (one line naming the option otherwise)."""
    if text is None:
        return None
    try:
        value = int(text)
    except ValueError:
        value = None
    if value is None or value < 1:
        raise SonotrackError(f"--workers {text!r}: expected a whole number of worker processes "
                             f">= 1 (this machine has {os.cpu_count()} CPUs)")
    return value


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (``sonotrack run: error: ...``), exit status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _parser(command=None):
    parser = _Parser(prog="sonotrack", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    build = sub.add_parser("build", help="build the FMUs into fmus/ (and fmus/tracking.ssp)")
    build.add_argument("names", nargs="*", help="FMU names (default: all)")
    build.add_argument("--out", default="fmus", help="output folder (default: fmus)")
    build.set_defaults(func=_cmd_build)

    validate = sub.add_parser("validate", help="check FMUs with fmpy, fmutool and a short run")
    validate.add_argument("fmus", nargs="*", type=Path, help="FMU files (default: fmus/*.fmu)")
    validate.add_argument("--dir", default="fmus", help="folder searched when no FMU is given")
    validate.add_argument("--no-simulate", action="store_true", help="skip the short simulation")
    validate.set_defaults(func=_cmd_validate)

    run = sub.add_parser("run", help="run a scenario through our master on fmpy")
    run.add_argument("scenario", nargs="?", help=f"TOML scenario (default: {DEFAULT_SCENARIO})")
    run.add_argument("--out", help="results folder (default: runs/<scenario name>)")
    run.add_argument("--master", choices=("gauss-seidel", "jacobi"),
                     help="override the scenario's master algorithm")
    run.add_argument("--fmu-dir", help="folder of the FMUs (default: beside the .ssd)")
    run.add_argument("--record-interval", default="0.02",
                     help="simulated seconds between recorded rows, in (0, 3600] "
                          "(default 0.02)")
    run.add_argument("--fsync", action="store_true",
                     help="fsync results.csv once a simulated second (default: at the end)")
    run.add_argument("--no-plots", action="store_true",
                     help="write no PNG plots (results.csv and summary.json only)")
    run.add_argument("--allow-outside", action="store_true",
                     help="let the scenario and .ssd read files outside their own folders")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.set_defaults(func=_cmd_run)

    sweep = sub.add_parser("sweep", help="run a scenario over a parameter grid and seeds on Dask")
    sweep.add_argument("scenario", nargs="?", help=f"TOML scenario (default: {DEFAULT_SCENARIO})")
    sweep.add_argument("--set", action="append", metavar="INSTANCE.PARAM=V1,V2",
                       help="parameter values to sweep (repeatable; all combinations run)")
    sweep.add_argument("--seeds", help="seeds, e.g. 1,2,3 or 1..10 (default: the scenario's)")
    sweep.add_argument("--out", help="sweep folder (default: runs/sweep_<scenario name>)")
    sweep.add_argument("--fmu-dir", help="folder of the FMUs (default: beside the .ssd)")
    sweep.add_argument("--scheduler", metavar="tcp://HOST:8786",
                       help="address of a Dask scheduler (default: worker processes on this "
                            "machine)")
    sweep.add_argument("--workers",
                       help="worker processes on this machine, >= 1 (default: CPUs)")
    sweep.add_argument("--allow-outside", action="store_true",
                       help="let the scenario and system files name files outside their "
                            "folders")
    sweep.add_argument("--quiet", action="store_true", help="no progress bar")
    sweep.set_defaults(func=_cmd_sweep)

    for name, (register, summary) in _EXTRA_COMMANDS.items():
        if command in (None, name):
            register(sub)
        else:  # listed in --help, but its module is not imported for another command
            sub.add_parser(name, help=summary)
    return parser


def _register_verify(sub):
    from orchestrator.verify import register_cli

    register_cli(sub)


def _register_reproduce(sub):
    from orchestrator.reproduce import register_cli

    register_cli(sub)


# Sub-commands whose parsers live in their own, heavier modules (numpy, python-control):
# imported only when that command runs (or for --help), so `sonotrack run` never pays for them.
_EXTRA_COMMANDS = {
    "verify": (_register_verify, "checks of the wheel-speed loop with verdicts (Routh, margins, "
                                 "robustness, FMUs vs models); exit status = failed checks"),
    "reproduce": (_register_reproduce, "the paper's experiments in simulation beside the "
                                       "paper's numbers"),
}


def _command_named(argv):
    """The sub-command in ``argv`` (its first word that is not an option), or None."""
    words = [a for a in argv if not a.startswith("-")]
    return words[0] if words else None


def main(argv=None):
    """Entry point of the ``sonotrack`` console script; returns the exit status."""
    argv = sys.argv[1:] if argv is None else list(argv)
    args = _parser(_command_named(argv)).parse_args(argv)
    try:
        return args.func(args)
    except SonotrackError as exc:
        print(f"sonotrack {args.command}: error: {exc}", file=sys.stderr)
        return getattr(exc, "exit_status", 2)
    except KeyboardInterrupt:
        print(f"sonotrack {args.command}: interrupted (Ctrl-C)",
              file=sys.stderr)
        return 130
    except Exception as exc:  # a bug of ours: one line, the traceback on request
        if os.environ.get("SONOTRACK_TRACEBACK"):
            raise
        text = " ".join(str(exc).split()) or "(no message)"
        print(f"sonotrack {args.command}: internal error: {type(exc).__name__}: {text} (set "
              "SONOTRACK_TRACEBACK=1 to see where; please report it)", file=sys.stderr)
        return 3


def console_main():
    """The ``sonotrack`` console script: :func:`main`, then, after ``run``, a fast exit.

    Everything ``run`` writes is closed, fsync'ed or renamed into place before :func:`main`
    returns; what is left is the interpreter tearing down every module it imported (about
    7 % of a default run's wall time), which no file needs, so the process ends there.
    Called from Python, :func:`main` returns as usual.
    """
    argv = sys.argv[1:]
    status = main(argv)
    if _command_named(argv) == "run":
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    return status


if __name__ == "__main__":
    sys.exit(console_main())
