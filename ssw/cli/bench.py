"""``ssw bench KIND``: benchmarks. Each ``ssw/bench/KIND.py`` registers one kind."""

from __future__ import annotations

import argparse
import importlib
import pkgutil


def register(sub: argparse._SubParsersAction) -> None:
    import ssw.bench as pkg

    p = sub.add_parser(
        "bench",
        help="run a benchmark (work-precision tables and plots under results/bench)",
        description="Benchmarks: each writes a table and a plot under results/bench/.",
    )
    kinds = p.add_subparsers(dest="bench_kind", metavar="KIND", required=True)
    for m in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda m: m.name):
        if not m.name.startswith("_"):
            importlib.import_module(f"ssw.bench.{m.name}").register(kinds)
