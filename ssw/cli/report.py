"""``ssw report``: one self-contained HTML file with every figure and table of a study."""

from __future__ import annotations

import argparse
from typing import Any

from ssw.cli import add_json_flag


def run_report(args: argparse.Namespace) -> dict[str, Any]:
    from ssw.config import DEFAULT_CONFIG, load_config
    from ssw.report import write_report

    cfg = load_config(args.config)
    return write_report(args.results, args.output, title=f"ssw study: {cfg.get('study', '')}",
                        captions_file=args.captions, config_file=args.config or DEFAULT_CONFIG)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("report", help="self-contained HTML report of a study's results",
                       description="Embeds every PNG and CSV under --results in one HTML file.")
    p.add_argument("--config", help="study config YAML (default config/config.yaml)")
    p.add_argument("--results", default="results", help="results folder")
    p.add_argument("--output", default="results/report/report.html", help="HTML file")
    p.add_argument("--captions", default="workflow/report/captions.yaml",
                   help="YAML: file-name glob -> caption")
    add_json_flag(p)
    p.set_defaults(func=run_report)
