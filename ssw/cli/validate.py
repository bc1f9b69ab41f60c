"""``ssw validate``: thesis Tables 2 and 3 and Figs 9 and 10 for the config's samples."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from ssw.cli import add_json_flag
from ssw.cli.daq import add_wall_options, wall_of

CURVE_POINTS = 40  # E points of each model curve in Fig 10


def run_validate(args: argparse.Namespace) -> dict[str, Any]:
    from ssw.chain import api
    from ssw.chain.params import ChainParams
    from ssw.config import load_config
    from ssw.signal.tof import TofOptions
    from ssw.validation.table import inverse_range, validate_samples

    cfg = load_config(args.config)
    over: dict[str, float] = {}
    if args.calibration:
        from ssw.chain.calibration import read_calibrated_velocity

        over["striker_velocity"] = read_calibrated_velocity(args.calibration)
    params = ChainParams.from_config(cfg, **over)
    wall, opts = wall_of(args, cfg)
    E_range = inverse_range(wall, opts, params)
    val = cfg.get("validation", {})
    tof_opts = TofOptions(lowpass=val.get("lowpass"), min_hits=val.get("min_hits", 1))
    rows = validate_samples(cfg, params, wall, opts, root=args.root, tof_options=tof_opts)
    out: dict[str, Any] = {"samples": [r.to_dict() for r in rows], "wall": wall,
                           "E_range": list(E_range)}
    if args.outdir:
        from ssw.validation.figures import plot_fig9, plot_fig10
        from ssw.validation.output import write_table, write_thesis_tables

        d = Path(args.outdir)
        inputs = {"config": args.config, "calibration": args.calibration, "wall": wall,
                  "K": args.K, "k_table": args.k_table, "chain_params": params.__dict__,
                  "E_range": E_range}
        write_table(d / "validation.csv", d / "validation.h5", rows, inputs)
        write_thesis_tables(d / "table2_tof.csv", d / "table3_modulus.csv", rows)
        E = np.geomspace(*E_range, CURVE_POINTS)
        nus = sorted({r.nu for r in rows})
        T = np.asarray(api.tof(E[None, :], np.array(nus)[:, None], params, wall, **opts))
        sweep_curves = {}
        if args.sweep:
            from ssw.chain.sweep import read_sweep

            sw = read_sweep(args.sweep)[0]
            sweep_curves = {float(nu): sw.curve(float(nu)) for nu in np.unique(sw.soil_nu)}
        plot_fig10(d / "fig10_tof_validation.png", rows,
                   {nu: (E, T[i]) for i, nu in enumerate(nus)}, sweep_curves)
        plot_fig9(d / "fig9_tof_scatter.png", rows)
        out["outputs"] = [str(d / n) for n in (
            "validation.csv", "validation.h5", "table2_tof.csv", "table3_modulus.csv",
            "fig10_tof_validation.png", "fig9_tof_scatter.png")]
    return out


def _human(r: dict[str, Any]) -> str:
    head = (f"{'sample':8} {'E_man MPa':>9} {'nu':>5} {'TOF_sim ms':>10} {'TOF_meas ms':>11} "
            f"{'dTOF %':>7} {'E_meas MPa':>10} {'COV E %':>8} {'dE %':>6}  source")
    lines = [f"wall law: {r['wall']}", head]
    for s in r["samples"]:
        cov = "-" if s["E_cov_pct"] is None else f"{s['E_cov_pct']:.2f}"
        lines.append(
            f"{s['sample']:8} {s['E_manufacturer'] / 1e6:9.1f} {s['nu']:5.2f} "
            f"{s['tof_sim'] * 1e3:10.4f} {s['tof_measured'] * 1e3:11.4f} "
            f"{s['tof_diff_pct']:7.2f} {s['E_measured'] / 1e6:10.1f} {cov:>8} "
            f"{s['E_diff_pct']:6.2f}  {s['tof_source']}")
    lines += [f"wrote {p}" for p in r.get("outputs", [])]
    return "\n".join(lines)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "validate", help="simulated vs measured TOF and inverted E (thesis Tables 2, 3)",
        description="For each config validation sample: TOF simulated at the manufacturer's "
        "E, measured TOF (recording, else the thesis's mean), % difference, E inverted "
        "from the measured TOF with its COV and % difference. SI units.")
    p.add_argument("--config", help="study config YAML (default config/config.yaml)")
    p.add_argument("--outdir", help="write validation.csv/.h5 and Figs 9, 10 here")
    p.add_argument("--root", default=".", help="folder relative recording paths start from")
    p.add_argument("--sweep", help="the chain's TOF(E, nu) sweep HDF5, drawn in Fig 10")
    p.add_argument("--calibration", metavar="FILE",
                   help="striker speed from a `ssw tof-calibrate --json` result (replaces "
                   "chain.striker_velocity; the workflow passes it when chain.use_calibration)")
    add_wall_options(p)
    add_json_flag(p)
    p.set_defaults(func=run_validate, human=_human)
