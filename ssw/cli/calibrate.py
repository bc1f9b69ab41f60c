"""``ssw calibrate``: identify device parameters from measured TOFs on reference samples.

Usage::

    ssw calibrate --reference E,nu,TOF[,TOF_STD] ... [--free NAME ...] [device flags]
                  [--output FILE.json] [--json]
    ssw calibrate --reference-recording FILE,E,nu ... [--free NAME ...]
    ssw calibrate --from-config [--config C] [--output FILE.json]   (the study's samples)

Without ``--free`` it identifies the striker speed and the preload (``--from-config``: the
config's ``calibration.free``). Every device, model and wall flag (:mod:`ssw.cli._flags`)
acts on the calibrated model and is recorded in the file; one it cannot honour is refused.

Prints (``--json``) ``{"parameters": {NAME: value}, "parameter_std": {...},
"singular_values": [...], "residuals": [...], "loo": [{"E", "E_predicted", "error_pct"}],
"model_error": {...} | null, "warnings": [...], ...inputs}`` and writes the calibration
file (:mod:`ssw.calibration.file`) with ``--output``. SI units. With ``--compare-laws``
(``--information features|waveform``) it also fits the references' records under each
dissipation law and reports each law's chi^2, parameter count, AIC and BIC and which the
data prefer (``law_comparison``, :mod:`ssw.calibration.laws`; the calibration itself stays
under the device's law). Where the references reject
the model (chi^2 beyond its 95 % quantile) the calibration carries a relative TOF model
error (``model_error``, :mod:`ssw.calibration.model_error`) instead of refusing; a fit that
did not converge or leaves a direction unidentified answers with that stated
(``warnings``). It refuses only its input: TOFs the device cannot produce, fewer references
than parameters freed.
"""

from __future__ import annotations

import argparse
from typing import Any

from ssw.calibration.fit import DEFAULT_FREE
from ssw.cli import add_json_flag
from ssw.cli._device import add_device_options, chain_context
from ssw.cli._flags import FLAGS, MODEL, refuse_for_calibration
from ssw.cli._soil import PLASTIC_MODELS
from ssw.errors import ConfigError


def _plastic_options(args: argparse.Namespace, ctx: Any, refs: list) -> dict[str, Any]:
    """The ``plastic`` wall's options for the config's references: each sample's model of
    ``--soil-model`` with its material's strengths (the library's, not fitted)."""
    from ssw.config import library
    from ssw.constitutive import model_of_strength

    if not args.from_config or args.reference or args.reference_recording:
        raise ConfigError("--soil-model", args.soil_model, "with --from-config alone (the "
                          "samples' materials give their strengths)")
    mats = library(ctx.cfg)
    by_id = {s["id"]: s.get("material") for s in ctx.cfg.get("validation", {})
             .get("samples", [])}
    models = []
    for r in refs:
        key = by_id.get(r.id)
        if key not in mats:
            raise ConfigError(f"validation.samples[{r.id}].material", key,
                              "a material of the library with strengths")
        models.append(model_of_strength(args.soil_model, mats[key].strength,
                                        f"materials.{key}"))
    return {"soil_model": tuple(models)}


def _ranges(items: list[str] | None) -> dict[str, tuple[float, float]]:
    out: dict[str, tuple[float, float]] = {}
    for it in items or []:
        try:
            name, span = it.split("=", 1)
            lo, hi = (float(x) for x in span.split(":", 1))
        except ValueError as exc:
            raise ConfigError("--range", it, "NAME=LO:HI (SI units)") from exc
        out[name.strip()] = (lo, hi)
    return out


def _references(args: argparse.Namespace, ctx: Any) -> list[Any]:
    """The references of ``ssw calibrate``: ``--reference E,nu,TOF[,STD]`` (SI units), each
    ``--reference-recording FILE,E,nu`` (its TOF picked from the recording) and, with
    ``--from-config``, the config's validation samples; ConfigError when malformed or none.
    """
    from ssw.calibration import parse_reference
    from ssw.calibration.references import from_config, recording_reference

    refs = [parse_reference(t, i) for i, t in enumerate(args.reference or [])]
    for j, t in enumerate(args.reference_recording or []):
        parts = t.split(",")
        if len(parts) != 3:
            raise ConfigError(f"--reference-recording[{j}]", t, "FILE,E,nu")
        try:
            E, nu = float(parts[1]), float(parts[2])
        except ValueError as exc:
            raise ConfigError(f"--reference-recording[{j}]", t, "FILE,E,nu") from exc
        refs.append(recording_reference(parts[0], E, nu, tof_options=_tof_options(ctx.params),
                                        full_scale=ctx.device.full_scale_force))
    if args.from_config:
        val = ctx.cfg.get("validation", {})
        refs += from_config(ctx.cfg, ctx.params, ctx.wall, ctx.wall_options, root=args.root,
                            tof_options=_tof_options(ctx.params, val.get("lowpass"),
                                                     val.get("min_hits", 3)),
                            full_scale=ctx.device.full_scale_force)
    if not refs:
        raise ConfigError("--reference", None, "references: --reference E,nu,TOF[,STD], "
                          "--reference-recording FILE,E,nu or --from-config")
    return refs


def run_calibrate(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw calibrate``: device parameters identified from measured TOFs on references (the bounded
    Levenberg-Marquardt of :mod:`ssw.calibration`).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw calibrate --help``).

    Returns
    -------
    dict of str to Any
        The identified parameters with their standard deviations, covariance, residuals,
        leave-one-out and alternatives, the calibration file (``output``) and the cost (s);
        SI units.

    Raises
    ------
    ssw.errors.ConfigError
        On flags that do not go together or a malformed ``--reference`` or
        ``--reference-recording``.
    """
    from ssw.calibration import calibrate, write_calibration
    from ssw.chain.params import numerics_of

    if args.calibration not in ("auto", "none"):
        raise ConfigError("--calibration", args.calibration,
                          "none here: a calibration starts from a device (--device)")
    args.calibration = "none"
    if args.compare_laws and args.information == "tof":
        raise ConfigError("--compare-laws", True, "with --information features or waveform "
                          "(the records identify the contacts' dissipation; TOFs do not)")
    ctx = chain_context(args)
    if ctx.wall == "table":
        raise ConfigError("--law", "table", "fem | hertz | fit | rigid (a law at any E)")
    refs = _references(args, ctx)
    cal_cfg = ctx.cfg.get("calibration", {})
    wall, wall_options = ctx.wall, ctx.wall_options
    if args.soil_model is not None:
        wall, wall_options = "plastic", _plastic_options(args, ctx, refs)
        if args.output:
            raise ConfigError("--output", args.output, "none with --soil-model (a plastic "
                              "sample's calibration is an analysis; ssw measure inverts "
                              "through the device's elastic law)")
    free = tuple(args.free or (cal_cfg.get("free") if args.from_config else None)
                 or DEFAULT_FREE)
    refuse_for_calibration(args, free)
    ranges = {**{k: tuple(v) for k, v in cal_cfg.get("ranges", {}).items()},
              **_ranges(args.range)} if args.from_config else _ranges(args.range)
    # the model calibrated, recorded whole: the config's numerics and every model flag
    numerics = {k: getattr(ctx.params, k) for k in sorted(
        set(numerics_of(ctx.cfg)) | {f.field for f in FLAGS if f.target == MODEL})}
    loo = not args.no_loo and (cal_cfg.get("loo", True) if args.from_config else True)
    from ssw.progress import progress_bar

    with progress_bar(None, desc="calibration", unit="run") as bar:
        cal = calibrate(
            refs, ctx.device, free, materials=_materials(ctx.cfg), numerics=numerics,
            wall=wall, wall_options=wall_options, ranges=ranges, loo=loo,
            scan_points=args.scan_points or cal_cfg.get("scan_points"),
            material_set=ctx.cfg.get("material_set", "realistic"),
            materials_file=ctx.cfg.get("materials_file"),
            provenance={"command": "ssw calibrate", "config": args.config}, on_run=bar,
            recorded_wall_options=ctx.device_wall_options, reference_sample=ctx.sample,
        )
    if args.information != "tof":
        cal = _with_information(args, ctx, cal)
    if args.output:
        write_calibration(args.output, cal)
    return _result(args, ctx, cal)


def _result(args: argparse.Namespace, ctx: Any, cal: Any) -> dict[str, Any]:
    """``ssw calibrate``'s result: the command's inputs, the calibration ``cal``'s
    parameters (SI units) with their uncertainties, residuals, leave-one-out and
    alternatives, the file written (``output``) and the cost (wall time, s; runs)."""
    out = {
        **ctx.inputs(),
        "parameters": cal.parameters, "parameter_std": cal.parameter_std,
        "at_bound": cal.at_bound, "covariance_parameters": list(cal.covariance_parameters),
        "covariance": cal.covariance, "singular_values": cal.singular_values,
        "unidentified": cal.unidentified, "residuals": cal.residuals,
        "references": cal.references, "model_error": cal.model_error,
        "warnings": list(cal.warnings),
        "loo": cal.loo, "alternatives": cal.alternatives,
        "drop_height": cal.device.drop_height, "output": args.output,
        "wall_time": cal.provenance["wall_time_s"],
        "parameter_sets_evaluated": cal.provenance["parameter_sets_evaluated"],
        "batched_runs": cal.provenance["batched_runs"],
    }
    if "information" in cal.provenance:
        out["information"] = cal.provenance["information"]
    if "law_comparison" in cal.provenance:
        out["law_comparison"] = cal.provenance["law_comparison"]
    return out


def _with_information(args: argparse.Namespace, ctx: Any, cal: Any) -> Any:
    """The TOF calibration ``cal`` refined by the reference recordings' features, and then
    their whole waveforms (:func:`ssw.calibration.records.calibrate_levels`): the device's
    globals they identify are freed, the others held; with ``--compare-laws`` the records
    fitted under each dissipation law too (:func:`ssw.calibration.laws.compare_laws`, in
    the provenance's ``law_comparison``)."""
    from ssw.calibration.hits import device_priors
    from ssw.calibration.records import calibrate_levels
    from ssw.calibration.waveform import Hits
    from ssw.daq.importers import read_any
    from ssw.daq.model import Acquisition
    from ssw.daq.settings import settings_from_config

    if not args.reference_recording or args.reference or args.from_config:
        raise ConfigError("--information", args.information, "tof, or reference recordings "
                          "alone (--reference-recording FILE,E,nu): a fit of their records")
    settings = settings_from_config(ctx.cfg, ctx.device)
    samples, trig, rate = [], settings.trigger_level, None
    for t in args.reference_recording:
        path, E, nu = t.split(",")
        rec = read_any(path, full_scale=ctx.device.full_scale_force, clipped="drop")
        trig = float(rec.meta.get("trigger_level", trig))
        rate = rec.sample_rate
        samples.append(Hits.from_recording(rec, E=float(E), nu=float(nu),
                                           full_scale=ctx.device.full_scale_force))
    scatter = ctx.device.tof_scatter or 1.53e-5  # the thesis's scatter when none is stated
    acq = Acquisition(sample_rate=float(rate), sensitivity=ctx.device.sensitivity,
                      coupling=settings.coupling)
    # the striker held to its weighed mass, within what the device file states of it
    prior = device_priors(cal.chain_params(), {"striker_mass": ctx.device.striker_mass_std})
    levels = calibrate_levels(cal, samples, acq, args.information, trigger_level=trig,
                              tof_scatter=float(scatter), wall=ctx.wall,
                              wall_options=ctx.wall_options, loo=not args.no_loo,
                              prior=prior)
    out = levels[args.information]
    if args.compare_laws:
        from dataclasses import replace

        from ssw.calibration.laws import compare_laws

        cmp = compare_laws(samples, cal.chain_params(), ctx.wall, ctx.wall_options, acq,
                           args.information, trigger_level=trig,
                           tof_scatter=float(scatter), prior=prior)
        out = replace(out, provenance={**out.provenance, "law_comparison": cmp})
    return out


def _tof_options(params: Any, lowpass: float | None = None, min_hits: int = 3) -> Any:
    """TOF picking of reference recordings: the reflected peak only after the device's
    shortest physical round trip (ssw.signal.tof.ChainPath)."""
    from ssw.signal.tof import ChainPath, TofOptions

    return TofOptions(lowpass=lowpass, min_hits=min_hits, chain=ChainPath.from_params(params))


def _materials(cfg: dict[str, Any]) -> dict[str, Any]:
    from ssw.config import library

    return library(cfg)


def _human(r: dict[str, Any]) -> str:
    lines = [f"device {r['device_name']} calibrated with the {r['wall']} wall on "
             f"{len(r['references'])} reference(s):"]
    for k, v in r["parameters"].items():
        std = (r["parameter_std"] or {}).get(k)
        side = r["at_bound"].get(k)
        lines.append(f"  {k} = {v:.6g}" + (
            f" (held on its {side} bound: no standard error; the others' covariance is "
            "conditional on it)" if side else f" +- {std:.3g}" if std is not None else
            " (no standard error: see below)"))
    lines.append(f"  (striker drop height {r['drop_height'] * 1e3:.3g} mm)")
    lines.append("  singular values: " + ", ".join(f"{s:.3g}" for s in r["singular_values"]))
    lines += [f"  not identified: {u}" for u in r["unidentified"]]
    lines += [f"  {w}" for w in r["warnings"]]
    lines.append(f"{'reference':10} {'E MPa':>8} {'nu':>5} {'TOF ms':>9} {'model ms':>9} "
                 f"{'resid %':>8}")
    for ref in r["references"]:
        lines.append(f"{ref['id']:10} {ref['E'] / 1e6:8.1f} {ref['nu']:5.2f} "
                     f"{ref['tof'] * 1e3:9.5f} {ref['tof_model'] * 1e3:9.5f} "
                     f"{ref['residual_pct']:8.3f}")
    if r["loo"]:
        lines.append("leave-one-out (each E from a calibration without it):")
        for row in r["loo"]:
            if row["E_predicted"] is None:
                lines.append(f"  {row['id']}: no prediction ({row['reason']})")
            else:
                sv = ", ".join(f"{v:.2g}" for v in row["singular_values"])
                lines.append(f"  {row['id']}: E {row['E'] / 1e6:.1f} MPa -> "
                             f"{row['E_predicted'] / 1e6:.1f} MPa ({row['error_pct']:+.1f} %; "
                             f"fit without it: chi2 {row['chi2']:.2g}, singular values {sv})")
                if not row.get("identified", True):
                    lines.append("    (the others do not identify every parameter: the "
                                 "unidentified direction stays at the full calibration)")
    for alt in r["alternatives"]:
        lines.append(f"  another solution within chi2 + 1: {alt}")
    info = r.get("information")
    if info:
        lines.append(f"the references' records ({info['level']}): freed "
                     + (", ".join(f"{k} = {v:.6g}" for k, v in info["values"].items())
                        or "nothing") + f"; DAQ gain {info['gain']:.5g}; chi2 "
                     f"{info['chi2']:.4g} on {info['chi2_dof']}"
                     + (" FLAGGED" if info["flagged"] else "")
                     + ("" if info["converged"] else " (not converged)"))
    cmp = r.get("law_comparison")
    if cmp:
        lines.append(f"dissipation laws on the references' records ({cmp['level']}):")
        lines.append(f"  {'law':14} {'coefficient':>22} {'chi2':>10} {'k':>4} {'n':>6} "
                     f"{'dAIC':>9} {'dBIC':>9}")
        for row in cmp["laws"]:
            d = {c: ("    (n/a)" if row[f"delta_{c}"] is None else f"{row[f'delta_{c}']:9.1f}")
                 for c in ("aic", "bic")}
            lines.append(f"  {row['law']:14} {row['coefficient']:11.4g} {row['unit']:>10} "
                         f"{row['chi2']:10.4g} {row['parameters']:4d} "
                         f"{row['observations']:6d} {d['aic']} {d['bic']}")
        lines.append(f"  {cmp['statement']}")
    if r["output"]:
        lines.append(f"wrote {r['output']}")
    return "\n".join(lines)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw calibrate`` subcommand to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser(
        "calibrate", help="identify device parameters from measured TOFs on references",
        description="Least-squares identification of device parameters (a batched global "
        "scan, then Levenberg-Marquardt; no monotonicity assumed) from measured TOFs on "
        "samples of known E and nu. Reports standard errors, singular values, residuals and "
        "leave-one-out predictions; writes a calibration file every chain command takes "
        "(--calibration). SI units.")
    p.add_argument("--reference", action="append", metavar="E,nu,TOF[,TOF_STD]",
                   help="a reference sample: E (Pa), nu, measured mean TOF (s) and its "
                   "standard uncertainty (s); repeat it")
    p.add_argument("--reference-recording", action="append", metavar="FILE,E,nu",
                   help="a recording of a sample of known E (Pa) and nu; repeat it")
    p.add_argument("--from-config", action="store_true",
                   help="the config's validation samples (recordings, else the published "
                   "measured means) and its calibration.free/ranges/loo")
    p.add_argument("--root", default=".",
                   help="folder the config's relative recording paths start from")
    p.add_argument("--free", action="append", metavar="NAME",
                   help="a device parameter to identify (striker_velocity, preload, "
                   "sensor_mass, striker_mass, beads); repeat it (default: the config's "
                   "calibration.free with --from-config, else "
                   f"{' and '.join(DEFAULT_FREE)})")
    p.add_argument("--range", action="append", metavar="NAME=LO:HI",
                   help="scan range of a free parameter, SI units")
    p.add_argument("--scan-points", type=int, help="grid points per continuous parameter")
    p.add_argument("--no-loo", action="store_true", help="skip the leave-one-out predictions")
    p.add_argument("--output", help="calibration file to write (JSON)")
    p.add_argument("--information", choices=("tof", "features", "waveform"), default="tof",
                   help="what of the reference recordings calibrates: their TOF (default), "
                   "or then also their features or whole waveforms, which free the device's "
                   "preload, masses, contact dashpot and DAQ gain where they identify them "
                   "(said in the output's information.freed)")
    p.add_argument("--compare-laws", action="store_true",
                   help="with --information features or waveform: also fit the reference "
                   "records under each contact dissipation law (dashpot, kuwabara_kono, "
                   "hunt_crossley) and report each law's chi2, parameter count, AIC and BIC "
                   "and which the data prefer (law_comparison; the calibration stays under "
                   "the device's law, --damping-law; each law's fit costs a calibration)")
    p.add_argument("--soil-model", choices=PLASTIC_MODELS,
                   help="the references as plastic samples of this model, each with its "
                   "material's strengths (--from-config): the plastic wall's first hit on the "
                   "virgin sample, through the device's plate (the leave-one-out inversions "
                   "tabulate the plastic FEM per trial modulus: minutes)")
    add_device_options(p)
    add_json_flag(p)
    p.set_defaults(func=run_calibrate, human=_human)
