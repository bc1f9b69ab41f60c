"""``ssw report``: a stage's tables (CSV) as one HTML page for Snakemake's study report.

The study report itself is ``snakemake --report results/report.html`` (figures and tables
flagged ``report(...)`` in the rules); CSV files appear there only as downloads, so the
workflow renders them with this command and flags the page (rule ``report_tables``).
"""

from __future__ import annotations

import argparse
from typing import Any

from ssw.cli import add_json_flag


def run_report(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw report``: CSV tables rendered as one HTML page, or several pages with ``--page``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw report --help``).

    Returns
    -------
    dict of str to Any
        What :func:`ssw.report.write_tables` returns, or ``pages``: that of each page by
        its output.

    Raises
    ------
    ssw.errors.ConfigError
        When tables and ``--output`` are missing (and no ``--page``), mixed with
        ``--page``, or a ``--page`` lacks its output, title or CSV.
    """
    from ssw.errors import ConfigError
    from ssw.report import write_tables

    if args.page:  # several pages in one process (the workflow's rule report_tables)
        if args.tables or args.output:
            raise ConfigError("--page", args.page, "pages without TABLES/--output")
        out = {}
        for page in args.page:
            if len(page) < 3:
                raise ConfigError("--page", page, "OUTPUT TITLE CSV [CSV ...]")
            out[page[0]] = write_tables(page[2:], page[0], title=page[1],
                                        captions_file=args.captions)
        return {"pages": out}
    if not args.tables or not args.output:
        raise ConfigError("tables", args.tables, "CSV files and --output (or --page)")
    return write_tables(args.tables, args.output, title=args.title,
                        captions_file=args.captions)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw report`` subcommand to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser("report", help="CSV tables as one HTML page (for the Snakemake report)",
                       description="Renders CSV tables (6 significant digits, long tables "
                       "cut) with their notes into one HTML page.")
    p.add_argument("tables", nargs="*", help="CSV files")
    p.add_argument("--output", help="HTML file")
    p.add_argument("--page", action="append", nargs="+", metavar="ITEM",
                   help="one page of several: OUTPUT TITLE CSV [CSV ...]; repeat it")
    p.add_argument("--title", default="ssw study tables", help="page title")
    p.add_argument("--captions", help="YAML: file-name glob -> note under the table")
    add_json_flag(p)
    p.set_defaults(func=run_report)
