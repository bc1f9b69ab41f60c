"""``ssw measure``: recordings of one test point -> its modulus with an interval.

    ssw measure FILE... [--device D] [--calibration C] --soil-nu NU|LO:HI [--json]

Works from any folder: the device defaults to the shipped thesis device, the calibration to
the study's (``results/calibration/calibration.json``) when there is one, the wall law to the
config's (``fem``: computed on demand). Prints E, its 95 % interval and what it is made of;
``--json`` prints ``{"E", "E_low", "E_high", "tof_mean", "tof_sem", "n_accepted", ...inputs}``.
"""

from __future__ import annotations

import argparse
from typing import Any

from ssw.cli import add_json_flag
from ssw.cli._device import add_device_options, chain_context
from ssw.cli.daq import add_recording_options, add_tof_options


def run_measure(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw measure``: the recordings of one test point read into the soil's E with its 95 %
    interval (:func:`ssw.measure.measure`).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw measure --help``).

    Returns
    -------
    dict of str to Any
        The device's inputs and the measurement (E and its 95 % interval, Pa; the
        contributions, %; the TOF's mean and scatter, s) with its validity checks.
    """
    from ssw.cli.daq import read_options, tof_options
    from ssw.daq.importers import read_any
    from ssw.measure import measure, parse_nu

    nu = parse_nu(args.soil_nu)
    ctx = chain_context(args)
    ropts = read_options(args)
    if args.clipped == "raise":  # a field session keeps its good hits: drop clipped ones
        ropts["clipped"] = "drop"
    if "sensitivity" not in ropts:  # data in volts: the device's sensor
        ropts["sensitivity"] = ctx.device.sensitivity
    ropts["full_scale"] = ctx.device.full_scale_force  # clipping, whatever the format
    recs = [read_any(f, **_format_options(f, ropts)) for f in args.files]
    if args.lowpass is None:
        args.lowpass = ctx.cfg.get("validation", {}).get("lowpass")
    from ssw.cli.chain import context_strengths, finite_sample_validity

    source = ("--sample-strength" if args.sample_strength is not None else
              f"the library's {args.sample_material}" if args.sample_material else "")
    m = measure(recs, nu, ctx.params, ctx.wall, ctx.wall_options,
                calibration=ctx.calibration, tof_options=tof_options(args, ctx.params),
                device=ctx.device, strength=sample_strength(args, ctx),
                sample_range=_sample_range(args, ctx),
                strengths=context_strengths(ctx, source=source),
                stresses=args.stress_checks)
    if args.information != "tof":
        m = _with_information(args, ctx, recs, m)
    out = {**ctx.inputs(), **m.to_dict()}
    if ctx.sample is not None and "validity" in out:  # the stated sample, read as modelled
        fs = finite_sample_validity(ctx, m.E, m.nu, m.tof_mean)
        _add_checks(out, fs.to_dict(0))
    if args.lift_thickness is not None:
        out.update(_lift_check(args, ctx, m, out["notes"]))
        _add_checks(out, _lift_validity(args, out).to_dict(0))
    return out


def _add_checks(out: dict[str, Any], more: dict[str, Any]) -> None:
    """Add the entries of ``more`` (:meth:`ssw.validity.Validity.to_dict`) to a result's."""
    out["validity"] = [*out.get("validity", []), *more["validity"]]
    out["checks_failed"] = [*out.get("checks_failed", []), *more["checks_failed"]]


def _lift_validity(args: argparse.Namespace, out: dict[str, Any]) -> Any:
    """The ``finite_sample`` check of a lift read as a half-space: its worst error over the
    subgrades (:func:`_lift_check`)."""
    from ssw.validity import finite_sample

    errs = out["lift_error"]
    return finite_sample([max(abs(v) for v in errs.values())],
                         f"a {args.lift_thickness * 1e3:g} mm lift on subgrades of "
                         f"{', '.join(errs)} x its modulus (--subgrade-ratio)")


def _with_information(args: argparse.Namespace, ctx: Any, recs: list[Any], m: Any) -> Any:
    """E from the records' features or waveforms (:func:`ssw.measure.measure_information`):
    the acquisition as recorded (rate, sensitivity, coupling, trigger level; the config's
    where a format does not say), each hit's TOF scatter the device's stated one (else the
    hits' own)."""
    import numpy as np

    from ssw.daq.model import Acquisition
    from ssw.daq.settings import settings_from_config
    from ssw.errors import ConfigError
    from ssw.measure import measure_information

    settings = settings_from_config(ctx.cfg, ctx.device)
    meta = recs[0].meta
    acq = Acquisition(sample_rate=float(m.sample_rate),
                      sensitivity=float(meta.get("sensitivity", ctx.device.sensitivity)),
                      coupling=str(meta.get("coupling", settings.coupling)))
    scatter = ctx.device.tof_scatter
    if scatter is None:
        scatter = m.tof_std
    if scatter is None or not np.isfinite(scatter) or not scatter > 0:
        raise ConfigError("--information", args.information, "tof, or a device that states "
                          "its TOF scatter per hit (repeatability.tof_std), or enough hits "
                          "to estimate it")
    cal = ctx.calibration
    info = (getattr(cal, "provenance", None) or {}).get("information") or {}
    gain = float(info.get("gain", 1.0))  # a waveform calibration's DAQ gain
    # its model-error floor, where it was calibrated at this level
    same = info.get("level") == args.information
    floor = info.get("floor") if same else None
    covariance = info.get("covariance") if same else None
    model_loo = info.get("model_loo") if same else None  # its references' leave-one-out term
    discrepancy = info.get("discrepancy") if same else None  # its model's correction
    return measure_information(
        m, recs, args.information, ctx.params, ctx.wall, ctx.wall_options, acquisition=acq,
        trigger_level=float(meta.get("trigger_level", settings.trigger_level)),
        tof_scatter=float(scatter), full_scale=ctx.device.full_scale_force, gain=gain,
        floor=floor, covariance=covariance, model_loo=model_loo, discrepancy=discrepancy)


#: The error of a half-space reading beyond which a lift's measurement warns.
LIFT_TOLERANCE = 0.02


def _lift_check(args: argparse.Namespace, ctx: Any, m: Any, notes: list[str]
                ) -> dict[str, Any]:
    """A test point on a lift of ``--lift-thickness`` over a subgrade of
    ``--subgrade-ratio`` x its modulus (default 0.5 and 2): the error of this half-space
    reading (:func:`ssw.lift.lift_errors` at the measured E), and a warning beyond
    :data:`LIFT_TOLERANCE`."""
    from ssw.cli.lift import parse_floats
    from ssw.errors import ConfigError
    from ssw.lift import lift_errors

    if not args.lift_thickness > 0:
        raise ConfigError("--lift-thickness", args.lift_thickness, "a thickness > 0 m")
    ratios = parse_floats(args.subgrade_ratio, "--subgrade-ratio")
    res = lift_errors(ctx.params, m.E, m.nu, ratios, [args.lift_thickness])
    errs = {f"{r:g}": float(e) for r, e in zip(ratios, res.error[:, 0], strict=True)}
    worst = max(errs.items(), key=lambda kv: abs(kv[1]))
    if abs(worst[1]) > LIFT_TOLERANCE:
        notes.append(f"a {args.lift_thickness * 1e3:g} mm lift read as a half-space: E is off by "
                     f"{100 * worst[1]:+.1f} % on a subgrade of {worst[0]} x its modulus "
                     f"(beyond {100 * LIFT_TOLERANCE:g} %; ssw lift-study): measure a thicker "
                     "lift or know the subgrade")
    return {"lift_thickness": args.lift_thickness, "lift_error": errs}


def _sample_range(args: argparse.Namespace, ctx: Any) -> list[dict[str, Any]] | None:
    """The wall options of the thinnest and thickest sample of ``--sample-thickness LO:HI``
    (the budget's sample term), or None."""
    from ssw.cli._sample import sample_of, thickness_range

    rng = thickness_range(args)
    if rng is None:
        return None
    base = (ctx.device_wall_options or {}).get("contact") or dict(ctx.cfg.get("contact", {}))
    return [{**ctx.wall_options, "contact": sample_of(args, h).contact_settings(base)}
            for h in rng]


def sample_strength(args: argparse.Namespace, ctx: Any) -> float | None:
    """The sample's uniaxial strength (Pa): ``--sample-strength``, else that of the library
    material ``--sample-material`` (:func:`ssw.measure.uniaxial_strength`), else None.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (``--sample-strength``, ``--sample-material``).
    ctx : ssw.cli._device.ChainContext
        The resolved chain context (its config's materials library).

    Returns
    -------
    float or None
        Pa, the strength, or None.

    Raises
    ------
    ssw.errors.ConfigError
        When both flags are given, the material is not in the library, or its entry
        states no strength.
    """
    from ssw.errors import ConfigError
    from ssw.measure import uniaxial_strength

    if args.sample_strength is not None and args.sample_material is not None:
        raise ConfigError("--sample-strength", args.sample_strength,
                          "not with --sample-material (which states one)")
    if args.sample_strength is not None:
        return float(args.sample_strength)
    if args.sample_material is None:
        return None
    from ssw.config import library

    mats = library(ctx.cfg)
    if args.sample_material not in mats:
        raise ConfigError("--sample-material", args.sample_material,
                          f"a material of the library: {', '.join(sorted(mats))}")
    value = uniaxial_strength(mats[args.sample_material].strength)
    if value is None:
        raise ConfigError("--sample-material", args.sample_material,
                          "a material whose library entry states a strength (yield, "
                          "compressive, or cohesion and friction angle)")
    return value


def _format_options(path: str, opts: dict[str, Any]) -> dict[str, Any]:
    """The reading options a file's format takes (an HDF5 session is in N already)."""
    from pathlib import Path

    if Path(path).suffix.lower() in (".h5", ".hdf5"):
        return {"clipped": opts["clipped"], "full_scale": opts.get("full_scale")}
    return opts


def _human(r: dict[str, Any]) -> str:
    nu = (f"nu {r['nu_range'][0]:g}..{r['nu_range'][1]:g}" if r["nu_range"]
          else f"nu {r['nu']:g}")
    cal = r.get("calibration_file") or "none"
    lines = [
        f"E = {r['E'] / 1e6:.1f} MPa, 95 % interval {r['E_low'] / 1e6:.1f} .. "
        f"{r['E_high'] / 1e6:.1f} MPa ({nu}; device {r['device_name']}, calibration {cal}, "
        f"{r['wall']} wall)",
        f"TOF {r['tof_mean'] * 1e3:.5f} ms +- "
        + (f"{r['tof_sem'] * 1e6:.2f} us (standard error)" if r["tof_sem"] is not None
           else "? (scatter not estimable)")
        + f" from {r['n_accepted']} of {r['n_hits'] + r.get('n_dropped', 0)} hits in "
        f"{len(r['files'])} file(s)",
        "uncertainty of E (1 sigma): {:.2f} % = {}".format(
            r["E_u_pct"], ", ".join(f"{k} {v:.2f} %" for k, v in r["contributions_pct"].items())),
    ]
    if "yield_index" in r:
        lines.append(f"yield index {r['yield_index']:.2f} (sample peak von Mises "
                     f"{r['sample_peak_von_mises'] / 1e6:.3g} MPa over its strength "
                     f"{r['sample_strength'] / 1e6:.3g} MPa)"
                     + (": YIELDED" if r["sample_yielded"] else ""))
    if "chi2" in r:
        lines.append(f"{r['information']} fit: chi2 {r['chi2']:.4g} on {r['chi2_dof']} degrees "
                     f"of freedom (quantile {r['chi2_quantile']:.4f})"
                     + (": FLAGGED" if r["flagged"] else "") + "; identified: "
                     + ", ".join(f"{k} {v['value']:.4g} +- {v['std']:.2g}"
                                 for k, v in r["identified"].items()))
    lines += [f"NOT IN THE INTERVAL: {k}: {v}" for k, v in r.get("missing_terms", {}).items()]
    if "validity" in r:
        from ssw.validity import human_lines

        lines += human_lines(r["validity"], r.get("checks_skipped"))
    lines += [f"note: {n}" for n in r["notes"]]
    lines += [f"rejected: {x}" for x in r["rejections"]]
    if r["synthetic"]:
        lines.append("SYNTHETIC recording(s): made by the simulated backend, not measured")
    return "\n".join(lines)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw measure`` subcommand to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser(
        "measure", help="recordings of one test point -> E with its 95 %% interval",
        description="Per-hit TOF (rejection rule per session), pooled mean and standard "
        "error, then E through the device and its calibration, with every contribution to "
        "its uncertainty. Reads HDF5 sessions, CSV, MAT and TDMS. SI units.")
    p.add_argument("files", nargs="+", help="recordings of one test point")
    p.add_argument("--soil-nu", required=True, metavar="NU|LO:HI",
                   help="Poisson's ratio of the medium, or a range LO:HI")
    p.add_argument("--sample-strength", type=float, metavar="PA",
                   help="the sample's uniaxial strength, Pa: report the yield index (peak von "
                   "Mises stress under the bead over it) and warn when the sample yielded")
    p.add_argument("--lift-thickness", type=float, metavar="H",
                   help="the test point is a lift of this thickness, m, on a subgrade: report "
                   "the error of reading it as a half-space and warn beyond 2 %%")
    p.add_argument("--subgrade-ratio", default="0.5,2", metavar="R,...",
                   help="with --lift-thickness: the subgrade's modulus over the lift's "
                   "(default 0.5,2)")
    p.add_argument("--sample-material", metavar="KEY",
                   help="the sample's material in the library (its strength, e.g. pcf15)")
    from ssw.cli.chain import add_stress_checks_option

    add_stress_checks_option(p, "fem")
    p.add_argument("--information", choices=("tof", "features", "waveform"), default="tof",
                   help="what of the records E comes from: the TOF (default), the features "
                   "(TOF, amplitude ratios, secondary reflection, pulse widths) or the whole "
                   "waveform, fitted through the measurement model; the latter two also "
                   "report the parameters the records identify and the fit's chi2 with its "
                   "quantile (flagged beyond 0.999)")
    add_recording_options(p)
    add_tof_options(p)
    add_device_options(p)
    add_json_flag(p)
    p.set_defaults(func=run_measure, human=_human, thickness_range_ok=True)
