"""``ssw acquire`` (one sample session, real or simulated) and ``ssw tof-recording``."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from ssw.cli import add_json_flag
from ssw.cli._device import add_device_options
from ssw.errors import ConfigError, SswError


def add_recording_options(p: argparse.ArgumentParser) -> None:
    """Flags of every command that reads recordings (.h5, .csv, .tdms, .mat).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser (the options are added to it).
    """
    p.add_argument("--units", help="unit of data columns/channels whose file gives none: "
                   "N, kN, lbf (force) or V, mV (sensor voltage, with --sensitivity)")
    p.add_argument("--sensitivity", type=float, help="data in volts: sensor sensitivity, V/N")
    p.add_argument("--sample-rate", type=float,
                   help="files without a time axis (no time column, no wf_increment): S/s")
    p.add_argument("--clipped", choices=["raise", "drop", "keep"], default="raise",
                   help="clipped hits: error (default), drop them, or keep them")


def read_options(args: argparse.Namespace) -> dict[str, Any]:
    """Keyword options of :func:`ssw.daq.importers.read_any` from those flags.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (the options of :func:`add_recording_options`).

    Returns
    -------
    dict of str to Any
        ``clipped`` and those of ``units``, ``sensitivity`` (V/N) and ``sample_rate`` (S/s)
        given.
    """
    opts: dict[str, Any] = {"clipped": args.clipped}
    for key in ("units", "sensitivity", "sample_rate"):
        if getattr(args, key, None) is not None:
            opts[key] = getattr(args, key)
    return opts


def add_tof_options(p: argparse.ArgumentParser) -> None:
    """Flags of the TOF picking (:class:`ssw.signal.tof.TofOptions`).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser (the options are added to it).
    """
    from ssw.signal.peaks import UPSAMPLE

    p.add_argument("--lowpass", type=float, help="zero-phase low-pass cutoff, Hz (default none)")
    p.add_argument("--min-hits", type=int, default=3,
                   help="accepted hits a recording needs (below 3 the TOF scatter is not "
                   "estimable)")
    p.add_argument("--upsample", type=int, default=UPSAMPLE,
                   help=f"band-limited interpolation before the parabolic vertex (default "
                   f"{UPSAMPLE}; 1: parabola on the samples)")
    p.add_argument("--min-tof", type=float,
                   help="shortest physical TOF, s (default: from the chain of --config: "
                   "sensor -> wall -> sensor at the fastest solitary wave speed)")
    p.add_argument("--no-bound", action="store_true",
                   help="no physical TOF bound (a record of an unknown device)")


def tof_options(args: argparse.Namespace, params: Any = None) -> Any:
    """:class:`ssw.signal.tof.TofOptions` from the flags; ``params`` (ChainParams) gives the
    physical bound (:class:`ssw.signal.tof.ChainPath`) unless ``--no-bound``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (the options of :func:`add_tof_options`).
    params : ssw.chain.params.ChainParams or None
        The chain whose shortest round trip bounds the TOF; None: no chain bound.

    Returns
    -------
    ssw.signal.tof.TofOptions
        The options (cutoff in Hz, shortest TOF in s).
    """
    from ssw.signal.tof import ChainPath, TofOptions

    bound = not getattr(args, "no_bound", False)
    return TofOptions(
        lowpass=getattr(args, "lowpass", None), min_hits=getattr(args, "min_hits", 3),
        upsample=getattr(args, "upsample", TofOptions.upsample),
        min_tof=getattr(args, "min_tof", None) if bound else None,
        chain=ChainPath.from_params(params) if bound and params is not None else None,
    )


def format_hit(r: Any) -> str:
    """One line per hit (a :class:`ssw.signal.live.HitReport`) for the person at the bench.

    Parameters
    ----------
    r : ssw.signal.live.HitReport
        The hit's report.

    Returns
    -------
    str
        The hit's TOF (ms) or why it was rejected, the running mean (ms) and SEM (us), and
        the running E estimate (MPa) when there is one.
    """
    head = f"hit {r.index + 1}: " + (f"TOF {r.tof * 1e3:.4f} ms" if r.tof is not None
                                     else f"rejected ({r.reason})")
    if r.tof_mean is None:
        return head
    line = f"{head} | mean {r.tof_mean * 1e3:.4f} ms"
    if r.n_accepted > 1:
        line += f" +- {r.tof_sem * 1e6:.2f} us (SEM)"
    line += f", {r.n_accepted} of {r.n_hits} hits"
    if r.estimate is not None:
        e = r.estimate
        line += f" | E {e['E'] / 1e6:.1f} MPa [{e['E_low'] / 1e6:.1f}, {e['E_high'] / 1e6:.1f}]"
    elif r.estimate_error:
        line += f" | E: {r.estimate_error}"
    return line


def run_acquire(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw acquire``: one sample session (N hits) recorded with an NI 9234, or simulated.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw acquire --help``).

    Returns
    -------
    dict of str to Any
        The recording written and its TOF (mean, std, COV, per hit; s).

    Raises
    ------
    ssw.errors.ConfigError
        When the analytic source has no ``--tof``, or the soil is neither a
        library material nor given by ``--soil-E`` and ``--soil-nu``.
    """
    from ssw.cli._device import chain_context
    from ssw.config import library
    from ssw.daq.backend import get_backend, run_session
    from ssw.daq.recording import read_recording
    from ssw.daq.settings import settings_from_config
    from ssw.measure import parse_nu, sampling_uncertainty
    from ssw.modulus import Estimator
    from ssw.signal.live import LiveTof
    from ssw.signal.tof import recording_tof

    ctx = chain_context(args)
    cfg = ctx.cfg
    if args.striker_velocity_cov is not None:
        cfg["daq"]["simulation"]["striker_velocity_cov"] = args.striker_velocity_cov
    settings = settings_from_config(cfg, ctx.device, hits=args.hits,
                                    sample_rate=args.sample_rate, trigger_mode=args.trigger)
    params, wall, wall_opts = ctx.params, ctx.wall, ctx.wall_options
    info: dict[str, Any] = {**ctx.inputs()}
    nu: Any = None if args.soil_nu is None else parse_nu(args.soil_nu)
    if args.simulate:
        from ssw.daq.simulated import analytic_waveform

        seed = cfg.get("seed", 0) if args.seed is None else args.seed
        if settings.simulation.source == "analytic" or args.tof is not None:
            if args.tof is None:
                raise ConfigError("--tof", None, "a TOF in s for the analytic source")
            backend = get_backend("simulated", waveform=analytic_waveform(args.tof), seed=seed,
                                  true_tof=args.tof)
        else:
            if args.material:
                mats = library(cfg)
                if args.material not in mats:
                    raise ConfigError("--material", args.material, f"one of {sorted(mats)}")
                E, nu_sim = mats[args.material].E, mats[args.material].nu
                nu = nu if nu is not None else nu_sim
            elif args.soil_E is not None and isinstance(nu, float):
                E, nu_sim = args.soil_E, nu
            else:
                raise ConfigError("--material", None, "a material key or --soil-E and --soil-nu "
                                  "(one value) for a simulated session")
            backend = get_backend("simulated", soil_E=E, soil_nu=nu_sim, chain_params=params,
                                  wall=wall, wall_options=wall_opts, seed=seed)
            info.update({"soil_E": E, "soil_nu": nu_sim})
    else:
        backend = get_backend("nidaqmx")
    opts = tof_options(args, params)
    on_hit = None
    if not args.json:  # one line per hit on stderr for the person at the bench
        import sys

        estimate = None
        if nu is not None and args.tof is None:
            try:
                estimate = Estimator(
                    params, wall, wall_opts, np.asarray(nu, float),
                    calibration=ctx.calibration,
                    extra={"sampling": sampling_uncertainty(settings.sample_rate)})
            except (SswError, OSError) as exc:
                print(f"E per hit unavailable: {exc}", file=sys.stderr)
        live = LiveTof(settings.sample_rate, settings.pretrigger_samples, opts, estimate)

        def on_hit(i: int, hit: Any) -> None:
            print(format_hit(live(i, hit)), file=sys.stderr, flush=True)

    path = run_session(backend, settings, args.output, sample_id=args.sample,
                       plate=args.plate, operator=args.operator, synthetic=args.simulate,
                       notes=args.notes, overwrite=args.overwrite, on_hit=on_hit)
    res = recording_tof(read_recording(path, clipped="drop"), opts)
    out = {"output": str(path), "backend": backend.name, "sample_id": args.sample,
           "hits": settings.hits, **info, **res.to_dict()}
    if str(path) != str(args.output):
        out["note"] = (f"{args.output} already holds a recording (kept): this session is "
                       f"{path} (--overwrite replaces it once the first new hit is on disk)")
    if getattr(backend, "true_tof", None) is not None:
        out["true_tof"] = backend.true_tof
    return out


def run_tof_recording(args: argparse.Namespace) -> dict[str, Any]:
    """``ssw tof-recording``: the TOF (mean, std, COV, per hit) of a recording.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw tof-recording --help``).

    Returns
    -------
    dict of str to Any
        The file, its metadata, the TOF result (s) and the hits dropped.
    """
    from ssw.cli._device import chain_context
    from ssw.daq.importers import read_any
    from ssw.signal.tof import recording_tof

    ctx = chain_context(args, numerics_only=True)
    params = None if args.no_bound else ctx.params
    rec = read_any(args.file, **read_options(args), full_scale=ctx.device.full_scale_force)
    opts = tof_options(args, params)
    res = recording_tof(rec, opts)
    meta = {k: rec.meta.get(k) for k in ("sample_id", "plate", "operator", "synthetic",
                                         "backend", "complete", "device", "channel", "format",
                                         "layout") if k in rec.meta}
    bound = opts.bound(float(np.nanmax(res.f_incident))) if np.any(res.accepted) else None
    return {"file": args.file, **meta, **res.to_dict(), "dropped": list(rec.dropped),
            "n_dropped": len(rec.dropped), "min_tof": bound}


def _human_tof(r: dict[str, Any]) -> str:
    dropped = r.get("n_dropped", 0)
    lines = [f"{r.get('file', r.get('output'))}: {r['n_accepted']} of "
             f"{r['n_hits'] + dropped} hits accepted"
             + (f" ({dropped} dropped on reading)" if dropped else ""),
             f"TOF mean {r['tof_mean'] * 1e3:.5f} ms, std {r['tof_std'] * 1e6:.3f} us, "
             f"COV {r['tof_cov_pct']:.3f} %"]
    if "true_tof" in r:
        lines.append(f"simulated wave's TOF {r['true_tof'] * 1e3:.5f} ms")
    lines += [f"rejected: {x}" for x in [*r.get("dropped", []), *r["rejections"]]]
    return "\n".join(lines)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw acquire``, ``ssw tof-recording`` subcommands to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser(
        "acquire", help="record one sample session (N hits) with an NI 9234, or simulate it",
        description="One finite reference-triggered record per hit, written to one HDF5 "
        "file flushed after every hit. Without --simulate the NI-DAQmx driver and the "
        "module must be present.")
    p.add_argument("--sample", required=True, help="sample id (e.g. PCF15)")
    p.add_argument("--output", required=True, help="session HDF5 file to create")
    p.add_argument("--hits", type=int, help="hits (default: config daq.hits)")
    p.add_argument("--sample-rate", type=float, help="S/s, 51200/n (default: config)")
    p.add_argument("--plate", default="PLA 0.4 mm", help="plate under the last bead")
    p.add_argument("--operator", default="", help="who recorded")
    p.add_argument("--notes", default="", help="free text stored with the session")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing file (when the first new hit is on disk; "
                   "without it, a new session never touches an existing file: it goes to "
                   "the next free name, FILE-2.h5, ...)")
    p.add_argument("--simulate", action="store_true",
                   help="simulated backend (chain model through a modelled NI 9234)")
    p.add_argument("--material", help="simulate: material key giving E and nu")
    p.add_argument("--soil-E", type=float, help="simulate: soil modulus, Pa")
    p.add_argument("--soil-nu", metavar="NU|LO:HI", help="the medium's Poisson's ratio "
                   "(simulate; and the running E printed after each hit: NU or a range LO:HI)")
    p.add_argument("--tof", type=float, help="simulate: two analytic pulses this TOF apart, s")
    p.add_argument("--seed", type=int, help="simulate: RNG seed (default: config seed)")
    p.add_argument("--striker-velocity-cov", type=float,
                   help="simulate: relative std of the striker speed hit to hit "
                   "(default: config daq.simulation.striker_velocity_cov)")
    p.add_argument("--trigger", choices=["auto", "hardware", "software"],
                   help="hardware: the module's analog reference trigger; software: "
                   "continuous acquisition cut by the same rule; auto (default): hardware "
                   "where the module supports it")
    add_device_options(p)
    add_tof_options(p)
    add_json_flag(p)
    p.set_defaults(func=run_acquire, human=_human_tof)

    p = sub.add_parser(
        "tof-recording", help="TOF (mean, std, COV, per hit) of a recording",
        description="Incident/reflected peaks per hit (band-limited upsampling, parabolic "
        "vertex; the reflected peak only after the shortest physical round trip), the hit "
        "rejection rule, statistics. Reads .h5 sessions, .csv (units in the header: "
        "time_s,force_N or 'force [N]'), .tdms (NI waveform channels) and .mat.")
    p.add_argument("file", help="recording (.h5, .csv, .tdms, .mat)")
    add_device_options(p)
    add_recording_options(p)
    add_tof_options(p)
    add_json_flag(p)
    p.set_defaults(func=run_tof_recording, human=_human_tof)
