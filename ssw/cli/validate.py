"""``ssw validate``: thesis Tables 2 and 3 and Figs 9 and 10 for the config's samples."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from ssw.cli import add_json_flag
from ssw.cli._device import add_device_options, chain_context

CURVE_POINTS = 40  # E points of each model curve in Fig 10


def run_validate(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw validate``: simulated against measured TOFs and the inverted E of the thesis's samples
    (Tables 2, 3).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw validate --help``).

    Returns
    -------
    dict of str to Any
        The device's inputs, each sample's row (``samples``) and the inverse's ``E_range``
        (Pa); with ``--outdir``, the ``outputs`` written (CSV, HDF5, the thesis's tables
        and Figs 9, 10).

    Raises
    ------
    ssw.errors.ConfigError
        On ``--law table`` (the inverse needs a law at any E).
    """
    from ssw.signal.tof import ChainPath, TofOptions
    from ssw.tof import api
    from ssw.validation.table import inverse_range, validate_samples

    ctx = chain_context(args)
    cfg, params, wall, opts = ctx.cfg, ctx.params, ctx.wall, ctx.wall_options
    if wall == "table":
        from ssw.errors import ConfigError

        raise ConfigError("--law", "table", "fem | hertz | fit (the inverse needs a law at "
                          "any E)")
    E_range = inverse_range(wall, opts, params)
    val = cfg.get("validation", {})
    # the reflected peak only after the device's shortest physical round trip
    tof_opts = TofOptions(lowpass=val.get("lowpass"), min_hits=val.get("min_hits", 3),
                          chain=ChainPath.from_params(params))
    from ssw.cli.chain import context_strengths

    rows = validate_samples(cfg, params, wall, opts, root=args.root, tof_options=tof_opts,
                            calibration=ctx.calibration,
                            full_scale=ctx.device.full_scale_force,
                            strengths=context_strengths(ctx),
                            stresses=args.stress_checks)
    out: dict[str, Any] = {**ctx.inputs(), "samples": [r.to_dict() for r in rows],
                           "E_range": list(E_range)}
    if args.outdir:
        from ssw.validation.figures import plot_fig9, plot_fig10
        from ssw.validation.output import write_table, write_thesis_tables

        d = Path(args.outdir)
        inputs = {"config": args.config, **ctx.inputs(), "chain_params": params.__dict__,
                  "E_range": E_range}
        write_table(d / "validation.csv", d / "validation.h5", rows, inputs)
        write_thesis_tables(d / "table2_tof.csv", d / "table3_modulus.csv", rows)
        E = np.geomspace(*E_range, CURVE_POINTS)
        nus = sorted({r.nu for r in rows})
        T = np.asarray(api.tof(E[None, :], np.array(nus)[:, None], params, wall, **opts))
        sweep_curves = {}
        if args.sweep:
            from ssw.tof.sweep import merge_sweeps, read_sweep, require_same_model

            parts = [read_sweep(p) for p in args.sweep]
            for path, (_, inp) in zip(args.sweep, parts, strict=True):
                require_same_model(inp, path, params, wall, opts)
            sw = merge_sweeps([p[0] for p in parts])
            sweep_curves = {float(nu): sw.curve(float(nu)) for nu in np.unique(sw.soil_nu)}
        plot_fig10(d / "fig10_tof_validation.png", rows,
                   {nu: (E, T[i]) for i, nu in enumerate(nus)}, sweep_curves)
        plot_fig9(d / "fig9_tof_scatter.png", rows)
        out["outputs"] = [str(d / n) for n in (
            "validation.csv", "validation.h5", "table2_tof.csv", "table3_modulus.csv",
            "fig10_tof_validation.png", "fig9_tof_scatter.png")]
    return out


def _human(r: dict[str, Any]) -> str:
    cal = r.get("calibration_file") or "none (the device as described)"
    head = (f"{'sample':8} {'E_man MPa':>9} {'nu':>5} {'TOF_sim ms':>10} {'TOF_meas ms':>11} "
            f"{'dTOF %':>7} {'E MPa':>7} {'95 % interval':>15} {'dE %':>6} {'E_loo MPa':>9}  "
            "source")
    lines = [f"wall law: {r['wall']}; device {r['device_name']}; calibration: {cal}", head]
    for s in r["samples"]:
        loo = "-" if s["E_loo"] is None else f"{s['E_loo'] / 1e6:.1f}"
        lines.append(
            f"{s['sample']:8} {s['E_manufacturer'] / 1e6:9.1f} {s['nu']:5.2f} "
            f"{s['tof_sim'] * 1e3:10.4f} {s['tof_measured'] * 1e3:11.4f} "
            f"{s['tof_diff_pct']:7.2f} {s['E_measured'] / 1e6:7.1f} "
            f"{s['E_low'] / 1e6:7.1f}-{s['E_high'] / 1e6:<7.1f} "
            f"{s['E_diff_pct']:6.2f} {loo:>9}  {s['tof_source']}")
        budget = ", ".join(f"{k} {v:.2f} %" for k, v in s["E_contributions_pct"].items())
        lines.append(f"{'':8} uncertainty of E (1 sigma): {s['E_u_pct']:.2f} % = {budget}")
        if s.get("validity"):
            lines.append(f"{'':8} checks failed at its E: "
                         + ("; ".join(s["checks_failed"]) or "none"))
    lines += [f"wrote {p}" for p in r.get("outputs", [])]
    return "\n".join(lines)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw validate`` subcommand to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser(
        "validate", help="simulated vs measured TOF and inverted E (thesis Tables 2, 3)",
        description="For each config validation sample: TOF simulated at the manufacturer's "
        "E, measured TOF (recording, else the thesis's mean), % difference, E inverted "
        "from the measured TOF with its COV and % difference. SI units.")
    p.add_argument("--outdir", help="write validation.csv/.h5 and Figs 9, 10 here")
    p.add_argument("--root", default=".", help="folder relative recording paths start from")
    p.add_argument("--sweep", nargs="+",
                   help="the chain's TOF(E, nu) sweep HDF5 (or its parts), drawn in Fig 10")
    add_device_options(p)
    from ssw.cli.chain import add_stress_checks_option

    # bound: the study's validation stays cheap (the contact FEM's stresses factor one
    # soil body per sample's Poisson's ratio, 0.45 s each); fem on request
    add_stress_checks_option(p, "bound")
    add_json_flag(p)
    p.set_defaults(func=run_validate, human=_human)
