"""``ssw bench KIND``: benchmarks. Each ``ssw/bench/KIND.py`` registers one kind (or more);
the command line adds the ``--json`` flag every subcommand has (the benchmarks import
nothing of :mod:`ssw.cli`)."""

from __future__ import annotations

import argparse
import importlib
import pkgutil


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw bench`` subcommand to the command line.

    Each kind of :mod:`ssw.bench` adds its own parser under ``ssw bench``; every one gets the
    ``--json`` flag.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    import ssw.bench as pkg
    from ssw.cli import add_json_flag

    p = sub.add_parser(
        "bench",
        help="run a benchmark (work-precision tables and plots under results/bench)",
        description="Benchmarks: each writes a table and a plot under results/bench/.",
    )
    kinds = p.add_subparsers(dest="bench_kind", metavar="KIND", required=True)
    for m in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda m: m.name):
        if not m.name.startswith("_"):
            importlib.import_module(f"ssw.bench.{m.name}").register(kinds)
    for parser in kinds.choices.values():
        add_json_flag(parser)
