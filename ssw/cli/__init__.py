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
import re
import signal
import sys
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ssw import __version__
from ssw.errors import SswError
from ssw.h5io import to_json


def add_json_flag(parser: argparse.ArgumentParser) -> None:
    """Add the ``--json`` flag every subcommand has.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The subcommand's parser.
    """
    parser.add_argument(
        "--json",
        action="store_true",
        help="print the result as JSON on stdout, with every input that produced it",
    )


def command_modules() -> list[str]:
    """Names of the modules of ``ssw.cli`` that define subcommands, sorted.

    Returns
    -------
    list of str
        Dotted module names (those not starting with an underscore).
    """
    import ssw.cli as pkg

    names = (m.name for m in pkgutil.iter_modules(pkg.__path__))
    return sorted(f"ssw.cli.{n}" for n in names if not n.startswith("_"))


#: ``sub.add_parser("name"`` in a command module (the name may follow on the next line).
_ADD_PARSER_RE = re.compile(r"\.add_parser\(\s*[\"']([\w-]+)[\"']")


def command_index() -> dict[str, str]:
    """Command name -> the module that registers it, found by reading the modules' text
    (importing every module would import everything they use: ~0.5 s per command run).

    Returns
    -------
    dict of str to str
        Command name to the dotted name of its module.
    """
    import ssw.cli as pkg

    out: dict[str, str] = {}
    for name in command_modules():
        path = Path(pkg.__path__[0]) / f"{name.rsplit('.', 1)[1]}.py"
        for cmd in _ADD_PARSER_RE.findall(path.read_text()):
            out.setdefault(cmd, name)
    return out


def _command_of(argv: Sequence[str]) -> str | None:
    """The subcommand named in ``argv`` (the first argument that is not an option or an
    option's value), or None."""
    it = iter(argv)
    for a in it:
        if a == "--inputs-sha256":
            next(it, None)
        elif not a.startswith("-"):
            return a
    return None


#: ``ssw --help``'s sections: title -> the commands it lists, in order. A command in no
#: section is listed under :data:`UNGROUPED` (``tests/test_cli.py`` fails on one).
GROUPS: dict[str, tuple[str, ...]] = {
    "the study (the workflow's jobs: contact FEM, fits, TOF sweeps, figures)": (
        "contact", "contact-plot", "fit-set", "fit-table", "fit-plot", "tof-sweep",
        "tof-merge", "validate"),
    "the instrument (record, read and calibrate the device)": (
        "acquire", "tof-recording", "measure", "calibrate", "identify", "survey-table"),
    "design (plates and whole devices)": ("design", "lift-study"),
    "analysis (one soil, one curve, one question)": (
        "tof", "invert", "chain", "dynamic-tof", "dynamic-study", "fit", "fit-range",
        "fit-deviation", "fit-tof-impact", "fit-calibrate-soil", "fit-thesis-statements"),
    "tools": ("check-config", "report", "bench"),
}

#: The section of a command missing from :data:`GROUPS`.
UNGROUPED = "other commands"


class _GroupedParser(argparse.ArgumentParser):
    """The top-level parser, whose help lists the subcommands by :data:`GROUPS` (argparse
    lists a subparsers action as one flat section; its per-command help lines are reused)."""

    def format_help(self) -> str:
        """The usage, the description, one section per group of commands, the options.

        Returns
        -------
        str
            The help text.
        """
        sub = next((a for a in self._actions if isinstance(a, argparse._SubParsersAction)),
                   None)
        if sub is None:
            return super().format_help()
        fmt = self._get_formatter()
        fmt.add_usage(self.usage, self._actions, self._mutually_exclusive_groups)
        fmt.add_text(self.description)
        rows = {a.dest: a for a in sub._choices_actions}
        sections = [(t, [rows.pop(n) for n in names if n in rows])
                    for t, names in GROUPS.items()]
        sections.append((UNGROUPED, list(rows.values())))
        for title, actions in sections:
            if actions:
                fmt.start_section(title)
                fmt.add_arguments(actions)
                fmt.end_section()
        for group in self._action_groups:
            actions = [a for a in group._group_actions if a is not sub]
            if actions:
                fmt.start_section(group.title)
                fmt.add_text(group.description)
                fmt.add_arguments(actions)
                fmt.end_section()
        fmt.add_text(self.epilog)
        return fmt.format_help()


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The ``ssw`` parser: every command, or, when ``argv`` names one, only the module that
    defines it (``ssw --help`` and an unknown command still see them all).

    Parameters
    ----------
    argv : sequence of str or None
        The arguments after ``ssw``; None: every command.

    Returns
    -------
    argparse.ArgumentParser
        The parser.
    """
    parser = _GroupedParser(
        prog="ssw",
        description="Solitary strain wave (SSW) device: the soil's Young's modulus from the "
        "time of flight of a solitary wave in a chain of spheres. Contact FEM, modified "
        "Hertz fits, chain dynamics, acquisition, calibration, design and validation; SI "
        "units throughout.",
        epilog="`ssw COMMAND --help` for a command's options; `--json` on any command "
        "prints its whole result with every input that produced it.",
    )
    parser.add_argument("--version", action="version", version=f"ssw {__version__}")
    parser.add_argument(
        "--inputs-sha256", metavar="DIGEST",
        help="digest of the study inputs this run was scheduled with (set by the workflow's "
        "rules; recorded as inputs_sha256 in every result; default: the digest of the "
        "command's own inputs)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    modules = command_modules()
    if argv is not None:
        cmd = _command_of(argv)
        owner = command_index().get(cmd) if cmd else None
        if owner is not None:
            modules = [owner]
    for name in modules:
        importlib.import_module(name).register(sub)
    return parser


def _inputs(args: argparse.Namespace) -> dict[str, Any]:
    return {k: v for k, v in vars(args).items()
            if k not in {"func", "json", "human", "inputs_sha256"}}


def _human(result: dict[str, Any]) -> str:
    """The short summary of a command without its own printer (:func:`ssw.cli._summary.default`)."""
    from ssw.cli._summary import default

    return default(result)


def _terminate(signum: int, frame: object) -> None:
    """SIGTERM (Snakemake cancelling a job, Slurm's scancel) unwinds like Ctrl-C, so every
    temporary ``.part`` file is removed by its ``finally`` (ssw.h5io.atomic_path)."""
    raise KeyboardInterrupt


#: Environment variable naming a folder: each ``ssw`` process writes its CPU and wall time
#: there when it ends (``_record_usage``; ``ssw bench study`` sets it).
USAGE_ENV = "SSW_USAGE_DIR"


def _process_wall() -> float:
    """Seconds since this process started (Linux ``/proc``), or NaN elsewhere."""
    try:
        ticks = os.sysconf("SC_CLK_TCK")
        start = int(Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()[19])
        uptime = float(Path("/proc/uptime").read_text().split()[0])
        return uptime - start / ticks
    except (OSError, ValueError, IndexError):
        return float("nan")


def _record_usage(argv: Sequence[str], started: float) -> None:
    """Write this process's CPU time (user + system, its own and its waited children's,
    s), wall time since it started and at :func:`main`'s start (s, the interpreter's
    start-up and the CLI's imports) and peak memory to ``$SSW_USAGE_DIR/<pid>.json``,
    with its command line and the file its stderr goes to (a workflow job's log: the job).
    Nothing when the variable is unset; a failure to write is ignored (a measurement,
    never the run's result)."""
    import json
    import resource

    folder = os.environ.get(USAGE_ENV)
    if not folder:
        return
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(
        resource.RUSAGE_CHILDREN)
    try:
        log = os.readlink("/proc/self/fd/2")
    except OSError:
        log = None
    rec = {"argv": list(argv), "log": log, "cwd": os.getcwd(),
           "cpu_s": me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime,
           "user_s": me.ru_utime + kids.ru_utime, "sys_s": me.ru_stime + kids.ru_stime,
           "wall_s": _process_wall(), "startup_s": started,
           "max_rss_mb": me.ru_maxrss / 1024.0}
    try:
        Path(folder).mkdir(parents=True, exist_ok=True)
        Path(folder, f"{os.getpid()}.json").write_text(json.dumps(rec))
    except OSError:
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """The ``ssw`` command: parse ``argv``, run the command, print its result.

    Library errors (:class:`ssw.errors.SswError`) are one line on stderr; with ``$SSW_USAGE_DIR``
    set, the process's CPU and wall time are written there.

    Parameters
    ----------
    argv : sequence of str or None
        The arguments after ``ssw`` (None: ``sys.argv[1:]``).

    Returns
    -------
    int
        The exit status: 0 on success, 2 on a library error, 130 when interrupted.
    """
    started = _process_wall()
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        return _main(argv)
    finally:
        _record_usage(argv, started)


def _main(argv: list[str]) -> int:
    from ssw.provenance import record, set_context

    parser = build_parser(argv)
    args = parser.parse_args(argv)
    set_context([getattr(args.func, "__module__", "ssw")], args.inputs_sha256)
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
        out["provenance"] = record(_inputs(args))
        print(to_json(out))
    else:
        human = getattr(args, "human", None)
        print(human(result) if human else _human(result))
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
