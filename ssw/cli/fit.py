"""``ssw fit``, ``ssw fit-table``, ``ssw fit-deviation``, ``ssw fit-plot``: modified-Hertz fits.

* ``ssw fit CURVE.h5 [--law L] [--range-mode M] [--delta-min D] [--delta-max D]
  [--weighting W] [--config C] [--json]``: one curve, one law; prints the parameters
  (``K`` or ``C, n`` or ``k1, k2``), ``rms_rel_residual``, ``max_rel_residual``, the range
  and every input.
* ``ssw fit-table CURVES... --output T.h5 [--csv T.csv] [--config C] [--json]``: fit every
  curve with the config's laws on its default range; write the K(E, nu) tables.
* ``ssw fit-deviation CURVES... --set-kind materials|thickness [--output F.csv]``:
  deviation from Hertz at ``fit.delta_ref`` next to the thesis's statements.
* ``ssw fit-plot {deviation,curves,k} INPUTS... --output F.png``: the Figs 5-7 analogues.
* ``ssw fit-set SET CURVES... --outdir results/fit [--config C]``: everything the study
  reports of one set, in one process (the workflow's one job per set): its table, and for a
  one-soil set the deviation from Hertz and its figures, for a grid set the K(E) figure and
  the fits' TOF cost; for the set of ``fit.set`` also ``k_table.*`` (the chain's fit wall).
"""

from __future__ import annotations

import argparse
import copy
from dataclasses import asdict
from typing import Any

from ssw.cli import add_json_flag
from ssw.config import load_config
from ssw.fit.laws import LAWS, WEIGHTINGS
from ssw.fit.range import RANGE_MODES


def _config_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--config",
                   help="study config YAML (default: ./config/config.yaml, else ssw's defaults)")


def _add_fit(sub: argparse._SubParsersAction) -> None:
    """Add ``ssw fit``: one law fitted to one contact curve."""
    p = sub.add_parser(
        "fit",
        help="fit a modified-Hertz law to one contact curve",
        description="Fit one law to a contact curve (HDF5 from `ssw contact`). K is defined "
        "against F_H = 4/3 E/(1-nu^2) sqrt(R) delta^1.5 (rigid indenter, soil E and nu).",
    )
    p.add_argument("curve", help="contact curve file (HDF5, ssw_kind contact_curve)")
    p.add_argument("--law", choices=list(LAWS), help="law (default: fit.law of the config)")
    p.add_argument("--range-mode", choices=RANGE_MODES, help="fit range mode (fit.range.mode)")
    p.add_argument("--delta-min", type=float, help="lower end of the fit range, m")
    p.add_argument("--delta-max", type=float, help="upper end, m (implies --range-mode fixed)")
    p.add_argument("--weighting", choices=WEIGHTINGS, help="least-squares weighting")
    _config_arg(p)
    add_json_flag(p)
    p.set_defaults(func=run_fit, human=_human_fit)


def _add_table(sub: argparse._SubParsersAction) -> None:
    """Add ``ssw fit-table``: every curve fitted, the K(E, nu) tables."""
    t = sub.add_parser(
        "fit-table",
        help="fit contact curves and aggregate K(E, nu) tables (HDF5 + CSV)",
        description="Fit every curve with the config's laws (fit.law + fit.compare_laws) on "
        "its default range and write per-plate tables over the soil grid.",
    )
    t.add_argument("curves", nargs="+", help="contact curve files")
    t.add_argument("--output", required=True, help="table HDF5 file (ssw_kind k_table)")
    t.add_argument("--csv", help="table CSV file, one row per scene")
    _config_arg(t)
    add_json_flag(t)
    t.set_defaults(func=run_table)


def _add_deviation(sub: argparse._SubParsersAction) -> None:
    """Add ``ssw fit-deviation``: deviation from Hertz next to the thesis's values."""
    d = sub.add_parser(
        "fit-deviation",
        help="deviation from Hertz at the reference indentation, next to the thesis's values",
    )
    d.add_argument("curves", nargs="+", help="contact curve files")
    d.add_argument("--set-kind", choices=["materials", "thickness"], required=True,
                   help="what the curves' set varies: the thesis's values to compare with "
                   "(Set 1: plate materials, Fig 5; Set 2: plate thickness, Fig 6)")
    d.add_argument("--output", help="CSV file of the rows")
    _config_arg(d)
    add_json_flag(d)
    d.set_defaults(func=run_deviation)


def _add_tof_impact(sub: argparse._SubParsersAction) -> None:
    """Add ``ssw fit-tof-impact``: the TOF error a fit's error costs."""
    i = sub.add_parser(
        "fit-tof-impact",
        help="TOF with the FEM curve itself vs the K and power fits (what fit error costs)",
        description="For each curve, TOF with the table law (the curve), fit K, fit (C, n) "
        "and bare Hertz, their errors against the table, and the implied modulus errors.",
    )
    i.add_argument("curves", nargs="+", help="contact curve files")
    i.add_argument("--output", help="CSV file of the rows")
    _config_arg(i)
    add_json_flag(i)
    i.set_defaults(func=run_tof_impact)


def _add_calibrate_soil(sub: argparse._SubParsersAction) -> None:
    """Add ``ssw fit-calibrate-soil``: the soil E at which a plate's deviation reaches a target."""
    c = sub.add_parser(
        "fit-calibrate-soil",
        help="soil E at which a plate's deviation from Hertz equals a target (FEM solves)",
        description="Find, by Brent's method on log E with one FEM solve per step, the soil "
        "modulus at which the plate's deviation F/F_H - 1 at fit.delta_ref equals --target.",
    )
    c.add_argument("--target", type=float, required=True, help="deviation F/F_H - 1")
    c.add_argument("--plate-material", required=True, help="material key of the plate")
    c.add_argument("--plate-thickness", type=float, required=True, help="plate thickness, m")
    c.add_argument("--soil-nu", type=float, default=0.3, help="soil Poisson's ratio")
    c.add_argument("--material-set", help="realistic | as_printed (default: the config's)")
    c.add_argument("--E-min", type=float, default=1.0e6, help="search from, Pa")
    c.add_argument("--E-max", type=float, default=1.0e10, help="search to, Pa")
    _config_arg(c)
    add_json_flag(c)
    c.set_defaults(func=run_calibrate)


def _add_statements(sub: argparse._SubParsersAction) -> None:
    """Add ``ssw fit-thesis-statements``: the thesis's Set 1/2 deviations, ours and theirs."""
    st = sub.add_parser(
        "fit-thesis-statements",
        help="the thesis's Set 1/2 deviations from Hertz, ours (both material sets) and theirs",
        description="Solve the config's set1_materials and set2_thickness scenes with the "
        "realistic and as_printed materials and print the deviation from Hertz at "
        "fit.delta_ref next to the thesis's statements.",
    )
    st.add_argument("--output", help="CSV file of the rows")
    _config_arg(st)
    add_json_flag(st)
    st.set_defaults(func=run_statements)


def _add_range(sub: argparse._SubParsersAction) -> None:
    """Add ``ssw fit-range``: the indentation range a scene's default fit needs."""
    g = sub.add_parser(
        "fit-range",
        help="the indentation range a scene's default fit needs (m)",
        description="Upper end of the default fit range of a soil under fit.range: in mode "
        "chain, the chain's peak wall indentation (Hertz wall) times fit.range.factor. The "
        "contact stage may compute each curve only that far.",
    )
    g.add_argument("--soil-E", type=float, required=True, help="soil Young's modulus, Pa")
    g.add_argument("--soil-nu", type=float, required=True, help="soil Poisson's ratio")
    _config_arg(g)
    add_json_flag(g)
    g.set_defaults(func=run_range)


def _add_set(sub: argparse._SubParsersAction) -> None:
    """Add ``ssw fit-set``: every fit output of one set (the workflow's fit job)."""
    fs = sub.add_parser(
        "fit-set", help="every fit output of one set of the config (the workflow's fit job)",
        description="Table, deviation, figures and TOF cost of one set's curves, in one "
        "process; file names as listed in workflow/rules/fit.smk.")
    fs.add_argument("set", help="set name of the config")
    fs.add_argument("curves", nargs="+",
                    help="the set's contact curve files, or folders holding them (the "
                    "workflow's plate families: the set's scenes are taken from them)")
    fs.add_argument("--outdir", required=True, help="the fit results folder (results/fit)")
    fs.add_argument("--contact-figure", metavar="PNG",
                    help="also draw the set's curves with Hertz (thesis Figs 5, 6: the contact "
                    "stage's figure, `ssw contact-plot`) here: the curves are read already")
    fs.add_argument("--label-by", choices=["material", "thickness"], default=None,
                    help="--contact-figure: label the curves by plate material or thickness")
    fs.add_argument("--title", default=None,
                    help="--contact-figure: its title (default: what the set varies)")
    _config_arg(fs)
    add_json_flag(fs)
    fs.set_defaults(func=run_set)


def _add_plot(sub: argparse._SubParsersAction) -> None:
    """Add ``ssw fit-plot``: the fits' figures."""
    f = sub.add_parser("fit-plot", help="figures of the fits (thesis Figs 5-7 analogues)")
    f.add_argument("kind", choices=["deviation", "curves", "k"],
                   help="the figure: deviation from Hertz (Figs 5, 6), fitted curves, or "
                   "K against E (Fig 7)")
    f.add_argument("inputs", nargs="+", help="curve files (deviation, curves) or a table (k)")
    f.add_argument("--output", required=True, help="PNG file")
    f.add_argument("--title", default="", help="figure title")
    _config_arg(f)
    add_json_flag(f)
    f.set_defaults(func=run_plot)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw fit``, ``ssw fit-table``, ``ssw fit-deviation``, ``ssw fit-tof-impact``, ``ssw
    fit-calibrate-soil``, ``ssw fit-thesis-statements``, ``ssw fit-range``, ``ssw fit-set``,
    ``ssw fit-plot`` subcommands to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    _add_fit(sub)
    _add_table(sub)
    _add_deviation(sub)
    _add_tof_impact(sub)
    _add_calibrate_soil(sub)
    _add_statements(sub)
    _add_range(sub)
    _add_set(sub)
    _add_plot(sub)


def _cfg_with(args: argparse.Namespace) -> dict[str, Any]:
    cfg = copy.deepcopy(load_config(args.config))
    rc = cfg["fit"]["range"]
    if getattr(args, "range_mode", None):
        rc["mode"] = args.range_mode
    if getattr(args, "delta_min", None) is not None:
        rc["delta_min"] = args.delta_min
    if getattr(args, "delta_max", None) is not None:
        rc["delta_max"], rc["mode"] = args.delta_max, "fixed"
    if getattr(args, "weighting", None):
        cfg["fit"]["weighting"] = args.weighting
    return cfg


def _human_fit(r: dict[str, Any]) -> str:
    law = LAWS[r["law"]]
    params = ", ".join(
        f"{p} = {r[p]:.6g}" + ("" if u == "1" else f" {u}")
        for p, u in zip(law.params, law.units, strict=True)
    )
    rng = r["range"]
    return (
        f"{law.formula}: {params}\n"
        f"relative residual: rms {r['rms_rel_residual']:.3g}, max {r['max_rel_residual']:.3g} "
        f"({r['n_points']} points)\n"
        f"range: {r['delta_lo'] * 1e3:.4g} .. {r['delta_hi'] * 1e3:.4g} mm (mode {rng['mode']}, "
        f"source {rng['source']}, needed {rng['needed'] * 1e3:.4g} mm"
        f"{', clipped to the curve' if rng['clipped'] else ''})\n"
        f"E* = {r['E_star']:.6g} Pa (soil, rigid indenter), R = {r['radius']:.6g} m"
    )


def run_fit(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw fit``: a modified-Hertz law fitted to one contact curve.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw fit --help``).

    Returns
    -------
    dict of str to Any
        The fit (the ``as_dict`` of :func:`ssw.fit.pipeline.fit_with_config`'s result, SI
        units), its indentation ``range`` and the law's ``formula``.
    """
    from ssw.curve import read_curve
    from ssw.fit.pipeline import fit_with_config

    cfg = _cfg_with(args)
    res, rng = fit_with_config(read_curve(args.curve, extras=False), cfg, args.law)
    out = res.as_dict()
    out["range"] = asdict(rng)
    out["formula"] = LAWS[res.law].formula
    return out


def run_table(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw fit-table``: contact curves fitted and aggregated into K(E, nu) tables (HDF5 and CSV).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw fit-table --help``).

    Returns
    -------
    dict of str to Any
        The output files and, per table, its grid sizes, interpolation error and largest
        relative residual of each law.
    """
    from ssw.fit.pipeline import config_laws, table_from_files
    from ssw.fit.table import write_tables

    cfg = load_config(args.config)
    tables, records = table_from_files(args.curves, cfg)
    inputs = {
        "curves": list(args.curves),
        "fit": cfg["fit"],
        "laws": config_laws(cfg),
        "ranges": [r["range"] for r in records],
    }
    write_tables(tables, args.output, args.csv, inputs)
    return {
        "output": args.output,
        "csv": args.csv,
        "tables": [
            {
                "name": tb.name,
                "n_E": int(tb.soil_E.size),
                "n_nu": int(tb.soil_nu.size),
                "interp_error": tb.interp_error(),
                "max_rel_residual": {
                    law: float(r["max_rel_residual"].max()) for law, r in tb.residuals.items()
                },
            }
            for tb in tables
        ],
    }


def run_deviation(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw fit-deviation``: each curve's deviation from Hertz at the reference indentation, next
    to the thesis's values.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw fit-deviation --help``).

    Returns
    -------
    dict of str to Any
        ``rows``: one per curve (written as CSV with ``--output``).
    """
    from ssw.curve import read_curve
    from ssw.fit.deviation import deviation_rows

    cfg = load_config(args.config)
    rows = deviation_rows(
        [read_curve(p, extras=False) for p in args.curves], args.set_kind, cfg["fit"]["delta_ref"]
    )
    for r in rows:
        r["material_set"] = cfg["material_set"]
    if args.output:
        from ssw.h5io import write_rows_csv

        write_rows_csv(rows, args.output)
    return {"rows": rows}


def run_plot(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw fit-plot``: a figure of the fits (thesis Figs 5-7 analogues).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw fit-plot --help``).

    Returns
    -------
    dict of str to Any
        The figure's path (``output``).
    """
    from ssw.fit import figures

    cfg = load_config(args.config)
    figures.PLOTS[args.kind](args.inputs, args.output, cfg, args.title)
    return {"output": args.output}


def run_tof_impact(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw fit-tof-impact``: the TOF with the FEM curve itself against the K and power fits (what
    the fit error costs).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw fit-tof-impact --help``).

    Returns
    -------
    dict of str to Any
        ``rows`` (one per curve; CSV with ``--output``) and ``max_abs``, the largest
        absolute TOF and E errors of each fit (relative, -).
    """
    from ssw.curve import read_curve
    from ssw.tof.impact import tof_impact

    rows = tof_impact([read_curve(p, extras=False) for p in args.curves], load_config(args.config))
    if args.output:
        from ssw.h5io import write_rows_csv

        write_rows_csv(rows, args.output)
    worst = {
        k: max(abs(r[k]) for r in rows)
        for k in ("tof_err_fit_k", "tof_err_fit_power", "E_err_fit_k", "E_err_fit_power")
    }
    return {"max_abs": worst, "rows": rows}


def run_calibrate(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw fit-calibrate-soil``: the soil E (Pa) at which a plate's deviation from Hertz equals a
    target (FEM solves).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw fit-calibrate-soil --help``).

    Returns
    -------
    dict of str to Any
        ``soil_E`` (Pa), the ``material_set`` and every solve's soil E (Pa) and deviation.
    """
    from ssw.config import Scene, library
    from ssw.contact import solve_scene
    from ssw.fit.deviation import calibrate_soil_E, deviation

    cfg = copy.deepcopy(load_config(args.config))
    if args.material_set:
        cfg["material_set"] = args.material_set
    mats = library(cfg)
    calls: list[dict[str, float]] = []

    def dev(E: float) -> float:
        sc = Scene(args.plate_material, args.plate_thickness, E, args.soil_nu)
        c = solve_scene(sc, cfg["contact"], cfg["indenter"]["radius"], mats)
        d = deviation(c, cfg["fit"]["delta_ref"])["deviation"]
        calls.append({"soil_E": E, "deviation": d})
        return d

    E = calibrate_soil_E(args.target, dev, args.E_min, args.E_max)
    return {"soil_E": E, "material_set": cfg["material_set"], "solves": calls}


def run_statements(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw fit-thesis-statements``: the thesis's Set 1/2 deviations from Hertz, ours (both
    material sets) and theirs.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw fit-thesis-statements --help``).

    Returns
    -------
    dict of str to Any
        ``rows``: one per statement (CSV with ``--output``).
    """
    from ssw.config import library
    from ssw.contact import solve_scene
    from ssw.fit.deviation import thesis_statements

    def solve(scene: Any, cfg: dict[str, Any]) -> Any:
        return solve_scene(scene, cfg["contact"], cfg["indenter"]["radius"], library(cfg))

    rows = thesis_statements(load_config(args.config), solve)
    if args.output:
        from ssw.h5io import write_rows_csv

        write_rows_csv(rows, args.output)
    return {"rows": rows}


def run_range(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw fit-range``: the indentation range a scene's default fit needs.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw fit-range --help``).

    Returns
    -------
    dict of str to Any
        ``delta_lo`` and ``delta_hi`` (m) and the range ``mode``.
    """
    from ssw.fit.range import scene_delta_max

    cfg = load_config(args.config)
    rc = cfg["fit"]["range"]
    return {
        "delta_lo": rc["delta_min"],
        "delta_hi": scene_delta_max(args.soil_E, args.soil_nu, cfg),
        "mode": rc["mode"],
    }


def run_set(args: argparse.Namespace) -> dict[str, Any]:
    """Every fit output of one set (the module docstring), one process: the config loaded
    once, every curve read once.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line of ``ssw fit-set`` (its flags: ``ssw fit-set --help``).

    Returns
    -------
    dict of str to Any
        The ``set`` and the ``outputs`` written (paths).

    Raises
    ------
    ssw.errors.ConfigError
        When the set is not in the config, or a curve stops short of the fit range the
        chain needs.
    """
    from pathlib import Path

    from ssw.config import expand_grid
    from ssw.curve import read_curve
    from ssw.fit import figures
    from ssw.fit.deviation import deviation_rows
    from ssw.fit.pipeline import config_laws, table_from_files
    from ssw.fit.table import write_tables
    from ssw.h5io import write_json, write_rows_csv
    from ssw.tof.impact import tof_impact

    cfg = load_config(args.config)
    if args.set not in cfg["sets"]:
        from ssw.errors import ConfigError

        raise ConfigError("set", args.set, f"one of the sets: {', '.join(cfg['sets'])}")
    spec = cfg["sets"][args.set]
    one_soil = (expand_grid(spec["soil_E"], f"sets.{args.set}.soil_E").size
                * expand_grid(spec["soil_nu"], f"sets.{args.set}.soil_nu").size) == 1
    kind = "materials" if len(spec["plate_material"]) > 1 else "thickness"
    out = Path(args.outdir)
    tdir = out / "sets" / args.set
    tdir.mkdir(parents=True, exist_ok=True)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    args.curves = set_curve_files(cfg, args.set, args.curves)
    curves = [read_curve(p, extras=False) for p in args.curves]
    written: list[str] = []

    def dump(path: Path, res: dict[str, Any]) -> None:
        write_json(path, {**res, "ssw_version": _version()},
                   {"set": args.set, "curves": list(args.curves), "fit": cfg["fit"]})
        written.append(str(path))

    tables, records = table_from_files(args.curves, cfg, curves=curves)
    _require_fit_range(args.curves, records, cfg)
    write_tables(tables, tdir / "k_table.h5", tdir / "k_table.csv", {
        "curves": list(args.curves), "fit": cfg["fit"], "laws": config_laws(cfg),
        "ranges": [r["range"] for r in records]})
    dump(tdir / "k_table.json", {"output": str(tdir / "k_table.h5"), "tables": [
        {"name": tb.name, "n_E": int(tb.soil_E.size), "n_nu": int(tb.soil_nu.size),
         "interp_error": tb.interp_error(),
         "max_rel_residual": {law: float(r["max_rel_residual"].max())
                              for law, r in tb.residuals.items()}} for tb in tables]})
    written += [str(tdir / "k_table.h5"), str(tdir / "k_table.csv")]
    plots = []
    if one_soil:
        rows = deviation_rows(curves, kind, cfg["fit"]["delta_ref"])
        for r in rows:
            r["material_set"] = cfg["material_set"]
        write_rows_csv(rows, out / f"deviation_{args.set}.csv")
        dump(out / f"deviation_{args.set}.json", {"rows": rows})
        written.append(str(out / f"deviation_{args.set}.csv"))
        plots += [("curves", args.curves, f"{args.set}_curves.png"),
                  ("deviation", args.curves, f"{args.set}_deviation.png")]
    else:
        plots.append(("k", [str(tdir / "k_table.h5")], f"{args.set}_k_vs_E.png"))
        rows = tof_impact(curves, cfg, records)
        write_rows_csv(rows, out / f"tof_impact_{args.set}.csv")
        worst = {k: max(abs(r[k]) for r in rows) for k in
                 ("tof_err_fit_k", "tof_err_fit_power", "E_err_fit_k", "E_err_fit_power")}
        dump(out / f"tof_impact_{args.set}.json", {"max_abs": worst, "rows": rows})
        written.append(str(out / f"tof_impact_{args.set}.csv"))
    for kind_, inputs, name in plots:
        figures.PLOTS[kind_](inputs, str(out / "figures" / name), cfg, args.set)
        written.append(str(out / "figures" / name))
    if getattr(args, "contact_figure", None):
        written.append(_contact_figure(args, curves, kind))
    return {"set": args.set, "outputs": written}


def _require_fit_range(paths: list[str], records: list[dict[str, Any]],
                       cfg: dict[str, Any]) -> None:
    """ConfigError naming the curves (of ``paths``, their fit ``records``) that stop short
    of the indentation (m) the chain needs, and the flag that lengthens them."""
    short = [(p, r["range"]) for p, r in zip(paths, records, strict=True)
             if r["range"]["clipped"]]
    if short:
        from ssw.errors import ConfigError

        p, rng = short[0]
        raise ConfigError(
            "contact.reach_energy", cfg["contact"].get("reach_energy"),
            f"curves that reach the fit range: {len(short)} of {len(records)} stop short of "
            f"what the chain needs (e.g. {p}: ends at {rng['hi']:.4g} m, the chain presses "
            f"{rng['needed']:.4g} m); raise contact.reach_energy (delta_mode energy) or "
            "contact.delta_max (fixed)")


def _contact_figure(args: argparse.Namespace, curves: list[Any], kind: str) -> str:
    """Draw ``ssw fit-set --contact-figure``: the set's curves with Hertz, labelled by what
    the set varies (``kind``) unless ``--label-by`` says; returns the PNG's path."""
    from ssw.contact.figures import plot_curves

    label_by = args.label_by or ("material" if kind == "materials" else "thickness")
    title = args.title if args.title is not None else (
        f"{args.set}: plate {'materials' if kind == 'materials' else 'thickness'}")
    plot_curves(curves, args.contact_figure, label_by=label_by, title=title)
    return str(args.contact_figure)


def set_curve_files(cfg: dict[str, Any], set_name: str, paths: list[str]) -> list[str]:
    """The curve files of a set: files as given; a folder contributes the set's scenes it
    holds (``<folder>/<scene_id>.h5``). ConfigError if a scene of the set has no file.

    Parameters
    ----------
    cfg : dict of str to Any
        The study config.
    set_name : str
        The set's name in the config.
    paths : list of str
        Curve files and folders of curve files.

    Returns
    -------
    list of str
        The curve files: those given, then the folders' files of the set's other scenes.

    Raises
    ------
    ssw.errors.ConfigError
        When a folder is given and a scene of the set has no file in any of them.
    """
    from pathlib import Path

    from ssw.config import scenes
    from ssw.errors import ConfigError

    files = [p for p in paths if not Path(p).is_dir()]
    dirs = [Path(p) for p in paths if Path(p).is_dir()]
    if not dirs:
        return files
    found = {Path(f).stem for f in files}
    for sc in scenes(cfg, set_name):
        if sc.scene_id in found:
            continue
        hits = [d / f"{sc.scene_id}.h5" for d in dirs if (d / f"{sc.scene_id}.h5").is_file()]
        if not hits:
            raise ConfigError("curves", [str(d) for d in dirs],
                              f"folders holding the curve of every scene of {set_name} "
                              f"(no {sc.scene_id}.h5)")
        files.append(str(hits[0]))
        found.add(sc.scene_id)
    return files


def _version() -> str:
    from ssw import __version__

    return __version__

