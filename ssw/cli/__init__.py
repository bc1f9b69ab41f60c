"""The ``ssw`` command line.

Subcommands live in the modules of this package; each module defines
``register(subparsers) -> None``, which adds its parsers and sets ``func`` to a callable
``run(args) -> dict`` returning the command's result in SI units. This module finds the
modules, parses, runs, and prints either a short human summary or, with ``--json``, the
result merged with every input that produced it.

Library errors (:class:`ssw.errors.SswError`) become a one-line message on stderr and exit
status 2; no traceback.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import signal
import sys
import threading
from collections.abc import Sequence
from typing import Any

from ssw import __version__
from ssw.errors import SswError
from ssw.h5io import to_json


def add_json_flag(parser: argparse.ArgumentParser) -> None:
    """Add the ``--json`` flag every subcommand has."""
    parser.add_argument(
        "--json",
        action="store_true",
        help="print the result as JSON on stdout, with every input that produced it",
    )


def command_modules() -> list[str]:
    """Names of the modules of ``ssw.cli`` that define subcommands, sorted."""
    import ssw.cli as pkg

    names = (m.name for m in pkgutil.iter_modules(pkg.__path__))
    return sorted(f"ssw.cli.{n}" for n in names if not n.startswith("_"))


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ssw",
        description="Solitary strain wave device studies: contact FEM, modified Hertz fits, "
        "chain dynamics, acquisition and validation. SI units throughout.",
    )
    parser.add_argument("--version", action="version", version=f"ssw {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in command_modules():
        importlib.import_module(name).register(sub)
    return parser


def _inputs(args: argparse.Namespace) -> dict[str, Any]:
    return {k: v for k, v in vars(args).items() if k not in {"func", "json", "human"}}


def _human(result: dict[str, Any]) -> str:
    lines = []
    for k, v in result.items():
        if isinstance(v, list | tuple) and len(v) > 6:
            lines.append(f"{k}: [{len(v)} values: {v[0]!r} ... {v[-1]!r}]")
        elif isinstance(v, dict):
            lines.append(f"{k}: {{{', '.join(map(str, v))}}}")
        else:
            lines.append(f"{k}: {v}")
    return "\n".join(lines)


def _terminate(signum: int, frame: object) -> None:
    """SIGTERM (Snakemake cancelling a job, Slurm's scancel) unwinds like Ctrl-C, so every
    temporary ``.part`` file is removed by its ``finally`` (ssw.h5io.atomic_path)."""
    raise KeyboardInterrupt


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _terminate)
        # PETSc would otherwise install its own SIGTERM handler when first initialized
        # (after this one) and abort without unwinding, leaving a `.part` file behind.
        opts = os.environ.get("PETSC_OPTIONS", "")
        if "-no_signal_handler" not in opts.split():
            os.environ["PETSC_OPTIONS"] = f"{opts} -no_signal_handler".strip()
    if getattr(args, "json", False):  # machine output: no progress bars (ssw.progress)
        from ssw.progress import set_enabled

        set_enabled(False)
    try:
        result = args.func(args)
    except SswError as exc:
        print(f"ssw {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"ssw {args.command}: interrupted", file=sys.stderr)
        return 130
    finally:
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if result is None:
        return 0
    if getattr(args, "json", False):
        out = {**_inputs(args), **result, "ssw_version": __version__}
        print(to_json(out))
    else:
        human = getattr(args, "human", None)
        print(human(result) if human else _human(result))
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
