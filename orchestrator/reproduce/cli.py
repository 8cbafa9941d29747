"""The ``sonotrack reproduce`` sub-command: arguments in, :func:`reproduce` called."""

__all__ = ["register_cli"]


def register_cli(subparsers):
    """Add the ``reproduce`` sub-command to an ``argparse`` sub-parser set.

    ``sonotrack reproduce [--out DIR] [--runs N] [--seed S] [--tables T,...]
    [--conditions free_field,room] [--room SCENARIO] [--workers N] [--scheduler ADDRESS]
    [--fmu-dir DIR] [--quiet]`` runs the study and prints the verdict
    counts and the report's (relative) path.
    """
    from .experiments import TABLES
    from .study import RUNS_PER_CELL

    import argparse

    parser = subparsers.add_parser(
        "reproduce", help="the paper's experiments as a Monte Carlo study beside its numbers",
        description="Run the paper's experiments (Tables 1-3, 6-9, its figures) as a Monte\n"
                    "Carlo study and judge each claim of the paper; write reproduction.html/\n"
                    ".md/.json and figures/. Resumes from finished runs (docs/reproduction.md).",
        epilog="examples:\n  sonotrack reproduce\n  sonotrack reproduce --runs 4 --tables "
               "table6,table7 --out runs/reproduce_quick",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="runs/reproduce",
                        help="report folder (default: runs/reproduce)")
    parser.add_argument("--runs", type=int, default=RUNS_PER_CELL,
                        help=f"Monte Carlo runs per cell (default {RUNS_PER_CELL})")
    parser.add_argument("--seed", type=int, default=0, help="study seed of the draws (default 0)")
    parser.add_argument("--tables", help=f"comma-separated subset of {','.join(TABLES)}")
    parser.add_argument("--conditions", default="free_field,room",
                        help="acoustic conditions, comma-separated (default free_field,room: "
                             "Tables 1-3 and Sec. 6.2 also in the room, side by side)")
    parser.add_argument("--room", help="scenario whose localizer.* parameters are the room "
                                       "(default scenarios/room.toml)")
    parser.add_argument("--workers", type=int, help="local Dask worker processes (default: CPUs)")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. tcp://HOST:8786 (default: the local engine, Dask's process scheduler on forked workers)")
    parser.add_argument("--fmu-dir", help="folder of the FMUs (default: beside the .ssd)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=_cmd_reproduce)
    return parser


def _cmd_reproduce(args):
    import sys

    from orchestrator.builder.fmus import REPO_ROOT
    from orchestrator.builder.system_fmu import stale_fmus_warning

    from .study import reproduce

    warning = stale_fmus_warning("reproduce", args.fmu_dir or REPO_ROOT / "fmus")
    if warning:
        print(warning, file=sys.stderr)
    tables = ([t.strip() for t in args.tables.split(",") if t.strip()]
              if args.tables else None)
    report = reproduce(args.out, fmu_dir=args.fmu_dir, workers=args.workers,
                       progress=not args.quiet, tables=tables, runs=args.runs,
                       study_seed=args.seed, scheduler=args.scheduler,
                       conditions=[c.strip() for c in args.conditions.split(",") if c.strip()],
                       room=args.room)
    counts = ", ".join(f"{v} {k}" for k, v in sorted(report.verdict_counts().items()))
    print(f"reproduce: {report.settings['runs_total']} runs "
          f"({report.settings['runs_computed']} computed) in "
          f"{report.settings['wall_time_s']:.0f} s; claims: {counts or 'none'}")
    if report.side_by_side is not None:
        print(f"room: {len(report.side_by_side.differing())} of "
              f"{len(report.side_by_side.pairs)} fix-dependent claims change verdict")
    for path in (report.markdown_path, report.html_path, report.json_path):
        if path is not None:
            print(f"report: {path}")
    return 0
