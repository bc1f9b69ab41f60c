"""``ssw acquire`` (one sample session, real or simulated) and ``ssw tof-recording``."""

from __future__ import annotations

import argparse
from typing import Any

from ssw.cli import add_json_flag
from ssw.errors import ConfigError

DEFAULT_K_TABLE = "results/fit/k_table.h5"


def wall_of(args: argparse.Namespace, cfg: dict[str, Any]) -> tuple[str, dict[str, Any]]:
    """The chain's last-contact law and options from ``--wall/--K/--k-table`` or the config."""
    wall = args.wall or cfg.get("chain", {}).get("wall_law", "hertz")
    if wall == "fit":
        if args.K is not None:
            return wall, {"K": args.K}
        return wall, {"k_table": args.k_table or DEFAULT_K_TABLE}
    if wall == "table":
        raise ConfigError("--wall", wall, "rigid | hertz | fit here (table needs one FEM "
                          "curve per soil E)")
    return wall, {}


def add_wall_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--wall", choices=["rigid", "hertz", "fit"],
                   help="chain last-contact law (default: the config's chain.wall_law)")
    p.add_argument("--K", type=float, help="fit wall: a constant K instead of the K table")
    p.add_argument("--k-table", help=f"fit wall: K table HDF5 (default {DEFAULT_K_TABLE})")


def _tof_options(lowpass: float | None, min_hits: int = 1) -> Any:
    from ssw.signal.tof import TofOptions

    return TofOptions(lowpass=lowpass, min_hits=min_hits)


def run_acquire(args: argparse.Namespace) -> dict[str, Any]:
    from ssw.config import library, load_config
    from ssw.daq.backend import get_backend, run_session
    from ssw.daq.recording import read_recording
    from ssw.daq.settings import settings_from_config
    from ssw.signal.tof import recording_tof

    cfg = load_config(args.config)
    if args.striker_velocity_cov is not None:
        cfg["daq"]["simulation"]["striker_velocity_cov"] = args.striker_velocity_cov
    settings = settings_from_config(cfg, hits=args.hits, sample_rate=args.sample_rate)
    info: dict[str, Any] = {}
    if args.simulate:
        from ssw.daq.simulated import analytic_waveform

        seed = cfg.get("seed", 0) if args.seed is None else args.seed
        if settings.simulation.source == "analytic" or args.tof is not None:
            if args.tof is None:
                raise ConfigError("--tof", None, "a TOF in s for the analytic source")
            backend = get_backend("simulated", waveform=analytic_waveform(args.tof), seed=seed,
                                  true_tof=args.tof)
        else:
            from ssw.chain.params import ChainParams

            if args.material:
                mats = library(cfg)
                if args.material not in mats:
                    raise ConfigError("--material", args.material, f"one of {sorted(mats)}")
                E, nu = mats[args.material].E, mats[args.material].nu
            elif args.soil_E is not None and args.soil_nu is not None:
                E, nu = args.soil_E, args.soil_nu
            else:
                raise ConfigError("--material", None, "a material key or --soil-E and --soil-nu "
                                  "for a simulated session")
            wall, opts = wall_of(args, cfg)
            backend = get_backend("simulated", soil_E=E, soil_nu=nu,
                                  chain_params=ChainParams.from_config(cfg), wall=wall,
                                  wall_options=opts, seed=seed)
            info = {"soil_E": E, "soil_nu": nu, "wall": wall}
    else:
        backend = get_backend("nidaqmx")
    path = run_session(backend, settings, args.output, sample_id=args.sample,
                       plate=args.plate, operator=args.operator, synthetic=args.simulate,
                       notes=args.notes, overwrite=args.overwrite)
    res = recording_tof(read_recording(path, clipped="drop"))
    out = {"output": str(path), "backend": backend.name, "sample_id": args.sample,
           "hits": settings.hits, **info, **res.to_dict()}
    if getattr(backend, "true_tof", None) is not None:
        out["true_tof"] = backend.true_tof
    return out


def run_tof_recording(args: argparse.Namespace) -> dict[str, Any]:
    from ssw.daq.importers import read_any
    from ssw.signal.tof import recording_tof

    opts = {}
    if args.sensitivity is not None:
        opts["sensitivity"] = args.sensitivity
    if args.sample_rate is not None:
        opts["sample_rate"] = args.sample_rate
    rec = read_any(args.file, clipped=args.clipped, **opts)
    res = recording_tof(rec, _tof_options(args.lowpass, args.min_hits))
    meta = {k: rec.meta.get(k) for k in ("sample_id", "plate", "operator", "synthetic",
                                         "backend", "complete", "device", "channel")
            if k in rec.meta}
    return {"file": args.file, **meta, **res.to_dict(), "dropped": list(rec.dropped)}


def _human_tof(r: dict[str, Any]) -> str:
    lines = [f"{r.get('file', r.get('output'))}: {r['n_accepted']} of {r['n_hits']} hits "
             f"accepted",
             f"TOF mean {r['tof_mean'] * 1e3:.5f} ms, std {r['tof_std'] * 1e6:.3f} us, "
             f"COV {r['tof_cov_pct']:.3f} %"]
    if "true_tof" in r:
        lines.append(f"simulated wave's TOF {r['true_tof'] * 1e3:.5f} ms")
    lines += [f"rejected: {x}" for x in r["rejections"]]
    return "\n".join(lines)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "acquire", help="record one sample session (N hits) with an NI 9234, or simulate it",
        description="One finite reference-triggered record per hit, written to one HDF5 "
        "file flushed after every hit. Without --simulate the NI-DAQmx driver and the "
        "module must be present.")
    p.add_argument("--config", help="study config YAML (default config/config.yaml)")
    p.add_argument("--sample", required=True, help="sample id (e.g. PCF15)")
    p.add_argument("--output", required=True, help="session HDF5 file to create")
    p.add_argument("--hits", type=int, help="hits (default: config daq.hits)")
    p.add_argument("--sample-rate", type=float, help="S/s, 51200/n (default: config)")
    p.add_argument("--plate", default="PLA 0.4 mm", help="plate under the last bead")
    p.add_argument("--operator", default="", help="who recorded")
    p.add_argument("--notes", default="", help="free text stored with the session")
    p.add_argument("--overwrite", action="store_true", help="replace an existing file")
    p.add_argument("--simulate", action="store_true",
                   help="simulated backend (chain model through a modelled NI 9234)")
    p.add_argument("--material", help="simulate: material key giving E and nu")
    p.add_argument("--soil-E", type=float, help="simulate: soil modulus, Pa")
    p.add_argument("--soil-nu", type=float, help="simulate: soil Poisson's ratio")
    p.add_argument("--tof", type=float, help="simulate: two analytic pulses this TOF apart, s")
    p.add_argument("--seed", type=int, help="simulate: RNG seed (default: config seed)")
    p.add_argument("--striker-velocity-cov", type=float,
                   help="simulate: relative std of the striker speed hit to hit "
                   "(default: config daq.simulation.striker_velocity_cov)")
    add_wall_options(p)
    add_json_flag(p)
    p.set_defaults(func=run_acquire, human=_human_tof)

    p = sub.add_parser(
        "tof-recording", help="TOF (mean, std, COV, per hit) of a recording",
        description="Incident/reflected peaks with parabolic interpolation per hit, the "
        "hit rejection rule, statistics. Reads .h5 sessions, .csv and .mat.")
    p.add_argument("file", help="recording (.h5, .csv, .mat)")
    p.add_argument("--lowpass", type=float, help="zero-phase low-pass cutoff, Hz (default none)")
    p.add_argument("--min-hits", type=int, default=1, help="accepted hits needed")
    p.add_argument("--clipped", choices=["raise", "drop", "keep"], default="raise",
                   help="clipped hits: error (default), drop them, or keep them")
    p.add_argument("--sensitivity", type=float, help="CSV/MAT in volts: sensor V/N")
    p.add_argument("--sample-rate", type=float, help="CSV without a time column: S/s")
    add_json_flag(p)
    p.set_defaults(func=run_tof_recording, human=_human_tof)
