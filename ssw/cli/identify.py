"""``ssw identify``: what TOF, features and the whole waveform identify on one sample.

    ssw identify [--device D] --soil-E PA [--soil-nu NU] [--hits N] [--tof-scatter S]
                 [--noise-rms N] [--damping-law LAW] [--damping C] [device flags] [--json]

:func:`ssw.calibration.information.identifiability` for the (calibrated) device at the
noise of a real recording: one hit's TOF scatters by ``--tof-scatter`` (default: the
device's stated scatter, the thesis's 1.53e-5 s), every feature and sample by the NI
9234's noise floor (``--noise-rms``). Prints, per level of information, the parameters'
marginal standard uncertainties (scaled coordinates: relative for E, the masses, the
striker speed and the gain), which are identified (at most 0.1 there, every other
parameter free), the singular values and the strongest correlations; ``--json`` prints
everything. The contact dissipation is the coefficient of the device's dissipation law
(``--damping-law``: dashpot, kuwabara_kono, hunt_crossley; ``--damping`` its value), in the
law's own unit and scale (:mod:`ssw.chain.dissipation`).
"""

from __future__ import annotations

import argparse
from typing import Any

from ssw.cli import add_json_flag
from ssw.cli._device import add_device_options, chain_context


def run(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw identify``: what the TOF, the waveform's features and the whole waveform identify of
    the device and the soil on a sample (:func:`ssw.calibration.information.identifiability`).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw identify --help``).

    Returns
    -------
    dict of str to Any
        The soil (E in Pa, nu), the device's inputs and the identifiability result
        (SI units).

    Raises
    ------
    ssw.errors.ConfigError
        When ``--hits`` is below 1, or no hit's TOF scatter is stated (flag or
        device file).
    """
    from ssw.calibration.information import identifiability
    from ssw.daq.settings import settings_from_config
    from ssw.errors import ConfigError

    ctx = chain_context(args, args.soil_E, args.soil_nu)
    if not args.hits >= 1:
        raise ConfigError("--hits", args.hits, "at least 1")
    scatter = args.tof_scatter if args.tof_scatter is not None else ctx.device.tof_scatter
    if scatter is None:
        raise ConfigError("--tof-scatter", None, "one hit's TOF scatter, s (the device file "
                          "states none: repeatability.tof_std)")
    settings = settings_from_config(ctx.cfg, ctx.device)
    res = identifiability(ctx.params, ctx.wall, ctx.wall_options, args.soil_E, args.soil_nu,
                          settings, hits=args.hits, tof_scatter=float(scatter),
                          noise=args.noise_rms)
    return {**ctx.inputs(), "soil_E": args.soil_E, "soil_nu": args.soil_nu, **res.as_dict()}


#: Levels, in the order of the table.
LEVELS = ("tof", "features", "waveform")


def _cell(v: float | None, log: bool, unit: str) -> str:
    """A marginal standard uncertainty: relative (log coordinate) or SI with its unit."""
    if v is None:
        return "-"
    if log:
        return f"{100 * v:.3g} %" if v < 10 else ">1000 %"
    return f"{v:.3g} {unit}" if unit != "1" else f"{v:.3g}"


def _human(r: dict[str, Any]) -> str:
    n = r["noise"]
    lines = [f"identifiability on E = {r['soil_E'] / 1e6:g} MPa, nu {r['soil_nu']:g} "
             f"(device {r['device_name']}, {r['wall']} wall; {n['hits']} hits, TOF scatter "
             f"{n['tof_scatter']:.3g} s per hit, noise {n['noise_rms'] * 1e3:.3g} mN rms)",
             r["criterion"],
             "marginal standard uncertainty (relative for E, the masses, the striker speed and "
             "the gain; SI for the others), * = identified"]
    names = r["levels"]["tof"]["parameters"]
    label = {n: ("contact dissipation" if n == "damping" else n) for n in names}
    lines.append(f"{r['labels']['damping']}: its coefficient, in {r['units']['damping']}")
    lines.append(f"{'parameter':20}" + "".join(f"{lv:>22}" for lv in LEVELS))
    for view, title in (("levels", "every other parameter free"),
                        ("nu_known", "nu known")):
        lines.append(f"-- {title}")
        for name in names:
            row = f"{label[name]:20}"
            for lv in LEVELS:
                d = r[view][lv]
                if name not in d["parameters"]:
                    row += f"{'(known)':>22}"
                    continue
                s = r["std"][view][lv][name]
                mark = "*" if name in d["identified"] else " "
                cell = _cell(s, r["coordinates"][name] == "log", r["units"][name])
                row += f"{cell + mark:>22}"
            lines.append(row)
    row = f"{'E, device known':20}"
    for lv in LEVELS:
        s = r["std"]["device_known"][lv]["E"]
        mark = "*" if "E" in r["device_known"][lv]["identified"] else " "
        row += f"{_cell(s, True, 'Pa') + mark:>22}"
    lines.append(row)
    for lv in LEVELS:
        d = r["levels"][lv]
        sv = ", ".join(f"{s:.3g}" for s in d["singular_values"])
        lines.append(f"{lv}: singular values {sv}")
        pairs = []
        for i, a in enumerate(d["parameters"]):
            for j in range(i + 1, len(d["parameters"])):
                c = d["correlation"][i][j]
                if c is not None and abs(c) > 0.9:
                    pairs.append(f"{a}~{d['parameters'][j]} {c:+.3f}")
        if pairs:
            lines.append("  correlations beyond 0.9: " + ", ".join(pairs))
    return "\n".join(lines)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw identify`` subcommand to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser(
        "identify", help="what TOF, features and the whole waveform identify on a sample",
        description="Singular values, marginal uncertainties and correlations of E, nu, the "
        "striker speed, the preload, the sensor and striker masses, the contact dissipation "
        "(the coefficient of the device's law, --damping-law) and the DAQ gain from (a) the "
        "TOF, (b) the waveform's features, (c) the whole "
        "waveform, at the noise of a real recording (the TOF scatter per hit, the NI "
        "9234's noise floor); which of them each level identifies. SI units.")
    p.add_argument("--soil-E", type=float, required=True, help="the sample's modulus, Pa")
    p.add_argument("--soil-nu", type=float, default=0.3, help="its Poisson's ratio")
    p.add_argument("--hits", type=int, default=5, help="hits averaged (default 5)")
    p.add_argument("--tof-scatter", type=float,
                   help="one hit's TOF scatter, s (default: the device's stated scatter)")
    p.add_argument("--noise-rms", type=float,
                   help="the noise floor, N rms (default: the NI 9234's, 50 uV rms over the "
                   "sensor's sensitivity)")
    add_device_options(p)
    add_json_flag(p)
    p.set_defaults(func=run, human=_human)
