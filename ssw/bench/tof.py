"""``ssw bench tof``: TOF error and cost of the simulated NI 9234 + peak picking vs rate.

For each NI 9234 rate ``51200/n`` and each control foam, ``--hits`` simulated hits are
recorded (random sample phase, jitter, noise, 24-bit quantization) and their TOF extracted
with each ``--upsample`` factor (1: the parabola on the samples; 16: band-limited x16
interpolation first, the default of ssw.signal). Sources of known TOF:

* ``chain`` (default): the chain's sensor force (Hertz wall unless ``--wall``); truth is the
  chain's own TOF on its integration grid (``ssw.tof.api.tof``);
* ``analytic``: two symmetric sech^2 pulses, the reflected one broader (widths
  ``ANALYTIC_WIDTHS``), at the thesis's measured TOF of each foam; truth is exact (a
  linear-phase filter delays a symmetric pulse's peak by its group delay, the same for both).

Reports the largest and mean (bias) error in seconds and in sample periods (the round-trip
tolerance is half a sample), and the wall time per hit of simulation and of extraction.
Writes ``tof_work_precision.csv`` and ``.png`` under the output folder.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from ssw.h5io import atomic_write_text
from ssw.plotting import pyplot, save_png

DIVISORS = (1, 2, 3, 4, 6, 8)
#: name, E (Pa), nu, measured TOF (s) of the thesis's control foams (Tables 2-3)
FOAMS = (("PCF08", 38e6, 0.34, 1.78e-3), ("PCF15", 123e6, 0.33, 1.46e-3),
         ("PCF30", 445e6, 0.30, 1.15e-3))
#: sech^2 widths (s) of the analytic incident and reflected pulses: ~3.5 samples at half
#: height at 51.2 kS/s (FWHM = 1.763 w), as the chain's, the reflected one broader.
ANALYTIC_WIDTHS = (40e-6, 55e-6)
UPSAMPLE = (1, 16)


def register(kinds: argparse._SubParsersAction) -> None:
    """Add the ``ssw bench tof`` command and its options.

    Parameters
    ----------
    kinds : argparse._SubParsersAction
        The ``ssw bench`` subcommands.
    """
    p = kinds.add_parser("tof", help="TOF error of simulated recordings vs NI 9234 rate")
    p.add_argument("--divisors", type=int, nargs="+", default=list(DIVISORS),
                   help="rate divisors n (rate = 51200/n S/s)")
    p.add_argument("--hits", type=int, default=20, help="hits per foam and rate")
    p.add_argument("--lowpass", type=float, help="zero-phase low-pass cutoff, Hz")
    p.add_argument("--upsample", type=int, nargs="+", default=list(UPSAMPLE),
                   help="interpolation factors compared (1: parabola on the samples)")
    p.add_argument("--source", choices=["chain", "analytic"], default="chain",
                   help="waveform of known TOF (module doc)")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Run ``ssw bench tof`` (module docstring) and write its outputs under ``--output-dir``.

    Parameters
    ----------
    args : argparse.Namespace
        The command's options (:func:`register`).

    Returns
    -------
    dict
        ``rows``: per source, interpolation, rate and sample, the TOF errors (s, and in
        sample periods) and the times per hit (s); ``outputs``: the files written.
    """
    from ssw.chain.params import ChainParams
    from ssw.config import load_config
    from ssw.daq.settings import NI9234_BASE_RATE, settings_from_config
    from ssw.daq.simulated import SimulatedBackend, analytic_waveform
    from ssw.signal.tof import ChainPath, TofOptions, session_tof

    cfg = load_config(args.config)
    params = ChainParams.from_config(cfg)
    path = ChainPath.from_params(params)
    rows = []
    for n in args.divisors:
        rate = NI9234_BASE_RATE / n
        s = settings_from_config(cfg, sample_rate=rate, hits=args.hits)
        for name, E, nu, tof in FOAMS:
            if args.source == "chain":
                b = SimulatedBackend(soil_E=E, soil_nu=nu, chain_params=params, seed=cfg["seed"])
            else:
                wave = analytic_waveform(tof, width=ANALYTIC_WIDTHS[0],
                                         width_reflected=ANALYTIC_WIDTHS[1])
                b = SimulatedBackend(wave, seed=cfg["seed"], true_tof=tof)
            t0 = time.perf_counter()
            hits = list(b.hits(s, args.hits))
            t1 = time.perf_counter()
            for up in args.upsample:
                t2 = time.perf_counter()
                opts = TofOptions(lowpass=args.lowpass, upsample=up,
                                  chain=path if args.source == "chain" else None)
                res = session_tof([h.force for h in hits], rate, s.pretrigger_samples, opts=opts)
                t3 = time.perf_counter()
                err = res.tof[res.accepted] - b.true_tof
                rows.append({"source": args.source, "upsample": up, "divisor": n, "rate": rate,
                             "sample": name, "true_tof": b.true_tof,
                             "n_accepted": res.n_accepted,
                             "max_abs_err": float(np.max(np.abs(err))),
                             "mean_err": float(np.mean(err)),
                             "max_abs_err_samples": float(np.max(np.abs(err)) * rate),
                             "sim_s_per_hit": (t1 - t0) / args.hits,
                             "tof_s_per_hit": (t3 - t2) / args.hits})
    out = Path(args.output_dir)
    keys = list(rows[0])
    atomic_write_text(out / "tof_work_precision.csv", "\n".join(
        [",".join(keys)] + [",".join(str(r[k]) for k in keys) for r in rows]) + "\n")
    _plot(out / "tof_work_precision.png", rows)
    return {"rows": rows, "outputs": [str(out / "tof_work_precision.csv"),
                                      str(out / "tof_work_precision.png")]}


def _plot(path: Path, rows: list[dict[str, Any]]) -> None:
    plt = pyplot()

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    ups = sorted({x["upsample"] for x in rows})
    for name, *_ in FOAMS:
        for up, style in zip(ups, ("o--", "s-", "^-.", "v:"), strict=False):
            r = [x for x in rows if x["sample"] == name and x["upsample"] == up]
            lab = f"{name}, " + ("parabola" if up == 1 else f"x{up} + parabola")
            rate = [x["rate"] for x in r]
            axes[0].loglog(rate, [x["max_abs_err"] * 1e6 for x in r], style, label=lab)
            axes[1].semilogx(rate, [x["mean_err"] * 1e6 for x in r], style, label=lab)
    rates = np.array(sorted({x["rate"] for x in rows}))
    axes[0].loglog(rates, 0.5e6 / rates, "k--", label="half a sample (tolerance)")
    axes[1].axhline(0.0, color="k", lw=0.8)
    for ax in axes:
        ax.set_xlabel("sample rate (S/s)")
    axes[0].set_ylabel("max |TOF error| (us)")
    axes[1].set_ylabel("mean TOF error, bias (us)")
    fig.suptitle(f"TOF from simulated NI 9234 recordings ({rows[0]['source']} source) vs truth")
    axes[0].legend(fontsize=6)
    fig.tight_layout()
    save_png(fig, path, dpi=120)
