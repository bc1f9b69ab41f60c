"""``python -m ssw.warmstart [--log FILE] -- COMMAND...``: run a Snakemake run of the study
with ssw's warm process started beside it (:func:`ssw.warmstart.run.run_with`)."""

from __future__ import annotations

import sys


def _cli(argv: list[str]) -> int:
    """Parse ``argv`` and run the command (:func:`ssw.warmstart.run.run_with`)."""
    import argparse
    from pathlib import Path

    from ssw.warmstart.run import run_with

    parser = argparse.ArgumentParser(
        prog="python -m ssw.warmstart",
        description="Run a Snakemake run of the study with ssw's warm process started beside "
        "it (the workflow starts one by itself otherwise, when its run begins).")
    parser.add_argument("--log", default="results/logs/warm-start.log",
                        help="file of the warm process's messages")
    parser.add_argument("command", nargs=argparse.REMAINDER,
                        help="the command, after --")
    args = parser.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("a command is required after --")
    return run_with(command, Path(args.log))


if __name__ == "__main__":
    raise SystemExit(_cli(sys.argv[1:]))
