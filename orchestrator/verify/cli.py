"""The ``sonotrack verify`` sub-command: calls :func:`.report.verify`, exits with the failures."""

from pathlib import Path

__all__ = ["register_cli"]


def _cmd_verify(args):
    from .report import verify

    report = verify(args.out, grid_size=args.grid, fmu=not args.no_fmu, strict=args.strict,
                    requirements=args.requirements)
    for line in report.summary_lines():
        print(f"  {line}")
    print(f"report: {Path(report.paths['html']).resolve()}")
    return report.exit_status(strict=args.strict)


def register_cli(subparsers):
    """Add the ``verify`` sub-command to the ``sonotrack`` parser's sub-parsers.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        From ``parser.add_subparsers``; the command calls :func:`.report.verify` and exits
        with the number of failed checks (warnings too with ``--strict``).
    """
    from .report import DEFAULT_OUT_DIR

    import argparse

    command = subparsers.add_parser(
        "verify", help="checks of the wheel-speed loop with verdicts (Routh, margins, "
                       "robustness, FMUs vs models); exit status = failed checks",
        description="Check the wheel-speed loop against stated requirements (stability over\n"
                    "the fuzzy gain surface, margins, robustness to the plant, the built FMUs\n"
                    "against their models); write verification.html/.md/.json. Exit status:\n"
                    "the number of failed checks (docs/verification.md).",
        epilog="examples:\n  sonotrack verify\n  sonotrack verify --no-fmu --grid 5 "
               "--out runs/verify_quick",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    command.add_argument("--out", default=DEFAULT_OUT_DIR,
                         help=f"report folder (default: {DEFAULT_OUT_DIR})")
    command.add_argument("--grid", type=int, default=11,
                         help="points per axis of the kp x kd grid (default 11)")
    command.add_argument("--no-fmu", action="store_true",
                         help="skip building the FMUs and every check run through them")
    command.add_argument("--strict", action="store_true",
                         help="count warnings (findings about the paper) as failures")
    command.add_argument("--requirements", default=None, metavar="TOML",
                         help="requirements file (default: the shipped "
                              "orchestrator/data/verification_requirements.toml)")
    command.set_defaults(func=_cmd_verify)
    return command
