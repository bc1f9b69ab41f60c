"""``ssw bench tof``: TOF error and cost of the simulated NI 9234 + peak picking vs rate.

For each NI 9234 rate ``51200/n`` and each control foam (chain model, Hertz wall unless
``--wall``), ``--hits`` simulated hits are recorded (random sample phase, jitter, noise,
24-bit quantization) and their TOF extracted; the error is against the chain's own TOF.
Reports the largest and mean error in seconds and in sample periods (the round-trip
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
FOAMS = (("PCF08", 38e6, 0.34), ("PCF15", 123e6, 0.33), ("PCF30", 445e6, 0.30))


def register(kinds: argparse._SubParsersAction) -> None:
    from ssw.cli import add_json_flag

    p = kinds.add_parser("tof", help="TOF error of simulated recordings vs NI 9234 rate")
    p.add_argument("--divisors", type=int, nargs="+", default=list(DIVISORS),
                   help="rate divisors n (rate = 51200/n S/s)")
    p.add_argument("--hits", type=int, default=20, help="hits per foam and rate")
    p.add_argument("--lowpass", type=float, help="zero-phase low-pass cutoff, Hz")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    add_json_flag(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> dict[str, Any]:
    from ssw.chain.params import ChainParams
    from ssw.config import load_config
    from ssw.daq.settings import NI9234_BASE_RATE, settings_from_config
    from ssw.daq.simulated import SimulatedBackend
    from ssw.signal.tof import TofOptions, session_tof

    cfg = load_config(args.config)
    params = ChainParams.from_config(cfg)
    rows = []
    for n in args.divisors:
        rate = NI9234_BASE_RATE / n
        s = settings_from_config(cfg, sample_rate=rate, hits=args.hits)
        for name, E, nu in FOAMS:
            b = SimulatedBackend(soil_E=E, soil_nu=nu, chain_params=params, seed=cfg["seed"])
            t0 = time.perf_counter()
            hits = list(b.hits(s, args.hits))
            t1 = time.perf_counter()
            res = session_tof([h.force for h in hits], rate, s.pretrigger_samples,
                              opts=TofOptions(lowpass=args.lowpass))
            t2 = time.perf_counter()
            err = res.tof[res.accepted] - b.true_tof
            rows.append({"divisor": n, "rate": rate, "sample": name, "true_tof": b.true_tof,
                         "n_accepted": res.n_accepted, "max_abs_err": float(np.max(np.abs(err))),
                         "mean_err": float(np.mean(err)),
                         "max_abs_err_samples": float(np.max(np.abs(err)) * rate),
                         "sim_s_per_hit": (t1 - t0) / args.hits,
                         "tof_s_per_hit": (t2 - t1) / args.hits})
    out = Path(args.output_dir)
    keys = list(rows[0])
    atomic_write_text(out / "tof_work_precision.csv", "\n".join(
        [",".join(keys)] + [",".join(str(r[k]) for k in keys) for r in rows]) + "\n")
    _plot(out / "tof_work_precision.png", rows)
    return {"rows": rows, "outputs": [str(out / "tof_work_precision.csv"),
                                      str(out / "tof_work_precision.png")]}


def _plot(path: Path, rows: list[dict[str, Any]]) -> None:
    plt = pyplot()

    fig, ax = plt.subplots(figsize=(6, 4))
    for name, *_ in FOAMS:
        r = [x for x in rows if x["sample"] == name]
        ax.loglog([x["rate"] for x in r], [x["max_abs_err"] * 1e6 for x in r], "o-", label=name)
    rates = np.array(sorted({x["rate"] for x in rows}))
    ax.loglog(rates, 0.5e6 / rates, "k--", label="half a sample (tolerance)")
    ax.set_xlabel("sample rate (S/s)")
    ax.set_ylabel("max |TOF error| (us)")
    ax.set_title("TOF from simulated NI 9234 recordings vs the chain's TOF")
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_png(fig, path, dpi=120)
