"""``ssw lift-study``: how wrong a half-space reading of a lift on a subgrade is.

    ssw lift-study [--E1 PA] [--nu NU] [--ratios 0.25,0.5,2,4] [--thicknesses M,...]
                   [--device D] [--csv F] [--plot F.png] [--json]

:func:`ssw.lift.lift_errors` with the (calibrated) device: ``E_app / E1 - 1`` per subgrade
ratio and lift thickness, and the thickness below which the error exceeds 2 %.
"""

from __future__ import annotations

import argparse
from typing import Any

from ssw.cli import add_json_flag
from ssw.cli._device import add_device_options, chain_context


def parse_floats(text: str, field: str) -> list[float]:
    """Comma-separated numbers.

    Parameters
    ----------
    text : str
        The numbers, comma-separated (empty items skipped).
    field : str
        The flag named in the error.

    Returns
    -------
    list of float
        The numbers.

    Raises
    ------
    ssw.errors.ConfigError
        When an item is no number.
    """
    from ssw.errors import ConfigError

    try:
        return [float(x) for x in text.split(",") if x.strip()]
    except ValueError as exc:
        raise ConfigError(field, text, "comma-separated numbers") from exc


def run(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw lift-study``: the error of a half-space reading of a lift on a subgrade, over subgrade
    ratios and lift thicknesses (:func:`ssw.lift.lift_errors`).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw lift-study --help``).

    Returns
    -------
    dict of str to Any
        The device's inputs and the study (TOFs, s; relative errors, -); the CSV and
        figure written when asked.

    Raises
    ------
    ssw.errors.ConfigError
        When ``--ratios`` or ``--thicknesses`` holds an item that is no number.
    """
    from ssw.h5io import write_csv_text
    from ssw.lift import lift_errors, plot_lift

    ctx = chain_context(args, numerics_only=True)
    res = lift_errors(ctx.params, args.E1, args.nu, parse_floats(args.ratios, "--ratios"),
                      parse_floats(args.thicknesses, "--thicknesses"),
                      subgrade_nu=args.subgrade_nu, energy=args.reach_energy)
    if args.csv:
        lines = ["subgrade_ratio,lift_thickness_m,tof_s,error_rel"]
        lines += [f"{r:g},{h:g},{res.tof[i, j]:.9g},{res.error[i, j]:.6g}"
                  for i, r in enumerate(res.ratios) for j, h in enumerate(res.thicknesses)]
        write_csv_text(args.csv, "\n".join(lines) + "\n",
                       {**ctx.inputs(), "E1": res.E1, "nu": res.nu,
                        "subgrade_nu": res.subgrade_nu, "energy": args.reach_energy})
    if args.plot:
        plot_lift(res, args.plot)
    return {**ctx.inputs(), **res.to_dict()}


def _human(r: dict[str, Any]) -> str:
    lines = [f"lift E1 = {r['E1'] / 1e6:g} MPa, nu {r['nu']:g}, read as a half-space: "
             "E / E1 - 1"]
    head = "E2/E1   " + " ".join(f"{h * 1e3:>8.0f}mm" for h in r["thicknesses"])
    lines.append(head)
    for ratio, row in zip(r["ratios"], r["error"], strict=True):
        lines.append(f"{ratio:<7g} " + " ".join(f"{100 * e:>+9.2f}%" for e in row))
    for ratio, h in r["warning_thickness"].items():
        lines.append(f"E2/E1 {ratio}: error beyond 2 % below "
                     + ("(not within the thicknesses computed)" if h is None
                        else f"{h * 1e3:.0f} mm"))
    return "\n".join(lines)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw lift-study`` subcommand to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser(
        "lift-study", help="error of a half-space reading of a lift on a subgrade",
        description="The device's chain on a lift of E1 over a subgrade of ratio x E1 (the "
        "layered oracle's exact contact laws), read as a half-space: E / E1 - 1 against the "
        "lift's thickness. SI units.")
    p.add_argument("--E1", type=float, default=100e6, help="the lift's modulus, Pa")
    p.add_argument("--nu", type=float, default=0.35, help="the lift's Poisson's ratio")
    p.add_argument("--subgrade-nu", type=float, help="the subgrade's (default: the lift's)")
    p.add_argument("--ratios", default="0.25,0.5,2,4", help="subgrade E2 / E1, comma-separated")
    p.add_argument("--thicknesses", default="0.02,0.05,0.1,0.15,0.3",
                   help="lift thicknesses, m, comma-separated")
    p.add_argument("--reach-energy", type=float, default=0.01,
                   help="J, the curves reach the Hertz indentation of this energy")
    p.add_argument("--csv", help="table of the errors (CSV)")
    p.add_argument("--plot", help="figure of the errors (PNG)")
    add_device_options(p)
    add_json_flag(p)
    p.set_defaults(func=run, human=_human)
