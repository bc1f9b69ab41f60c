"""``ssw survey-table``: gather the test points of a survey (their ``ssw measure --json``
results) into a table (CSV + HDF5) with verdicts against their targets, and its figures.

    ssw survey-table RESULT.json... [--config C] --csv T.csv --h5 T.h5
                     [--plot E.png] [--map M.png] [--geojson P.geojson] [--json]

The results follow the order of the config's ``survey.points`` (one per point, named by
its id). SI units; coordinates in the frame of ``survey.frame`` (ssw.survey.Frame).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from ssw.cli import add_json_flag
from ssw.errors import ConfigError


def run_table(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw survey-table``: a survey's points: their table, verdicts against the targets and
    figures.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw survey-table --help``).

    Returns
    -------
    dict of str to Any
        The ``points`` (one row each), the files written and the count of each of the
        ``verdicts`` (pass, fail, inconclusive, no target).

    Raises
    ------
    ssw.errors.ConfigError
        When the survey has no points, a point has no result file, or a map is asked
        of points without coordinates.
    """
    from ssw.config import load_config
    from ssw.survey import (
        plot_map,
        plot_survey,
        read_results,
        survey_frame,
        survey_table,
        write_geojson,
        write_survey,
    )

    cfg = load_config(args.config)
    sv = cfg.get("survey", {})
    points = sv.get("points", [])
    if not points:
        raise ConfigError("survey.points", [], "one or more test points")
    by_id = {Path(p).stem: p for p in args.results}
    missing = [pt["id"] for pt in points if pt["id"] not in by_id]
    if missing:
        raise ConfigError("results", sorted(by_id), f"one file per point, named by its id: "
                          f"missing {missing}")
    results = read_results([by_id[pt["id"]] for pt in points])
    frame = survey_frame(sv)
    rows = survey_table(points, results, frame)
    located = any(r.x is not None or r.latitude is not None for r in rows)
    for flag, path in (("--map", args.map), ("--geojson", args.geojson)):
        if path and not located:
            raise ConfigError(flag, path, "a survey whose points have coordinates (x/y or "
                              "latitude/longitude); nothing was written")
    write_survey(args.csv, args.h5, rows, {"config": args.config, "points": points})
    out: dict[str, Any] = {"points": [r.__dict__ for r in rows], "csv": args.csv,
                           "h5": args.h5}
    if args.plot:
        plot_survey(args.plot, rows, sv.get("title", ""))
        out["plot"] = args.plot
    if args.map:
        plot_map(args.map, rows, sv.get("title", ""), frame)
        out["map"] = args.map
    if args.geojson:
        write_geojson(args.geojson, rows, frame, sv.get("title", ""))
        out["geojson"] = args.geojson
    counts = {v: sum(r.verdict == v for r in rows) for v in
              ("pass", "fail", "inconclusive", "no target")}
    out["verdicts"] = counts
    return out


def _human(r: dict[str, Any]) -> str:
    lines = [f"{'point':10} {'E MPa':>8} {'95 % interval':>17} {'target':>8} {'verdict':>13}"]
    for p in r["points"]:
        tgt = "-" if p["target_E"] is None else f"{p['target_E'] / 1e6:.0f}"
        lines.append(f"{p['id']:10} {p['E'] / 1e6:8.1f} {p['E_low'] / 1e6:8.1f}-"
                     f"{p['E_high'] / 1e6:<8.1f} {tgt:>8} {p['verdict']:>13}")
    lines += [f"{p['id']:10} {p['verdict']}: {p['reason']}" for p in r["points"]
              if p.get("reason")]
    lines.append(", ".join(f"{k}: {v}" for k, v in r["verdicts"].items()))
    return "\n".join(lines)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw survey-table`` subcommand to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser(
        "survey-table", help="a survey's points: table, verdicts against targets, figures",
        description="Gather the `ssw measure --json` results of the config's survey.points "
        "(files named by point id) into CSV and HDF5 with pass/fail/inconclusive verdicts "
        "from each 95 % interval and target, a figure of E per point and a plan view.")
    p.add_argument("results", nargs="+", help="ssw measure --json results, {id}.json")
    p.add_argument("--config", help="study config YAML with the survey section")
    p.add_argument("--csv", required=True, help="survey table CSV")
    p.add_argument("--h5", required=True, help="survey table HDF5")
    p.add_argument("--plot", help="PNG: E per point with its interval and target")
    p.add_argument("--map", help="PNG: plan view of the points with coordinates")
    p.add_argument("--geojson", help="GeoJSON (RFC 7946) of the points with coordinates: "
                   "WGS84 longitude/latitude, else the local x/y with its frame named")
    add_json_flag(p)
    p.set_defaults(func=run_table, human=_human)
