"""``ssw bench chain``: work-precision of the batched Verlet chain and of scipy's DOP853.

Model: the study's chain (``ChainParams.from_config`` of ``--config``: its device, 20
beads, gravity, the device's striker speed, no calibration file) on the Hertz wall, at the
300 points of the TOF sweep (E 10..1000 MPa step 10 x nu 0.1/0.3/0.5, thesis Fig 8).

**Accuracy** is the TOF's relative error against an independent reference
(:mod:`ssw.chain.baseline`: the same equations solved by scipy's DOP853 with its own
initial state and peak location) at ``REFERENCE_RTOL`` = 1e-12, on every 10th point (30
points), each run 1.5 x as long as ssw's run of that point. The reference's own error is
stated from a second solve at ``CHECK_RTOL`` = 1e-10 (the error of the 1e-10 solution;
the 1e-12 one is smaller) and from ``sample_dt`` (peak location between samples).

**Work** is the wall time per TOF point, everything included (set-up, integration, peak
picking), best of ``--repeat``, for two uses:

* *batched*: the whole 300-point sweep in one call; Verlet (``ssw.tof.api.peaks``, every
  scene in one (N, n) array) at ``--spcs`` steps per contact time, and DOP853 on the same
  300 scenes as one ODE system (``solve_dop853`` with 300 walls) at ``--batched-rtols``;
* *one at a time*: a loop of single-point calls over every 3rd reference point (10
  points), Verlet (``ssw.tof.api.tof``) and DOP853 (``solve_dop853``) at ``--rtols``.

Every DOP853 run simulates as long as ssw's run of the same point (its early-stop time).
The speed-up at equal error is the ratio of the times at which the two methods' error
curves (log-log, piecewise linear on each method's Pareto front) reach a target error.
Also measured: the relative energy error ``max |E(t) - E(0)| / |E(0)|`` of one scene (E 100
MPa, nu 0.3, 3 ms, as ``ssw chain --json`` reports it) per ``steps_per_contact``.

Writes ``chain_work_precision.{csv,json,png}`` under ``--output-dir``.
"""

from __future__ import annotations

import argparse
import itertools
import time
from typing import Any

import numpy as np

from ssw.bench import best_time
from ssw.h5io import atomic_write_text, write_json
from ssw.plotting import pyplot, save_png

SPCS = (10, 20, 40, 80, 160, 320)
SINGLE_SPCS = (20, 40, 80, 160, 320)
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9)
BATCHED_RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7)
#: The reference's tolerance and the looser one that states its error.
REFERENCE_RTOL, CHECK_RTOL = 1e-12, 1e-10
#: The reference's sensor sample step (s): the peak's cubic-Hermite location error is
#: ~1e-12 s there (1e-6 s and 2.5e-7 s differ by 1e-10 s at 38 MPa).
REFERENCE_SAMPLE_DT = 2.5e-7
#: The reference runs this much longer than ssw's run of the same point.
REFERENCE_LENGTH = 1.5
#: Every ``REFERENCE_STRIDE``-th sweep point has a reference; every ``SINGLE_STRIDE``-th
#: of those is timed one at a time.
REFERENCE_STRIDE, SINGLE_STRIDE = 10, 3
TARGETS = (1e-3, 1e-4, 1e-5)
#: The energy scene (the defaults of ``ssw chain``) and its simulated time (s).
ENERGY_SCENE, ENERGY_T_END = (100.0e6, 0.3), 3.0e-3


def register(kinds: argparse._SubParsersAction) -> None:
    """Add the ``ssw bench chain`` command and its options.

    Parameters
    ----------
    kinds : argparse._SubParsersAction
        The ``ssw bench`` subcommands.
    """
    p = kinds.add_parser("chain", help="work-precision of the chain integrator vs DOP853")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--spcs", type=int, nargs="+", default=list(SPCS),
                   help="Verlet steps per contact time, batched sweep")
    p.add_argument("--single-spcs", type=int, nargs="+", default=list(SINGLE_SPCS),
                   help="Verlet steps per contact time, one point at a time")
    p.add_argument("--rtols", type=float, nargs="+", default=list(RTOLS),
                   help="DOP853 relative tolerances, one point at a time")
    p.add_argument("--batched-rtols", type=float, nargs="+", default=list(BATCHED_RTOLS),
                   help="DOP853 relative tolerances, the whole sweep as one system")
    p.add_argument("--repeat", type=int, default=2, help="timing repeats (best is kept)")
    p.set_defaults(func=run, human=human)


def time_at_error(rows: list[dict[str, Any]], method: str, target: float) -> float:
    """Time per point (s) at which ``method`` reaches ``target`` (log-log interpolation on
    its Pareto front); NaN when no setting reaches it, the cheapest time when all do.

    Parameters
    ----------
    rows : list of dict
        The measurements: ``method``, ``time_per_point`` (s) and ``error`` (relative).
    method : str
        The method whose rows are used.
    target : float
        The target error, relative.

    Returns
    -------
    float
        The time per point, s.
    """
    pts = sorted((r["time_per_point"], r["error"]) for r in rows if r["method"] == method)
    front: list[tuple[float, float]] = []
    for t, e in pts:  # keep settings that are more accurate than every cheaper one
        if not front or e < front[-1][1]:
            front.append((t, e))
    if not front or front[-1][1] > target:
        return float("nan")
    if front[0][1] <= target:
        return front[0][0]
    for (t0, e0), (t1, e1) in itertools.pairwise(front):
        if e1 <= target < e0:
            f = np.log(target / e0) / np.log(e1 / e0)
            return float(np.exp(np.log(t0) + f * np.log(t1 / t0)))
    return float("nan")


def energy_error(params: Any, spc: int) -> float:
    """``max |E(t) - E(0)| / |E(0)|`` of the energy scene at ``spc`` steps per contact.

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The chain.
    spc : int
        Steps per contact time.

    Returns
    -------
    float
        The relative energy error, dimensionless.
    """
    from ssw.tof.api import run_chain

    run = run_chain(params.with_(steps_per_contact=spc), *ENERGY_SCENE, "hertz",
                    t_end=ENERGY_T_END)
    e = run.energy[:, 0]
    return float(np.max(np.abs(e - e[0])) / abs(e[0]))


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Run ``ssw bench chain`` (module docstring) and write its outputs under ``--output-dir``.

    Parameters
    ----------
    args : argparse.Namespace
        The command's options (:func:`register`).

    Returns
    -------
    dict
        The measurements (times in s, errors relative, SI units otherwise) and the files
        written.
    """
    from pathlib import Path

    from ssw.chain.baseline import hertz_wall, solve_dop853
    from ssw.chain.params import ChainParams
    from ssw.config import expand_grid, load_config
    from ssw.tof import api
    from ssw.tof.sweep import grid_points

    cfg = load_config(args.config)
    params = ChainParams.from_config(cfg)
    sw = cfg["chain"]["sweep"]
    E, nu = grid_points(expand_grid(sw["soil_E"], "chain.sweep.soil_E"),
                        expand_grid(sw["soil_nu"], "chain.sweep.soil_nu"))
    sub = np.arange(0, E.size, REFERENCE_STRIDE)
    one = sub[::SINGLE_STRIDE]
    pk_def, run_def = api.peaks(E, nu, params, "hertz")
    stop = run_def.stop_time  # s, ssw's simulated time per point

    ref, check, t_ref, share = _reference(params, E[sub], nu[sub], stop[sub])
    ref_of = dict(zip(sub.tolist(), ref, strict=True))

    def err(idx: np.ndarray, tof: np.ndarray) -> float:
        return float(np.max(np.abs(tof / np.array([ref_of[k] for k in idx]) - 1)))

    rows: list[dict[str, Any]] = []

    def add(method: str, setting: float, t: float, points: int, idx: np.ndarray,
            tof: np.ndarray, **extra: Any) -> None:
        rows.append({"method": method, "setting": setting, "error": err(idx, tof),
                     "time_per_point": t / points, "points": points, **extra})

    for spc in args.spcs:
        p = params.with_(steps_per_contact=spc)
        t, (pk, rn) = best_time(lambda p=p: api.peaks(E, nu, p, "hertz"), args.repeat)
        add("verlet_batched", spc, t, E.size, sub, pk.tof[sub], dt=rn.dt,
            energy_error=energy_error(params, spc))
    for spc in args.single_spcs:
        p = params.with_(steps_per_contact=spc)
        t, tof = best_time(lambda p=p: np.array(
            [float(api.tof(E[k], nu[k], p, "hertz")) for k in one]), args.repeat)
        add("verlet_single", spc, t, one.size, one, tof)
    walls = hertz_wall(params, E, nu)
    for rtol in args.batched_rtols:
        t, r = best_time(lambda r=rtol: solve_dop853(params, walls, t_end=stop, rtol=r),
                          args.repeat)
        add("dop853_batched", rtol, t, E.size, sub, r.tof[sub], nfev=r.nfev, steps=r.steps)
    for rtol in args.rtols:
        t, tof = best_time(lambda r=rtol: np.array(
            [solve_dop853(params, hertz_wall(params, E[k], nu[k]), t_end=stop[k],
                          rtol=r).tof[0] for k in one]), args.repeat)
        add("dop853_single", rtol, t, one.size, one, tof)

    speedup = {
        use: {f"{tg:g}": time_at_error(rows, f"dop853_{use}", tg)
              / time_at_error(rows, f"verlet_{use}", tg) for tg in TARGETS}
        for use in ("batched", "single")
    }
    out = Path(args.output_dir)
    result = {
        "command": "ssw bench chain", "config": args.config, "wall": "hertz",
        "points": int(E.size), "reference_points": int(sub.size), "single_points": int(one.size),
        "reference": {
            "method": "scipy DOP853 (ssw.chain.baseline.solve_dop853)",
            "rtol": REFERENCE_RTOL, "sample_dt": REFERENCE_SAMPLE_DT,
            "length": f"{REFERENCE_LENGTH} x ssw's run",
            "error_of_rtol_1e-10_solution": float(np.max(np.abs(check / ref - 1))),
            "time_per_point": float(np.mean(t_ref)),
            "reflected_peak_share_of_run": float(np.max(share)),
        },
        "default_spc": params.steps_per_contact,
        "default_error": err(sub, pk_def.tof[sub]),
        "reference_points_table": [
            {"soil_E": float(E[k]), "soil_nu": float(nu[k]), "tof_reference": float(ref[i]),
             "tof_rtol_1e-10": float(check[i]), "tof_ssw_default": float(pk_def.tof[k])}
            for i, k in enumerate(sub)],
        "striker_velocity": params.striker_velocity,
        "rows": rows, "speedup_at_equal_error": speedup,
        "outputs": [str(out / f"chain_work_precision.{x}") for x in ("csv", "png", "json")],
    }
    _write(out, result)
    write_json(out / "chain_work_precision.json", result, result)
    return result



def _reference(params: Any, E: np.ndarray, nu: np.ndarray, stop: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The reference TOFs: one DOP853 solve per point at :data:`REFERENCE_RTOL` over
    :data:`REFERENCE_LENGTH` times ssw's run (``stop``, s), and its check at
    :data:`CHECK_RTOL`. ``E`` (Pa), ``nu`` (-) the points, ``params`` the chain. Returns
    the reference and the check TOFs (s), the reference's CPU time per point (s) and the
    reflected peak's time as a share of the run (it lies well inside)."""
    from ssw.chain.baseline import hertz_wall, solve_dop853

    ref, check, t_ref, share = (np.empty(E.size) for _ in range(4))
    for i in range(E.size):
        w = hertz_wall(params, E[i], nu[i])
        t_end = REFERENCE_LENGTH * stop[i]
        t0 = time.perf_counter()
        r = solve_dop853(params, w, t_end=t_end, rtol=REFERENCE_RTOL,
                         sample_dt=REFERENCE_SAMPLE_DT)
        t_ref[i] = time.perf_counter() - t0
        c = solve_dop853(params, w, t_end=t_end, rtol=CHECK_RTOL,
                         sample_dt=REFERENCE_SAMPLE_DT)
        ref[i], check[i] = r.tof[0], c.tof[0]
        share[i] = r.t_reflected[0] / t_end
    return ref, check, t_ref, share


LABELS = {
    "verlet_batched": ("velocity Verlet, 300-point sweep in one call (ssw)", "o-", "C0"),
    "verlet_single": ("velocity Verlet, one point per call (ssw)", "o--", "C0"),
    "dop853_batched": ("scipy DOP853, 300 points as one ODE system", "s-", "C3"),
    "dop853_single": ("scipy DOP853, one point per call", "s--", "C3"),
}


def _write(out: Any, result: dict[str, Any]) -> None:
    plt = pyplot()
    rows = result["rows"]
    head = "method,setting,tof_rel_error,time_per_point_s,points,energy_rel_error"
    lines = [head] + [
        f"{r['method']},{r['setting']:g},{r['error']:.4e},{r['time_per_point']:.4e},"
        f"{r['points']},{r.get('energy_error', float('nan')):.4e}" for r in rows
    ]
    atomic_write_text(out / "chain_work_precision.csv", "\n".join(lines) + "\n")
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.4))
    for m, (label, style, color) in LABELS.items():
        # in the order of the setting, from coarse to fine (Verlet: more steps; DOP853:
        # smaller rtol), so that timing noise shows as a kink, not as a reordering
        sign = 1.0 if m.startswith("verlet") else -1.0
        rr = sorted((r for r in rows if r["method"] == m), key=lambda r: sign * r["setting"])
        if rr:
            ax.loglog([r["time_per_point"] for r in rr], [r["error"] for r in rr], style,
                      color=color, label=label, ms=4)
    ref_err = result["reference"]["error_of_rtol_1e-10_solution"]
    ax.axhline(ref_err, color="gray", lw=0.8, ls=":")
    ax.text(ax.get_xlim()[0], ref_err, " reference rtol 1e-10 vs 1e-12", va="bottom",
            fontsize=7, color="gray")
    ax.set_xlabel("wall time per TOF point (s)")
    ax.set_ylabel("max TOF relative error")
    ax.set_title("work-precision (Hertz wall, 20 beads, gravity)", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    vb = sorted((r for r in rows if r["method"] == "verlet_batched"), key=lambda r: r["setting"])
    spc = np.array([r["setting"] for r in vb], float)
    bx.loglog(spc, [r["error"] for r in vb], "o-", color="C0", label="TOF error vs DOP853")
    bx.loglog(spc, [r["energy_error"] for r in vb], "^-", color="C2",
              label="energy error max|E-E0|/E0 (100 MPa, 3 ms)")
    if spc.size:
        guide = vb[0]["error"] * (spc / spc[0]) ** -2.0
        bx.loglog(spc, guide, color="gray", lw=0.8, ls="--", label="slope -2")
    bx.axvline(result["default_spc"], color="k", lw=0.6, ls=":")
    bx.set_xlabel("Verlet steps per contact time (default dotted)")
    bx.set_ylabel("relative error")
    bx.set_title("velocity Verlet: second order", fontsize=10)
    bx.grid(alpha=0.3, which="both")
    bx.legend(fontsize=7)
    fig.suptitle("ssw bench chain: TOF error vs scipy DOP853 rtol 1e-12 (30 of the 300 "
                 "sweep points)", fontsize=10)
    fig.tight_layout()
    save_png(fig, out / "chain_work_precision.png", dpi=150)


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
    ref = result["reference"]
    lines = [
        f"reference: {ref['method']} rtol {ref['rtol']:g} on {result['reference_points']} of "
        f"{result['points']} points ({ref['time_per_point']:.2f} s/point); the rtol 1e-10 "
        f"solution differs by {ref['error_of_rtol_1e-10_solution']:.1e}",
        f"{'method':16s} {'setting':>8s} {'TOF error':>10s} {'s/point':>10s} {'energy':>9s}",
    ]
    for r in result["rows"]:
        lines.append(f"{r['method']:16s} {r['setting']:8g} {r['error']:10.2e} "
                     f"{r['time_per_point']:10.2e} {r.get('energy_error', float('nan')):9.1e}")
    for use, sp in result["speedup_at_equal_error"].items():
        lines.append(f"speed-up at equal error, {use}: " + ", ".join(
            f"{k}: {v:.1f}x" for k, v in sp.items()))
    lines.append("outputs: " + ", ".join(result["outputs"]))
    return "\n".join(lines)
