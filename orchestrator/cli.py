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
import textwrap
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
    if args.system:   # a wrong scenario name is one line before anything is built
        from orchestrator.scenario import find_scenario

        scenario = find_scenario(args.scenario or DEFAULT_SCENARIO)
    paths = build_all(args.out, names, portable=args.portable)
    for path in paths:
        print(f"built {path}")
    if names is None:
        _write_ssp(Path(args.out))
    if args.system:
        from orchestrator.run.as_fmu import build_scenario_fmu

        built = build_scenario_fmu(scenario, args.out, fmu_dir=args.out, portable=args.portable)
        print(f"built {built}")
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
        raise SonotrackError(f"no FMU given and none in {args.dir}; "
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


def _scenario(args):
    """The scenario named on the command line, with its --stop-time and --set applied.

    A --set word without '=' is reported first: its value was then read as the scenario.
    """
    from orchestrator.scenario import find_scenario, load_scenario, parse_override, parse_seconds

    for text in args.set or []:
        if "=" not in text:
            parse_override(text, stray=args.scenario)   # raises, with the spelling that works
    stop_time = (parse_seconds(args.stop_time, "--stop-time", maximum=1e9)
                 if args.stop_time is not None else None)
    path = find_scenario(args.scenario or DEFAULT_SCENARIO)
    # a directory, bad TOML, a bad field: one line each, before anything is loaded
    loaded = load_scenario(path, allow_outside=args.allow_outside)
    return path, loaded, stop_time


def _cmd_run(args):
    from orchestrator.run.runner import run_scenario
    from orchestrator.run.summary_text import summary_lines
    from orchestrator.scenario import apply_overrides, parse_seconds

    record_interval = parse_seconds(args.record_interval, "--record-interval")
    scenario, loaded, stop_time = _scenario(args)
    loaded = apply_overrides(loaded, stop_time, args.set or ())
    out = Path(args.out) if args.out else Path("runs") / loaded.name
    _warn_stale_fmus("run", args.fmu_dir or Path(loaded.system).parent)
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
    for line in summary_lines(result.summary):
        print(line)
    if loaded.parameters:   # the values this run used, as the scenario gave them
        from components.common.ranges import show

        used = ", ".join(f"{k} = {show(v)}" for k, v in sorted(loaded.parameters.items()))
        print(f"  {'parameters':28s} {used}")
    print(f"results: {result.out_dir} (the figures: docs/metrics.md)")
    if result.plots_error:   # results and summary are complete; the pictures are not
        print(f"sonotrack run: error: {result.plots_error} (results.csv and summary.json are "
              f"complete; the summary records this as plots_error)", file=sys.stderr)
        return 1
    return 0


DEFAULT_SCENARIO = "scenarios/s_curve.toml"


def _warn_stale_fmus(command, folder):
    """One line on stderr when the FMUs about to run carry other code than components/."""
    from orchestrator.builder.system_fmu import stale_fmus_warning

    warning = stale_fmus_warning(command, folder)
    if warning:
        print(warning, file=sys.stderr)


def _cmd_sweep(args):
    from orchestrator.scenario import apply_overrides
    from orchestrator.sweep import parse_assignment, parse_seeds, sweep

    scenario_path, loaded, stop_time = _scenario(args)
    loaded = apply_overrides(loaded, stop_time)
    grid = {}
    for text in args.set or []:
        key, values = parse_assignment(text)
        if key in grid:
            raise SonotrackError(f"--set {key} is given twice; list all its values in one "
                                 f"--set, e.g. {key}=a,b")
        grid[key] = values
    seeds = parse_seeds(args.seeds) if args.seeds is not None else None
    out = Path(args.out) if args.out else Path("runs") / f"sweep_{loaded.name}"
    _warn_stale_fmus("sweep", args.fmu_dir or Path(loaded.system).parent)
    result = sweep(loaded, grid, out,
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


def _cmd_info(args):
    from orchestrator.builder.fmus import REPO_ROOT
    from orchestrator.fmu.info import find_fmu, fmu_info, format_info

    path = find_fmu(args.fmu, folders=(Path("fmus"), REPO_ROOT / "fmus"))
    print(format_info(*fmu_info(path)))
    return 0


def _cmd_compare(args):
    from orchestrator.run.compare import compare_runs

    result = compare_runs(args.run_dirs, args.out)
    print(result.text())
    print(f"comparison: {result.markdown}")
    for path in result.figures:
        print(f"figure: {path}")
    return 0


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
    """argparse with one-line errors (``sonotrack run: error: ...``), exit status 2; the
    line points to the help of the command it is about."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _command(sub, name, summary, description, examples):
    """A sub-command whose ``--help`` says what it does and shows examples."""
    epilog = "examples:\n" + "\n".join(f"  {line}" for line in examples)
    return sub.add_parser(name, help=summary, description=textwrap.fill(description, 79),
                          epilog=epilog,
                          formatter_class=argparse.RawDescriptionHelpFormatter)


def _parser(command=None):
    parser = _Parser(prog="sonotrack", description=__doc__.splitlines()[0],
                     epilog="Each command has its own help: sonotrack COMMAND --help. "
                            "Guide: README.md; every command: docs/commands.md.")
    sub = parser.add_subparsers(dest="command", required=True)

    build = _command(sub, "build", "build the FMUs into fmus/ (and fmus/tracking.ssp)",
                     "Build the FMI 2.0 co-simulation FMUs (all five by default) and the "
                     "SSP archive tracking.ssp.",
                     ["sonotrack build", "sonotrack build WheelController --out /tmp/fmus",
                      "sonotrack build --system",
                      "sonotrack build --portable --out build/portable-fmus"])
    build.add_argument("names", nargs="*", help="FMU names (default: all)")
    build.add_argument("--out", default="fmus", help="output folder (default: fmus)")
    build.add_argument("--system", action="store_true",
                       help="also build TrackingSystem.fmu: the whole loop of --scenario in one "
                            "FMU, from the five FMUs in --out (docs/system_fmu.md)")
    build.add_argument("--portable", action="store_true",
                       help="each FMU carries its own Python runtime (libpython, the standard "
                            "library it needs, numpy; under 20 MB) and runs where no Python is "
                            "installed (docs/fmi_binary.md, 'Portable FMUs')")
    build.add_argument("--scenario", default=None,
                       help=f"with --system: TOML file or shipped scenario name whose schedule "
                            f"and parameter values it runs (default: {DEFAULT_SCENARIO})")
    build.set_defaults(func=_cmd_build)

    validate = _command(sub, "validate", "check FMUs with fmpy, fmutool and a short run",
                        "Check FMUs with fmpy's validator, fmu-manipulation-toolbox's checker "
                        "and a short simulation; print every problem. Exit status: the number "
                        "of problems.", ["sonotrack validate", "sonotrack validate "
                                         "fmus/RobotPlant.fmu --no-simulate"])
    validate.add_argument("fmus", nargs="*", type=Path, help="FMU files (default: fmus/*.fmu)")
    validate.add_argument("--dir", default="fmus", help="folder searched when no FMU is given")
    validate.add_argument("--no-simulate", action="store_true", help="skip the short simulation")
    validate.set_defaults(func=_cmd_validate)

    run = _command(sub, "run", "run a scenario through our master on fmpy",
                   "Run one scenario through sonotrack's master on fmpy; write results.csv, "
                   "summary.json and PNG plots into one folder and print the summary "
                   "(every figure is defined in docs/metrics.md).",
                   ["sonotrack run                      # scenarios/s_curve.toml",
                    "sonotrack run static_case1         # a shipped scenario, from any folder",
                    "sonotrack run my.toml --stop-time 10 --set planner.v_cruise=0.2 "
                    "--out runs/slow"])
    run.add_argument("scenario", nargs="?",
                     help=f"TOML file or shipped scenario name (default: {DEFAULT_SCENARIO})")
    run.add_argument("--out", help="results folder (default: runs/<scenario name>)")
    run.add_argument("--stop-time", metavar="S",
                     help="simulated seconds, replacing the scenario's stop_time")
    run.add_argument("--set", action="append", metavar="INSTANCE.PARAM=VALUE",
                     help="a parameter value, checked like the scenario's [parameters] "
                          "(repeatable)")
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

    sweep = _command(sub, "sweep", "run a scenario over a parameter grid and seeds on Dask",
                     "Run every combination of the --set values and seeds as separate runs "
                     "on Dask (this machine's cores, or a scheduler); resumable. Writes "
                     "runs/<hash>/ per run and the table sweep.csv / sweep.json.",
                     ["sonotrack sweep --set planner.v_cruise=0.2,0.3 --seeds 1..5",
                      "sonotrack sweep straight --stop-time 10 --set planner.mode="
                      "curvature,pure_pursuit --out runs/modes"])
    sweep.add_argument("scenario", nargs="?",
                       help=f"TOML file or shipped scenario name (default: {DEFAULT_SCENARIO})")
    sweep.add_argument("--stop-time", metavar="S",
                       help="simulated seconds of every run, replacing the scenario's")
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

    info = _command(sub, "info", "an FMU's variables: causality, type, unit, start, range",
                    "Show what an FMU declares: model facts, then each variable's causality, "
                    "type, unit, start value, valid range and description.",
                    ["sonotrack info fmus/WheelController.fmu",
                     "sonotrack info RobotPlant          # fmus/RobotPlant.fmu"])
    info.add_argument("fmu", help="an .fmu file, or a model name found in fmus/")
    info.set_defaults(func=_cmd_info)

    compare = _command(sub, "compare", "finished runs side by side: figures and a table",
                       "Overlay the trajectories and wheel speeds of finished runs and "
                       "tabulate their summary figures; writes two PNGs and comparison.md.",
                       ["sonotrack compare runs/s_curve runs/slow",
                        "sonotrack compare runs/a runs/b runs/c --out runs/abc"])
    compare.add_argument("run_dirs", nargs="+", metavar="RUN_DIR",
                         help="run folders written by sonotrack run (two or more)")
    compare.add_argument("--out", default="runs/compare",
                         help="folder for the figures and comparison.md (default: "
                              "runs/compare)")
    compare.set_defaults(func=_cmd_compare)

    for name, (register, summary) in _EXTRA_COMMANDS.items():
        if command in (None, name):
            register(sub)
        else:  # listed in --help, but its module is not imported for another command
            sub.add_parser(name, help=summary)
    parser.commands = sub.choices   # name -> its parser, for errors about its options
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
    parser = _parser(_command_named(argv))
    args, unknown = parser.parse_known_args(argv)
    if unknown:   # named by the command they were given to, with its help
        parser.commands[args.command].error(f"unrecognized arguments: {' '.join(unknown)}")
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
