"""``ssw bench chain``: work-precision of the batched Verlet chain vs scipy DOP853.

Accuracy is the TOF's relative error against a reference run (velocity Verlet at
``REFERENCE_SPC`` steps per contact time, whose own error is ~1e-7 by the dt^2 law; it is
cross-checked against DOP853 at rtol 1e-10). Work is wall time per TOF point:

* ours: the whole sweep (default 300 points: E 10..1000 MPa x nu 0.1/0.3/0.5) in one
  batched run at ``steps_per_contact`` = 10..320, time / points; errors over every 10th
  E of each nu (30 reference points);
* baseline (:mod:`ssw.chain.baseline`): one scene at a time with ``solve_ivp(DOP853)``
  at rtol 1e-3..1e-9 (atol = 1e-6 rtol m, the displacement scale), on E = 38, 123,
  445 MPa (nu 0.3) over the same simulated time as our run (its stop time).

The speed-up at equal accuracy is the cheapest DOP853 setting that reaches a target error
divided by the cheapest Verlet setting that does. Writes ``chain_work_precision.csv``,
``.png`` and ``.json`` under the output folder.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

from ssw.h5io import atomic_write_text, to_json
from ssw.plotting import pyplot, save_png

SPCS = (10, 20, 40, 60, 80, 160, 320)
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9)
REFERENCE_SPC = 1280
BASELINE_E = (38e6, 123e6, 445e6)
TARGETS = (1e-3, 1e-4, 1e-5)


def register(kinds: argparse._SubParsersAction) -> None:
    from ssw.cli import add_json_flag

    p = kinds.add_parser("chain", help="work-precision of the chain integrator vs DOP853")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--spcs", type=int, nargs="+", default=list(SPCS),
                   help="Verlet steps per contact time to try")
    p.add_argument("--rtols", type=float, nargs="+", default=list(RTOLS),
                   help="DOP853 relative tolerances to try")
    p.add_argument("--repeat", type=int, default=3, help="timing repeats (best is kept)")
    add_json_flag(p)
    p.set_defaults(func=run, human=human)


def _best_time(fn: Any, repeat: int) -> tuple[float, Any]:
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def _cheapest(rows: list[dict[str, Any]], method: str, target: float) -> float:
    ok = [r["time_per_point"] for r in rows if r["method"] == method and r["error"] <= target]
    return min(ok) if ok else float("nan")


def run(args: argparse.Namespace) -> dict[str, Any]:
    from pathlib import Path

    from ssw.chain.api import peaks
    from ssw.chain.baseline import solve_dop853
    from ssw.chain.params import ChainParams
    from ssw.chain.sweep import grid_points
    from ssw.chain.walls import build_wall
    from ssw.config import expand_grid, load_config

    cfg = load_config(args.config)
    params = ChainParams.from_config(cfg)
    sw = cfg["chain"]["sweep"]
    E, nu = grid_points(expand_grid(sw["soil_E"], "chain.sweep.soil_E"),
                        expand_grid(sw["soil_nu"], "chain.sweep.soil_nu"))
    sub = np.arange(0, E.size, 10)
    ref_p = params.with_(steps_per_contact=REFERENCE_SPC)
    ref_pk, _ = peaks(E[sub], nu[sub], ref_p, "hertz")
    ref_sub = ref_pk.tof
    bE = np.array(BASELINE_E)
    ref_b, ref_run = peaks(bE, 0.3, ref_p, "hertz")
    rows: list[dict[str, Any]] = []
    for spc in args.spcs:
        p = params.with_(steps_per_contact=spc)
        t_all, (pk, run_) = _best_time(lambda p=p: peaks(E, nu, p, "hertz"), args.repeat)
        err = float(np.max(np.abs(pk.tof[sub] / ref_sub - 1)))
        rows.append({"method": "verlet_batched", "setting": spc, "error": err,
                     "time_per_point": t_all / E.size, "points": int(E.size),
                     "dt": run_.dt})
    p1 = params.with_(steps_per_contact=params.steps_per_contact)
    t_one, (pk1, _) = _best_time(lambda: peaks(bE[:1], 0.3, p1, "hertz"), args.repeat)
    rows.append({"method": "verlet_single_scene", "setting": params.steps_per_contact,
                 "error": float(abs(pk1.tof[0] / ref_b.tof[0] - 1)),
                 "time_per_point": t_one, "points": 1, "dt": float("nan")})
    t_end = ref_run.stop_time
    solve_dop853(params, build_wall("hertz", params, bE[0], 0.3), t_end=t_end[0], rtol=1e-3)
    for rtol in args.rtols:
        errs, times = [], []
        for k, e in enumerate(bE):
            w = build_wall("hertz", params, e, 0.3)
            tk, res = _best_time(
                lambda w=w, k=k, r=rtol: solve_dop853(params, w, t_end=float(t_end[k]),
                                                      rtol=r, atol=1e-6 * r), args.repeat)
            errs.append(abs(res.tof / ref_b.tof[k] - 1))
            times.append(tk)
        rows.append({"method": "dop853", "setting": rtol, "error": float(max(errs)),
                     "time_per_point": float(np.mean(times)), "points": len(bE),
                     "dt": float("nan")})
    check = solve_dop853(params, build_wall("hertz", params, bE[1], 0.3),
                         t_end=float(t_end[1]), rtol=1e-10, atol=1e-16)
    ref_vs_dop = float(abs(check.tof / ref_b.tof[1] - 1))
    speedup = {
        f"{tg:g}": _cheapest(rows, "dop853", tg) / _cheapest(rows, "verlet_batched", tg)
        for tg in TARGETS
    }
    out = Path(args.output_dir)
    _write(out, rows)
    result = {
        "rows": rows, "speedup_at_equal_error": speedup,
        "reference_vs_dop853_rtol1e-10": ref_vs_dop,
        "outputs": [str(out / f"chain_work_precision.{x}") for x in ("csv", "png", "json")],
    }
    atomic_write_text(out / "chain_work_precision.json", to_json(result, indent=1))
    return result


def _write(out: Any, rows: list[dict[str, Any]]) -> None:
    plt = pyplot()

    head = "method,setting,tof_rel_error,time_per_point_s,points,dt_s"
    lines = [head] + [
        f"{r['method']},{r['setting']:g},{r['error']:.4e},{r['time_per_point']:.4e},"
        f"{r['points']},{r['dt']:.4e}" for r in rows
    ]
    atomic_write_text(out / "chain_work_precision.csv", "\n".join(lines) + "\n")
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for m, style in (("verlet_batched", "o-"), ("dop853", "s-"), ("verlet_single_scene", "^")):
        rr = [r for r in rows if r["method"] == m]
        ax.loglog([r["time_per_point"] for r in rr], [max(r["error"], 1e-12) for r in rr],
                  style, label=m)
    ax.axhline(1e-4, color="gray", lw=0.8, ls="--")
    ax.set_xlabel("wall time per TOF point (s)")
    ax.set_ylabel("TOF relative error")
    ax.set_title("Chain: work-precision (hertz wall, gravity)")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    fig.tight_layout()
    save_png(fig, out / "chain_work_precision.png", dpi=150)


def human(result: dict[str, Any]) -> str:
    lines = [f"{'method':22s} {'setting':>9s} {'error':>10s} {'s/point':>10s}"]
    for r in result["rows"]:
        lines.append(f"{r['method']:22s} {r['setting']:9g} {r['error']:10.2e} "
                     f"{r['time_per_point']:10.2e}")
    lines.append("speed-up at equal error: " + ", ".join(
        f"{k}: {v:.0f}x" for k, v in result["speedup_at_equal_error"].items()))
    lines.append(f"reference vs DOP853 rtol 1e-10: {result['reference_vs_dop853_rtol1e-10']:.1e}")
    lines.append("outputs: " + ", ".join(result["outputs"]))
    return "\n".join(lines)
