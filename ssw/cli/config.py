"""``ssw check-config``: validate a study config and summarize what it will compute."""

from __future__ import annotations

import argparse
from typing import Any

from ssw.cli import add_json_flag
from ssw.config import expand_grid, load_config, scenes


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw check-config`` subcommand to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser(
        "check-config",
        help="validate a study config (schema + semantic checks) and count its jobs",
        description="Validate a study config against the schema and the materials library; "
        "print the number of contact scenes per set and of chain sweep points.",
    )
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    add_json_flag(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw check-config``: a study config validated (schema and semantic checks) and its jobs
    counted.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw check-config --help``).

    Returns
    -------
    dict of str to Any
        ``valid``, the study, the scenes of each set and the chain sweep's points.
    """
    cfg = load_config(args.config)
    per_set = {name: len(scenes(cfg, name)) for name in cfg["sets"]}
    sweep = cfg["chain"]["sweep"]
    n_E = len(expand_grid(sweep["soil_E"], "chain.sweep.soil_E"))
    n_nu = len(expand_grid(sweep["soil_nu"], "chain.sweep.soil_nu"))
    return {
        "valid": True,
        "study": cfg["study"],
        "scenes_per_set": per_set,
        "chain_sweep_points": n_E * n_nu,
    }
