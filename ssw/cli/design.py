"""``ssw design``: which plate under the chain (material, thickness; optionally diameter and
striker speed) makes the device most sensitive to the soil's modulus over a range of soils
while the plate stays elastic and the sample yields least.

The device is resolved as for every chain command (:mod:`ssw.cli._device`: config, device,
calibration, device flags); its plate is the reference candidate. The chain always runs
with the exact FEM wall (``fem``) of each candidate plate. Objective, constraints and the
JSON fields: :mod:`ssw.design.spec`, :mod:`ssw.design.evaluate`, :mod:`ssw.design.optimize`.

TOF uncertainty of one measurement (the resolution dE/E): the device file's stated scatter
(``repeatability.tof_std``) over ``sqrt(--hits)``, and the sampling term of the DAQ's rate
(``daq.sample_rate``, :func:`ssw.measure.sampling_uncertainty`), in quadrature. A device
without a stated scatter uses the thesis's 1.53e-5 s (0.4 mm PLA plate), labelled so.

``--merge A.json B.json ...`` ranks the candidates of several results of the same question
together (the workflow runs one job per material).
"""

from __future__ import annotations

import argparse
from typing import Any

from ssw.cli import add_json_flag
from ssw.errors import ConfigError

#: s, one hit's TOF scatter used when the device states none: the thesis's, with the plate.
THESIS_TOF_SCATTER = 1.53e-5
THESIS_TOF_SCATTER_SOURCE = ("the thesis's 1.53e-5 s over three consecutive hits with the "
                             "0.4 mm PLA plate (Stage III, Fig 9), used because the device "
                             "file states no repeatability.tof_std")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw design`` subcommand to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    from ssw.cli._device import add_device_options
    from ssw.design.spec import MATERIALS, THICKNESS

    p = sub.add_parser(
        "design",
        help="design plates (material x thickness) and whole devices (beads, striker, plate)"
        " for resolution of the soil's modulus over a range of soils",
        description="Design the plate under the chain (--space plate, the default: material, "
        "thickness; optionally diameter and striker speed) or the whole device (--space "
        "device: beads, sensor, striker, drop, plate) that resolves the soil's modulus best "
        "over a range of soils while the plate stays elastic and the sample yields least.",
    )
    g = p.add_argument_group("the question")
    g.add_argument("--space", choices=("plate", "device"), default="plate",
                   help="what is designed: the plate under the device's chain (default) or "
                   "the whole device (beads, sensor, striker, drop, plate; the config's "
                   "design.device section; ssw.design.device_search)")
    g.add_argument("--family", metavar="D:MATERIAL", action="append",
                   help="with --space device: only this bead diameter (m) and plate "
                   "material (repeatable; the workflow's jobs)")
    g.add_argument("--soil-E", help="LO:HI soil moduli, Pa (e.g. 10e6:100e6)")
    g.add_argument("--soil-nu", type=float, help="soil Poisson's ratio")
    g.add_argument("--soil-range", help="a named soil range of the config's design.soils "
                   "(instead of --soil-E/--soil-nu; the section's other settings apply)")
    g.add_argument("--materials", help=f"plate materials, comma-separated (default "
                   f"{','.join(MATERIALS)})")
    g.add_argument("--thickness", help=f"LO:HI plate thickness searched, m (default "
                   f"{THICKNESS[0]:g}:{THICKNESS[1]:g})")
    g.add_argument("--plate-diameters", help="plate diameters tried, m, comma-separated "
                   "(default: the device's)")
    g.add_argument("--striker-velocities", help="striker speeds tried, m/s, comma-separated "
                   "(default: the device's)")
    g.add_argument("--moduli", type=int, help="soil moduli of the sensitivity curve (default 20)")
    g.add_argument("--soil-strength", type=float, help="the soil's yield stress, Pa (default: "
                   "--soil-strength-ratio x E)")
    g.add_argument("--soil-strength-ratio", type=float,
                   help="soil yield stress over modulus (default 0.01, an assumption)")
    g.add_argument("--soil-yield-limit", type=float, help="largest soil yield index allowed "
                   "(default 1: first yield)")
    g.add_argument("--max-mass-ratio", type=float,
                   help="largest plate mass over a bead's (default 1)")
    g.add_argument("--scan-points", type=int, help="thicknesses scanned per material before "
                   "the bounded search (default 5)")
    g.add_argument("--thickness-tol", type=float,
                   help="the bounded search's tolerance in ln(thickness) (default 0.01)")
    g.add_argument("--hits", type=int, help="TOF hits averaged per measurement (default 3)")
    g.add_argument("--tof-scatter", type=float, help="one hit's TOF standard deviation, s "
                   "(default: the device's repeatability.tof_std)")
    g.add_argument("--sample-rate", type=float, help="DAQ sample rate, S/s (default: the "
                   "config's daq.sample_rate)")
    g.add_argument("--no-reference", action="store_true",
                   help="do not evaluate the device's own plate")
    g.add_argument("--jobs", type=int, default=1, help="processes (one material search each)")
    g.add_argument("--plastic-hits", type=int, metavar="N",
                   help="strike a yielding sample N times through the recommended plate and "
                   "the device's own (von Mises at the design's soil strength, at the soil "
                   "where the elastic yield index is largest): per hit TOF, permanent set, "
                   "dissipated energy, and the TOF drift (ssw.design.hits_check); with "
                   "--space device the finalists and the base device, through their plate "
                   "yielding as von Mises (the plate's dent; default design.device."
                   "plastic_hits, 0: off; with --merge on the merged ranking, the base device "
                   "of --config/--calibration)")
    _add_device_options(g)
    o = p.add_argument_group("outputs")
    o.add_argument("--output", help="the result JSON (with its provenance)")
    o.add_argument("--csv", help="the candidates' table (CSV)")
    o.add_argument("--plot", help="the Pareto front and sensitivity curves (PNG)")
    o.add_argument("--output-device", metavar="FILE",
                   help="the recommended device as a device YAML that every command takes "
                   "(--device FILE): the base device with the design's beads, sensor, "
                   "striker and plate (ssw.design.device_file)")
    o.add_argument("--output-device-rank", type=int, default=1, metavar="K",
                   help="with --output-device: the candidate of rank K instead (default 1: "
                   "the recommended)")
    add_device_options(p, walls=("fem",))
    add_json_flag(p)
    p.set_defaults(func=run, human=human)


def _add_device_options(g: argparse._ArgumentGroup) -> None:
    """The options of ``ssw design --space device`` alone: its budget (``--size``), the
    workflow's scatter and merge, the predicted measurement and the virtual prototype.

    Parameters
    ----------
    g : argparse._ArgumentGroup
        The command's group of the question.
    """
    g.add_argument("--size", type=int, metavar="N",
                   help="with --space device: about N evaluations (the scan grown to at "
                   "most 3/4 of N, the rest in bounded searches from the best devices: "
                   "ssw.design.device_search.sized; default: the config's design.device."
                   "size, else its space as stated)")
    g.add_argument("--part", metavar="I/N",
                   help="with --space device and --family: only the family's chains I, I+N, "
                   "... (the workflow's scatter; no plastic check, the merge strikes)")
    g.add_argument("--merge", nargs="+", metavar="JSON",
                   help="rank together the results of several ssw design runs (written "
                   "with --output) instead of computing")
    g.add_argument("--predict", action="store_true",
                   help="with --space device: the 95 %% interval of E that ssw measure "
                   "would report with the recommended and the base device, per hit and per "
                   "point of --point-hits hits, at the TOF and the features levels "
                   "(ssw identify's information, the calibration's covariance and model "
                   "error: ssw.design.predict)")
    g.add_argument("--point-hits", type=int, default=5, metavar="N",
                   help="with --predict: hits of one measured point (default 5)")
    g.add_argument("--objective", choices=("tof", "features"), default="tof",
                   help="with --space device: rank by the TOF's resolution (default) or by "
                   "the predicted interval of E per point at the features level among the "
                   "--objective-pool best devices of that ranking (implies --predict)")
    g.add_argument("--objective-pool", type=int, default=4, metavar="K",
                   help="with --objective features: devices predicted (default 4)")
    g.add_argument("--prototype", metavar="FOLDER",
                   help="with --space device: a virtual prototype of the recommended device "
                   "(its recordings in FOLDER): 3 reference and 4 unseen samples across the "
                   "range simulated (striker scatter, the DAQ's noise and filter), "
                   "calibrated and measured at the TOF level; the achieved errors and "
                   "interval widths beside the predicted (ssw.design.prototype)")
    g.add_argument("--striker-cov", type=float, default=0.01,
                   help="with --prototype: the striker speed's relative scatter from hit to "
                   "hit (default 0.01)")


def _spec(args: argparse.Namespace, ctx: Any) -> Any:
    """The :class:`ssw.design.spec.DesignSpec` of the command line and the config."""
    from ssw.design.spec import DesignSpec, parse_list, parse_range, spec_from_config
    from ssw.measure import sampling_uncertainty

    cfg, device = ctx.cfg, ctx.device
    rate = args.sample_rate if args.sample_rate is not None else float(
        cfg.get("daq", {}).get("sample_rate", 51200.0))
    if not rate > 0:
        raise ConfigError("--sample-rate", rate, "a sample rate > 0 S/s")
    if args.tof_scatter is not None:
        scatter, source = args.tof_scatter, "--tof-scatter"
    elif getattr(device, "tof_scatter", None) is not None:
        scatter = float(device.tof_scatter)
        source = f"device {device.name}: {device.tof_scatter_source or 'repeatability.tof_std'}"
    else:
        scatter, source = THESIS_TOF_SCATTER, THESIS_TOF_SCATTER_SOURCE
    fields: dict[str, Any] = {"tof_scatter": scatter, "tof_scatter_source": source,
                              "tof_sampling": sampling_uncertainty(rate), "sample_rate": rate}
    flags = {"materials": tuple(args.materials.split(",")) if args.materials else None,
             "thickness": parse_range(args.thickness, "--thickness") if args.thickness
             else None,
             "plate_diameters": parse_list(args.plate_diameters, "--plate-diameters") or None,
             "striker_velocities": parse_list(args.striker_velocities,
                                              "--striker-velocities") or None,
             "moduli": args.moduli, "soil_strength": args.soil_strength,
             "soil_strength_ratio": args.soil_strength_ratio,
             "soil_yield_limit": args.soil_yield_limit, "max_mass_ratio": args.max_mass_ratio,
             "hits": args.hits, "scan_points": args.scan_points,
             "thickness_tol": args.thickness_tol}
    fields.update({k: v for k, v in flags.items() if v is not None})
    if args.soil_range:
        if args.soil_E or args.soil_nu is not None:
            raise ConfigError("--soil-range", args.soil_range, "not with --soil-E/--soil-nu")
        return spec_from_config(cfg.get("design", {}), args.soil_range, **fields)
    if not args.soil_E or args.soil_nu is None:
        raise ConfigError("--soil-E/--soil-nu", (args.soil_E, args.soil_nu),
                          "a soil range LO:HI (Pa) and a Poisson's ratio, or --soil-range")
    design = cfg.get("design", {})
    for key in ("moduli", "log_step", "soil_strength", "soil_strength_ratio",
                "soil_yield_limit", "max_mass_ratio", "hits", "scan_points", "thickness_tol"):
        if design.get(key) is not None and key not in fields:
            fields[key] = design[key]
    return DesignSpec(soil_E=parse_range(args.soil_E, "--soil-E"), soil_nu=args.soil_nu,
                      **fields)


def run(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw design``: plates (material x thickness) or, with ``--space device``, whole devices
    designed for a soil range.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw design --help``).

    Returns
    -------
    dict of str to Any
        The design's JSON (:meth:`ssw.design.run.DesignResult.to_dict` or
        :meth:`ssw.design.device_search.DeviceDesignResult.to_dict`).

    Raises
    ------
    ssw.errors.ConfigError
        On flags that belong to the other design space.
    """
    if args.space == "device":
        return _run_device(args)
    from ssw.cli._device import chain_context
    from ssw.design.output import plot, write_table
    from ssw.design.run import merge_results, run_design

    if args.size is not None:
        raise ConfigError("--size", args.size, "with --space device (the plate design's "
                          "budget: --scan-points, --thickness-tol)")
    if args.predict or args.objective != "tof" or args.prototype:
        raise ConfigError("--predict/--objective/--prototype", args.objective,
                          "with --space device (the plate design's devices are the base "
                          "device's chain: ssw identify on it)")
    if args.merge and args.plastic_hits is not None:
        raise ConfigError("--plastic-hits", args.plastic_hits,
                          "not with --merge (it strikes the plates of one design run)")
    if args.merge:
        results = _load_results(args.merge)
        res = merge_results(results).to_dict()
        inputs = {"merge": list(args.merge),
                  "merged_inputs": [r.get("provenance", {}).get("inputs_sha256")
                                    for r in results]}
    else:
        from ssw.config import library

        ctx = chain_context(args, numerics_only=True)
        spec = _spec(args, ctx)
        mats = ctx.calibration.materials() if ctx.calibration is not None else library(ctx.cfg)
        contact = dict(ctx.cfg.get("contact", {}))
        res = run_design(spec, ctx.params, mats, contact, reference=not args.no_reference,
                         jobs=max(1, int(args.jobs)),
                         bead_material=ctx.device.bead_material).to_dict()
        if args.plastic_hits is not None:
            from ssw.design.hits_check import hits_check

            plates = [res["recommended"]]
            if res["reference"] is not None and (res["reference"]["material"],
                                                 res["reference"]["thickness"]) != (
                    res["recommended"]["material"], res["recommended"]["thickness"]):
                plates.append(res["reference"])
            res["plastic_check"] = [hits_check(spec, ctx.params, mats, c, args.plastic_hits)
                                    for c in plates]
        res.update({"device_name": ctx.device.name, "device_source": ctx.device.source,
                    "device_values": ctx.device.physics_dict(),
                    "calibration_file": None if ctx.calibration is None
                    else ctx.calibration.path, "wall": "fem"})
        inputs = {k: v for k, v in vars(args).items() if k not in ("func", "human", "json")}
        inputs["spec"] = res["spec"]
    _write(args, res, inputs, write_table, plot)
    _output_device(args, res)
    return res


def _families(items: list[str] | None) -> list[tuple[float, str]] | None:
    """``--family D:MATERIAL`` values -> (diameter, material) pairs."""
    if not items:
        return None
    out = []
    for it in items:
        d, _, m = it.partition(":")
        try:
            out.append((float(d), m))
        except ValueError as exc:
            raise ConfigError("--family", it, "D:MATERIAL (a bead diameter in m and a plate "
                              "material key)") from exc
        if not m:
            raise ConfigError("--family", it, "D:MATERIAL")
    return out


def _run_device(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw design --space device`` (:func:`ssw.design.device_search.run_device_design`)."""
    from ssw.cli._device import chain_context, contact_for_bead
    from ssw.config import library
    from ssw.design.device_search import run_device_design, with_plastic_check
    from ssw.design.device_spec import DeviceSpec
    from ssw.design.space import point_of, space_from_dict

    for flag, v in (("--materials", args.materials), ("--thickness", args.thickness)):
        if v:
            raise ConfigError(flag, v, "not with --space device (its space is the config's "
                              "design.device section)")
    if (args.family or args.part) and args.plastic_hits is not None:
        raise ConfigError("--plastic-hits", args.plastic_hits, "not with --family/--part "
                          "(the merge of the family runs strikes the finalists of all)")
    if args.merge and (args.family or args.part):
        raise ConfigError("--family/--part", args.family or args.part,
                          "not with --merge (the families' runs are merged whole)")
    if args.merge:
        from dataclasses import replace

        from ssw.design.device_search import merge_device_results

        merged = merge_device_results(_load_results(args.merge))
        if args.plastic_hits is not None:
            merged = replace(merged, spec=replace(merged.spec, plastic_hits=args.plastic_hits))
        if merged.spec.plastic_hits:
            base, mats = _merge_base(args, merged)
            merged = with_plastic_check(merged, base, mats, jobs=max(1, int(args.jobs)))
        res = merged.to_dict()
        _predict(args, res)
        _prototype(args, res)
        inputs = {"merge": list(args.merge), "plastic_hits": merged.spec.plastic_hits}
        _write_device(args, res, inputs)
        _output_device(args, res)
        return res
    ctx = chain_context(args, numerics_only=True)
    plate_spec = _spec(args, ctx)
    cfg, dev = ctx.cfg, ctx.device
    section = dict(cfg.get("design", {}).get("device") or {})
    p = ctx.params
    space = space_from_dict(section, p.plate_diameter / (2.0 * p.bead_radius))
    kw = {k: section[k] for k in ("moduli", "max_mass", "max_length", "finalists",
                                  "plate_yield_limit", "refine_evaluations", "phases",
                                  "noise_rms", "plastic_hits")
          if section.get(k) is not None}
    for key in ("moduli", "plastic_hits"):
        if getattr(args, key) is not None:
            kw[key] = getattr(args, key)
    if "noise_rms" not in kw:
        kw["noise_rms"] = float(cfg.get("daq", {}).get("simulation", {}).get("noise_rms", 0.05))
    spec = DeviceSpec(plate_spec.soil_E, plate_spec.soil_nu, soil_strength=plate_spec.soil_strength,
                      soil_strength_ratio=plate_spec.soil_strength_ratio,
                      soil_yield_limit=plate_spec.soil_yield_limit,
                      max_plate_mass_ratio=plate_spec.max_mass_ratio, hits=plate_spec.hits,
                      tof_scatter=plate_spec.tof_scatter,
                      tof_scatter_source=plate_spec.tof_scatter_source,
                      sample_rate=plate_spec.sample_rate, **kw)
    mats = ctx.calibration.materials() if ctx.calibration is not None else library(cfg)
    size = args.size if args.size is not None else section.get("size")
    if size is not None:
        from ssw.design.device_search import sized

        space, spec = sized(space, spec, size)
    ref = None if args.no_reference else point_of(p, dev.bead_material, dev.plate_material)
    families = _families(args.family)
    # the config's contact lengths are its device's bead's: scaled to the base device's
    result = run_device_design(space, spec, p, mats, contact_for_bead(cfg, p.bead_radius),
                               dev.full_scale_force, ref, jobs=max(1, int(args.jobs)),
                               families=families, parts=_part(args.part))
    if families is None and args.part is None:  # a family's or part's run: the merge strikes
        result = with_plastic_check(result, p, mats, jobs=max(1, int(args.jobs)))
    res = result.to_dict()
    res.update({"device_name": dev.name, "device_source": dev.source, "wall": "fem"})
    _predict(args, res, ctx)
    _prototype(args, res, ctx)
    inputs = {k: v for k, v in vars(args).items() if k not in ("func", "human", "json")}
    inputs["spec"] = res["spec"]
    inputs["space"] = res["space"]
    _write_device(args, res, inputs)
    _output_device(args, res, ctx)
    return res


def _predict(args: argparse.Namespace, res: dict[str, Any], ctx: Any = None) -> None:
    """``--predict``: the predicted measurement (:mod:`ssw.design.predict`) into ``res``
    (``prediction``), on the base device of ``ctx`` (default: that of ``--config``/
    ``--device``/``--calibration``)."""
    if not (args.predict or args.objective != "tof"):
        return
    if not args.point_hits >= 1:
        raise ConfigError("--point-hits", args.point_hits, "an integer >= 1")
    if not args.objective_pool >= 1:
        raise ConfigError("--objective-pool", args.objective_pool, "an integer >= 1")
    from ssw.cli._device import chain_context, contact_for_bead
    from ssw.config import library
    from ssw.daq.settings import settings_from_config
    from ssw.design.predict import (
        device_prediction,
        model_error_of,
        predicted_measurement,
        rank_by_level,
    )

    ctx = ctx if ctx is not None else chain_context(args, numerics_only=True)
    mats = ctx.calibration.materials() if ctx.calibration is not None else library(ctx.cfg)
    contact = contact_for_bead(ctx.cfg, ctx.params.bead_radius)
    settings = settings_from_config(ctx.cfg, ctx.device)
    kw = {"point_hits": args.point_hits, "calibration": ctx.calibration,
          "model_error": model_error_of(ctx.calibration)}
    if args.objective != "tof":
        rank_by_level(res, args.objective, args.objective_pool, lambda c: device_prediction(
            c, res["spec"], ctx.params, mats, contact, settings, **kw))
    res["prediction"] = predicted_measurement(res, ctx.params, mats, contact, settings, **kw)


def _prototype(args: argparse.Namespace, res: dict[str, Any], ctx: Any = None) -> None:
    """``--prototype FOLDER``: the recommended device simulated, calibrated and measured
    (:func:`ssw.design.prototype.run_prototype`) into ``res`` (``prototype``)."""
    if not args.prototype:
        return
    if not (args.striker_cov >= 0):
        raise ConfigError("--striker-cov", args.striker_cov, "a relative scatter >= 0")
    from ssw.chain.params import numerics_of
    from ssw.cli._device import chain_context, contact_for_bead
    from ssw.config import library
    from ssw.daq.settings import settings_from_config
    from ssw.design.device_file import designed_device
    from ssw.design.prototype import run_prototype

    ctx = ctx if ctx is not None else chain_context(args, numerics_only=True)
    cal = ctx.calibration
    mats = cal.materials() if cal is not None else library(ctx.cfg)
    numerics = dict(cal.numerics) if cal is not None else numerics_of(ctx.cfg)
    dev = designed_device(res, res["recommended"], ctx.device, mats, "prototype")
    res["prototype"] = run_prototype(
        dev, mats, numerics, {"contact": contact_for_bead(ctx.cfg, dev.bead_radius)},
        settings_from_config(ctx.cfg, dev), tuple(res["spec"]["soil_E"]),
        float(res["spec"]["soil_nu"]), args.prototype, striker_cov=args.striker_cov)


def _output_device(args: argparse.Namespace, res: dict[str, Any], ctx: Any = None) -> None:
    """``--output-device``: the candidate of rank ``--output-device-rank`` as a device YAML
    on the base device of ``ctx`` (default: that of ``--config``/``--device``/
    ``--calibration``) with the design's materials."""
    if not args.output_device:
        if args.output_device_rank != 1:
            raise ConfigError("--output-device-rank", args.output_device_rank,
                              "with --output-device FILE")
        return
    from ssw.cli._device import chain_context, contact_for_bead
    from ssw.config import library
    from ssw.design.device_file import write_designed_device

    ctx = ctx if ctx is not None else chain_context(args, numerics_only=True)
    mats = ctx.calibration.materials() if ctx.calibration is not None else library(ctx.cfg)
    write_designed_device(args.output_device, res, args.output_device_rank, ctx.device, mats,
                          contact=contact_for_bead(ctx.cfg, ctx.params.bead_radius),
                          base_radius=ctx.params.bead_radius)


def _merge_base(args: argparse.Namespace, merged: Any) -> tuple[Any, dict[str, Any]]:
    """The base chain and materials of ``--config``/``--calibration`` for the plastic check
    of merged results; ConfigError when that base device is not the merged runs' own."""
    from ssw.cli._device import chain_context
    from ssw.config import library
    from ssw.design.space import point_of

    ctx = chain_context(args, numerics_only=True)
    mats = ctx.calibration.materials() if ctx.calibration is not None else library(ctx.cfg)
    ref = merged.reference
    if ref is not None:
        mine = point_of(ctx.params, ctx.device.bead_material, ctx.device.plate_material)
        if mine.key != ref.point.key:
            raise ConfigError("--config/--calibration", mine.label(),
                              f"the base device of the merged runs ({ref.point.label()}): "
                              "the plastic check strikes the devices of their chain")
    return ctx.params, mats


def _part(text: str | None) -> tuple[int, int] | None:
    """``--part I/N`` -> (I, N)."""
    if text is None:
        return None
    i, _, n = text.partition("/")
    try:
        return int(i), int(n)
    except ValueError as exc:
        raise ConfigError("--part", text, "I/N: part I (0-based) of N") from exc


def _write_device(args: argparse.Namespace, res: dict[str, Any], inputs: Any) -> None:
    """The device design's JSON, CSV and figure, each atomically."""
    from ssw.design.device_output import plot, write_table

    _write(args, res, inputs, write_table, plot)


def _write(args: argparse.Namespace, res: dict[str, Any], inputs: Any, write_table: Any,
           plot: Any) -> None:
    """``--output`` (JSON), ``--csv`` and ``--plot`` of a result, each atomically."""
    from ssw.h5io import write_json

    if args.output:
        write_json(args.output, res, inputs)
    if args.csv:
        write_table(args.csv, res, inputs)
    if args.plot:
        plot(args.plot, res)


def _load_results(paths: list[str]) -> list[dict[str, Any]]:
    """The JSON results of ``--merge``; ConfigError naming an unreadable one."""
    import json

    results = []
    for path in paths:
        try:
            with open(path) as fh:
                results.append(json.load(fh))
        except (OSError, ValueError) as exc:
            raise ConfigError("--merge", path, f"a readable ssw design JSON ({exc})") from exc
    return results


def human(res: dict[str, Any]) -> str:
    """The ranking as a short table and the recommendation with its reasons.

    Parameters
    ----------
    res : dict of str to Any
        The result of :func:`run` (a plate design or, ``ssw_kind`` ``design_device``, a
        device design: :func:`ssw.design.device_output.human`).

    Returns
    -------
    str
        The text for the terminal (thickness in mm, the rest in SI units).
    """
    if res.get("ssw_kind") == "design_device":
        from ssw.design.device_output import human as device_human

        return device_human(res)
    rec = res["recommended"]
    lines = [f"soils {res['spec']['soil_E'][0]:.4g}-{res['spec']['soil_E'][1]:.4g} Pa, "
             f"nu {res['spec']['soil_nu']:g}; objective: {res['objective']}",
             f"{'material':10s} {'t (mm)':>8s} {'source':>9s} {'S worst':>8s} {'dE/E':>7s} "
             f"{'plate Y':>8s} {'soil Y':>8s} {'mass':>6s} feasible"]
    for c in res["candidates"][:25]:
        lines.append(f"{c['material']:10s} {c['thickness'] * 1e3:8.4g} {c['source']:>9s} "
                     f"{c['sensitivity']:8.4f} {c['resolution']:7.3g} "
                     f"{c['plate_yield_index']:8.3g} {c['soil_yield_index']:8.3g} "
                     f"{c['mass_ratio']:6.3g} {c['feasible']}")
    if len(res["candidates"]) > 25:
        lines.append(f"... {len(res['candidates']) - 25} more")
    lines.append(f"recommended: {rec['material']} {rec['thickness'] * 1e3:.4g} mm")
    lines += [f"  - {r}" for r in rec["reasons"]]
    if rec.get("validity"):
        lines.append("  checks failing on some soil of the range: "
                     + ("; ".join(rec["checks_failed"]) or "none"))
    lines.append(f"{res['evaluations']} candidates in {res['wall_time']:.1f} s")
    for chk in res.get("plastic_check") or []:
        tofs = ", ".join(f"{h['tof'] * 1e3:.4f}" for h in chk["hits"])
        lines.append(f"{len(chk['hits'])} hits through {chk['material']} "
                     f"{chk['thickness'] * 1e3:.4g} mm on E {chk['soil_E']:.4g} Pa (von Mises "
                     f"Y {chk['yield_stress']:.3g} Pa, elastic index "
                     f"{chk['elastic_soil_yield_index']:.3g}): TOF {tofs} ms, set "
                     f"{chk['hits'][-1]['permanent_set'] * 1e6:.3g} um, TOF std "
                     f"{chk['tof_std']:.3g} s")
    return "\n".join(lines)
