"""``ssw bench design``: the cost of a whole plate design (ssw.design).

For each soil range (default: the thesis's soils, 10-100 and 100-1000 MPa, nu 0.3), the
design over ``--materials`` (default PLA, Al 6061-T6, A36) x continuous thickness x
``--moduli`` soil moduli (default 20) is run twice with ``--jobs`` processes (default 2):

* ``cold``: with an empty operator cache (a fresh ``SSW_CACHE_DIR``): every plate thickness
  the search visits is meshed and condensed;
* ``warm``: again, the operators on disk (a repeated or extended design; what the workflow's
  reruns pay).

Reports the wall time of each, the candidates evaluated, the seconds per candidate, and the
recommended plate. Writes ``design_bench.csv`` and ``design_bench.json`` under the output
folder.

``--space device --sizes 100,1000,10000`` times the whole device design instead
(:mod:`ssw.design.device_search`): for each size N, ``ssw design --space device --size N``
on the 20-200 MPa soils at nu 0.3 with ``--jobs`` processes and ``--config``'s device space
(:func:`device_argv`; the scan grown to about 3/4 of N, the rest in bounded searches from
the best devices), with wall and CPU time (this process and its workers), candidates per
second, CPU per candidate and the recommended device. Writes ``design_device_bench.csv``
and ``.json``.

Measured (2 cores, 43 candidates a range): 38-45 s a range with the operators cached on a
quiet machine (``ssw design --soil-range soft|stiff --jobs 2``), 43-66 s cold or warm with
the cores shared (load 2), 55-86 s at load 3.3. A candidate costs 1-1.4 s: the chain's 60
scenes on the fem wall, a mesh of the new plate and the factorization of its two bodies for
the stresses; cached operators save the condensation only (0.3 s).
"""

from __future__ import annotations

import argparse
import csv
import io
import os
import tempfile
import time
from pathlib import Path
from typing import Any

from ssw.h5io import write_csv_text, write_json

#: Soil ranges timed by default: (name, lo Pa, hi Pa, nu).
RANGES = (("soft", 10e6, 100e6, 0.3), ("stiff", 100e6, 1000e6, 0.3))


def register(kinds: argparse._SubParsersAction) -> None:
    """Add the ``ssw bench design`` command and its options.

    Parameters
    ----------
    kinds : argparse._SubParsersAction
        The ``ssw bench`` subcommands.
    """
    from ssw.design.spec import MATERIALS, MODULI

    p = kinds.add_parser("design", help="wall time of a whole plate design (ssw design)")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    p.add_argument("--materials", default=",".join(MATERIALS),
                   help="plate materials, comma-separated")
    p.add_argument("--moduli", type=int, default=MODULI, help="soil moduli per range")
    p.add_argument("--jobs", type=int, default=2, help="processes (one material each)")
    p.add_argument("--ranges", nargs="+", default=[r[0] for r in RANGES],
                   choices=[r[0] for r in RANGES], help="soil ranges timed")
    p.add_argument("--no-cold", action="store_true",
                   help="time the warm run only (the operators of this machine's cache)")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--space", choices=("plate", "device"), default="plate",
                   help="time the plate design (default) or the device design's evaluation")
    p.add_argument("--sizes", default="100,1000,10000",
                   help="with --space device: candidates per run, comma-separated")
    p.set_defaults(func=run, human=human)


def _design(spec: Any, params: Any, mats: Any, contact: Any, jobs: int) -> tuple[float, Any]:
    from ssw.contact import stress
    from ssw.design.run import run_design

    stress._FIELDS.clear()  # the stress fields of the last run are not kept across runs
    t0 = time.perf_counter()
    res = run_design(spec, params, mats, contact, jobs=jobs)
    return time.perf_counter() - t0, res


#: The device design timed by ``--space device``: ``ssw design`` on these soils (Pa, -).
DEVICE_SOILS = ("20e6:200e6", "0.3")


def device_argv(config: str, size: int, jobs: int) -> list[str]:
    """The ``ssw design`` command line timed by ``--space device`` for one size.

    Parameters
    ----------
    config : str
        The study config (its ``design.device`` space; default space without one).
    size : int
        ``--size``: about this many evaluations.
    jobs : int
        ``--jobs``: processes.

    Returns
    -------
    list of str
        ``design --space device --config CONFIG --calibration none --soil-E 20e6:200e6
        --soil-nu 0.3 --size SIZE --jobs JOBS`` (the arguments after ``ssw``).
    """
    return ["design", "--space", "device", "--config", config, "--calibration", "none",
            "--soil-E", DEVICE_SOILS[0], "--soil-nu", DEVICE_SOILS[1], "--size", str(size),
            "--jobs", str(jobs)]


def run_device(args: argparse.Namespace) -> dict[str, Any]:
    """``--space device``: the whole device design (``ssw design --space device --size N``,
    :func:`device_argv`) at each size, timed in this process.

    Parameters
    ----------
    args : argparse.Namespace
        The command's options (:func:`register`).

    Returns
    -------
    dict
        Per size: candidates evaluated (scan, search), searches, wall and CPU time (s, this
        process and its workers), candidates per s, CPU s per candidate, the recommended
        device, its worst-case resolution dE/E (-) and the feasible devices; and the files
        written (``design_device_bench.csv``, ``.json``).
    """
    from ssw.cli import build_parser
    from ssw.design.device_search import cpu_time
    from ssw.design.spec import parse_list

    rows = []
    for n in (int(x) for x in parse_list(args.sizes, "--sizes")):
        argv = device_argv(args.config, n, args.jobs)
        ns = build_parser(argv).parse_args(argv)
        t0, c0 = time.perf_counter(), cpu_time()
        res = ns.func(ns)
        wall, cpu = time.perf_counter() - t0, cpu_time() - c0
        done = int(res["evaluations"])
        rec = res["recommended"]
        rows.append({"size": n, "candidates": done,
                     "scanned": sum(c["source"] == "scan" for c in res["candidates"]),
                     "searches": len(res["searches"]), "jobs": args.jobs,
                     "wall_time": wall, "cpu_time": cpu, "candidates_per_s": done / wall,
                     "cpu_per_candidate": cpu / done, "recommended": rec["label"],
                     "resolution": rec["resolution"], "feasible": res["feasible"],
                     "loadavg": " ".join(Path("/proc/loadavg").read_text().split()[:3])
                     if Path("/proc/loadavg").exists() else ""})
    return _write_rows(Path(args.output_dir), "design_device_bench",
                       "ssw bench design --space device", args.config, rows)


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Run ``ssw bench design`` (module docstring) and write its outputs under
    ``--output-dir`` (``--space device``: :func:`run_device`).

    Parameters
    ----------
    args : argparse.Namespace
        The command's options (:func:`register`).

    Returns
    -------
    dict
        Per soil range and cache state: candidates, wall time (s), s per candidate and
        the recommended plate; and the files written (``design_bench.csv``, ``.json``).
    """
    if args.space == "device":
        return run_device(args)
    from ssw.chain.params import chain_params, numerics_of
    from ssw.config import device_of, library, load_config
    from ssw.design.spec import DesignSpec
    from ssw.measure import sampling_uncertainty

    cfg = load_config(args.config)
    mats = library(cfg)
    device = device_of(cfg)
    params = chain_params(device, mats, **numerics_of(cfg))
    contact = dict(cfg.get("contact", {}))
    rate = float(cfg.get("daq", {}).get("sample_rate", 51200.0))
    rows = []
    old = os.environ.get("SSW_CACHE_DIR")
    for name, lo, hi, nu in (r for r in RANGES if r[0] in args.ranges):
        spec = DesignSpec(soil_E=(lo, hi), soil_nu=nu, materials=tuple(args.materials.split(",")),
                          moduli=args.moduli, tof_scatter=device.tof_scatter or 1.53e-5,
                          tof_scatter_source="device", tof_sampling=sampling_uncertainty(rate),
                          sample_rate=rate)
        runs = []
        with tempfile.TemporaryDirectory(prefix="ssw-bench-design-") as tmp:
            if not args.no_cold:
                os.environ["SSW_CACHE_DIR"] = tmp
                runs.append(("cold", *_design(spec, params, mats, contact, args.jobs)))
            runs.append(("warm", *_design(spec, params, mats, contact, args.jobs)))
            if old is None:
                os.environ.pop("SSW_CACHE_DIR", None)
            else:
                os.environ["SSW_CACHE_DIR"] = old
        for cache, wall, res in runs:
            rec = res.ranking.recommended
            n = len(res.ranking.candidates)
            rows.append({"range": name, "soil_E_lo": lo, "soil_E_hi": hi, "soil_nu": nu,
                         "cache": cache, "materials": len(spec.materials),
                         "moduli": spec.moduli, "jobs": args.jobs, "candidates": n,
                         "wall_time": wall, "time_per_candidate": wall / n,
                         "recommended": f"{rec.material} {rec.thickness:.6g}",
                         "sensitivity": rec.sensitivity,
                         "soil_yield_index": rec.soil_yield_index,
                         "plate_yield_index": rec.plate_yield_index})
    return _write_rows(Path(args.output_dir), "design_bench", "ssw bench design",
                       args.config, rows)


def _write_rows(out: Path, stem: str, command: str, config: str,
                rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The benchmark's rows as ``out/stem.csv`` and ``out/stem.json`` (atomically, with
    their provenance).

    Parameters
    ----------
    out : pathlib.Path
        The output folder.
    stem : str
        The files' name without suffix.
    command : str
        The benchmark's command, recorded.
    config : str
        The study config it ran.
    rows : list of dict
        One row per measured size (the same keys each).

    Returns
    -------
    dict
        The JSON's content.
    """
    result = {"command": command, "config": config, "rows": rows,
              "cpu_count": os.cpu_count(),
              "outputs": [str(out / f"{stem}.{x}") for x in ("csv", "json")]}
    keys = list(rows[0])
    text = io.StringIO()  # a field with a comma (a device's label) quoted
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(keys)
    writer.writerows([[str(r[k]) for k in keys] for r in rows])
    write_csv_text(out / f"{stem}.csv", text.getvalue(), result)
    write_json(out / f"{stem}.json", result, result)
    return result


def human(result: dict[str, Any]) -> str:
    """The result of :func:`run` as text for the terminal.

    Parameters
    ----------
    result : dict
        The result of :func:`run`.

    Returns
    -------
    str
        One line per measurement.
    """
    if result["command"].endswith("--space device"):
        lines = [f"{'size':>6s} {'cands':>6s} {'wall s':>8s} {'CPU s':>8s} {'cand/s':>7s} "
                 f"{'CPU s/cand':>10s} {'dE/E':>7s}  recommended  (load)"]
        for r in result["rows"]:
            lines.append(f"{r['size']:6d} {r['candidates']:6d} {r['wall_time']:8.1f} "
                         f"{r['cpu_time']:8.1f} {r['candidates_per_s']:7.2f} "
                         f"{r['cpu_per_candidate']:10.4f} {r['resolution']:7.4f}  "
                         f"{r['recommended']}  ({r['loadavg']})")
        return "\n".join(lines)
    lines = [f"{'range':6s} {'cache':5s} {'cands':>5s} {'wall s':>7s} {'s/cand':>7s}  recommended"]
    for r in result["rows"]:
        lines.append(f"{r['range']:6s} {r['cache']:5s} {r['candidates']:5d} "
                     f"{r['wall_time']:7.1f} {r['time_per_candidate']:7.2f}  {r['recommended']}"
                     f" (S {r['sensitivity']:.4f}, soil Y {r['soil_yield_index']:.3g}, "
                     f"plate Y {r['plate_yield_index']:.3g})")
    return "\n".join(lines)
