"""``ssw bench dynamic``: the dynamic wall's verification and cost.

Parts (``--parts``, default all):

* ``punch``: vertical impedance ``k(a0)``, ``c(a0)`` of a rigid punch (radius 5 mm, soil
  20 MPa, 2000 kg/m^3, nu = 1/3) on the FEM half-space against Veletsos & Verbic (1973)
  and Lysmer's analog (:mod:`ssw.dynamics.punch`), with the fine default mesh; writes
  ``dynamic_punch.csv`` and ``.png``;
* ``static-limit``: soil and plate of density 1e-6 kg/m^3, the quasi-static FEM's box and
  mesh (1 m, fixed): the dynamic FEM wall's TOF against the quasi-static pipeline of the
  study (``ssw.contact.solve_curve`` -> ``table`` wall -> ``ssw.chain.integrate``);
* ``point``: one FEM-wall TOF point on the softest, densest soil with the plate (the
  dearest scene: the longest run), its wall time (the goal: <= 5 min on 2 cores),
  size and energy balance;
* ``sweep-cost``: a 300-point sweep (E 10..1000 MPa x nu 0.1/0.3/0.5, Hertz law) with the
  quasi-static wall and with the reduced wall through the chain's one integrator
  (``ssw.chain.integrate.simulate``) over the same record (no early stop), and the chain
  stage's own quasi-static sweep (early stop) for scale; the goal: reduced <= 2x.

Timings are wall times on a shared machine: the best of ``--repeat``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from ssw.bench import best_time
from ssw.h5io import atomic_write_text, write_json

PARTS = ("punch", "static-limit", "point", "sweep-cost")
A0 = (0.25, 0.5, 0.75, 1.0, 1.25, 1.5)


def register(kinds: argparse._SubParsersAction) -> None:
    """Add the ``ssw bench dynamic`` command and its options.

    Parameters
    ----------
    kinds : argparse._SubParsersAction
        The ``ssw bench`` subcommands.
    """
    p = kinds.add_parser("dynamic", help="dynamic wall: punch impedance, static limit, cost")
    p.add_argument("--parts", nargs="+", choices=PARTS, default=list(PARTS),
                   help="which measurements to run")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--repeat", type=int, default=1, help="timing repeats (best is kept)")
    p.set_defaults(func=run, human=human)


def punch_part(out: Path) -> dict[str, Any]:
    """The punch impedance against the published values.

    Parameters
    ----------
    out : pathlib.Path
        The output folder.

    Returns
    -------
    dict
        ``a0``, the FEM's and the published ``k`` and ``c``, their largest relative
        differences, the static stiffness ratio, the mesh's size, ``wall`` (s) and
        ``outputs``.
    """
    from ssw.dynamics.punch import lysmer_analog, punch_impedance, veletsos_verbic
    from ssw.dynamics.system import Material
    from ssw.plotting import pyplot, save_png

    a0 = np.array(A0)
    soil = Material(20e6, 1.0 / 3.0, 2000.0)
    t0 = time.perf_counter()
    r = punch_impedance(soil, 5e-3, a0)
    wall = time.perf_counter() - t0
    k_vv, c_vv = veletsos_verbic(a0, soil.nu)
    _, c_ly = lysmer_analog(a0)
    lines = ["a0,k_fem,k_veletsos_verbic,c_fem,c_veletsos_verbic,c_lysmer"]
    lines += [f"{x:g},{k:.5f},{kv:.5f},{c:.5f},{cv:.5f},{cl:.3f}"
              for x, k, kv, c, cv, cl in zip(a0, r.k, k_vv, r.c, c_vv, c_ly, strict=True)]
    atomic_write_text(out / "dynamic_punch.csv", "\n".join(lines) + "\n")
    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(9, 3.8))
    ax[0].plot(a0, r.k, "o-", label="FEM")
    ax[0].plot(a0, k_vv, "s--", label="Veletsos & Verbic 1973")
    ax[0].plot(a0, np.ones_like(a0), ":", label="Lysmer's analog")
    ax[1].plot(a0, r.c, "o-", label="FEM")
    ax[1].plot(a0, c_vv, "s--", label="Veletsos & Verbic 1973")
    ax[1].plot(a0, c_ly, ":", label="Lysmer's analog")
    for a, name in zip(ax, ("k (stiffness)", "c (damping)"), strict=True):
        a.set_xlabel("a0 = omega a / c_s")
        a.set_title(f"rigid punch, nu = 1/3: {name}")
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    fig.tight_layout()
    save_png(fig, out / "dynamic_punch.png", dpi=150)
    return {"a0": a0.tolist(), "k": r.k.tolist(), "c": r.c.tolist(),
            "k_veletsos_verbic": k_vv.tolist(), "c_veletsos_verbic": c_vv.tolist(),
            "max_k_error_vs_vv": float(np.max(np.abs(r.k / k_vv - 1))),
            "max_c_error_vs_vv": float(np.max(np.abs(r.c / c_vv - 1))),
            "max_c_error_vs_lysmer": float(np.max(np.abs(r.c / c_ly - 1))),
            "K_static_over_4Ga_1mnu": r.K_static * (1 - soil.nu) / (4 * soil.G * 5e-3),
            "dofs": r.dofs, "domain": r.domain, "wall": wall,
            "outputs": [str(out / "dynamic_punch.csv"), str(out / "dynamic_punch.png")]}


def static_limit_part() -> dict[str, Any]:
    """Density 1e-6 in the quasi-static FEM's box and mesh vs the study's pipeline.

    Returns
    -------
    dict
        The soil (Pa), the two TOFs (s), their ``relative_difference``, the two meshes' dofs
        and the dynamic run's ``wall`` time (s).
    """
    from ssw.chain.dense import dense_peaks
    from ssw.chain.integrate import simulate as chain_simulate
    from ssw.chain.params import ChainParams
    from ssw.chain.wall import table_wall
    from ssw.contact import solve_curve
    from ssw.dynamics.fem_wall import fem_wall

    p = ChainParams()
    E, nu = 100e6, 0.3
    spec = {"domain": 1.0, "size_max": 0.1, "size_contact": 10e-6}
    t0 = time.perf_counter()
    wall, sc = fem_wall(p, E, nu, 1e-6, boundary="fixed", spec=spec, bead="scale",
                        plate_density=1e-6)
    try:
        run = chain_simulate(p, wall, t_end=float(sc.t_end[0]), dt=sc.dt, stop_early=False)
        dofs = wall.contacts[0].system.ndof
    finally:
        wall.destroy()
    t_fem = time.perf_counter() - t0
    cfg = {"soil_radius": 1.0, "soil_depth": 1.0, "mesh_size_contact": 10e-6,
           "mesh_growth": 0.1, "mesh_size_max": 0.1, "plate_layers": 4,
           "delta_max": 2.0 * float(sc.d_peak[0]), "steps": 1000, "candidate_factor": 1.5}
    curve, _ = solve_curve((E, nu), (p.plate_E, p.plate_nu), p.plate_thickness,
                           p.bead_radius, cfg)
    qs = chain_simulate(p, table_wall(p, E, nu, curve=curve), dt=sc.dt)
    tof_fem = float(dense_peaks(run).tof[0])
    tof_qs = float(dense_peaks(qs).tof[0])
    return {"soil_E": E, "soil_nu": nu, "density": 1e-6, "tof_fem_dynamic": tof_fem,
            "tof_quasi_static_pipeline": tof_qs, "relative_difference": tof_fem / tof_qs - 1,
            "dofs": dofs, "dofs_contact_solver": curve.stats["dofs"], "wall": t_fem}


def point_part() -> dict[str, Any]:
    """One FEM-wall TOF point: 10 MPa, 2200 kg/m^3, 0.4 mm PLA.

    Returns
    -------
    dict
        The scene, its TOFs (s), errors (relative), ``wall`` (s), energy balance and the
        FEM's statistics.
    """
    from ssw.chain.params import ChainParams
    from ssw.dynamics.api import fem_tof

    t0 = time.perf_counter()
    r = fem_tof(ChainParams(), 10e6, 0.3, 2200.0)
    wall = time.perf_counter() - t0
    st = r.stats[0]
    return {"soil_E": 10e6, "soil_density": 2200.0, "tof_dynamic": float(r.tof_dynamic[0]),
            "tof_half_space": float(r.tof_half_space[0]), "error": float(r.error[0]),
            "error_box": float(r.error_box[0]), "wall": wall,
            "energy_balance_relative": st["energy_drift"] / st["energy_input"],
            "radiated_share": st["energy_radiated"] / st["energy_input"], **st}


def sweep_cost_part(repeat: int) -> dict[str, Any]:
    """300-point sweep: quasi-static vs reduced wall, same integrator; the chain stage's.

    Parameters
    ----------
    repeat : int
        Timings; the fastest is kept.

    Returns
    -------
    dict
        ``points``, ``t_end`` (s), the wall times (s) and their ``ratio``.
    """
    from ssw.chain.integrate import simulate as chain_simulate
    from ssw.chain.integrate import time_step
    from ssw.chain.params import ChainParams
    from ssw.dynamics.reduced import plate_areal_density, reduced_wall
    from ssw.walls import build_wall

    p = ChainParams()
    E = np.repeat(np.arange(10e6, 1000e6 + 1, 10e6), 3)
    nu = np.tile([0.1, 0.3, 0.5], E.size // 3)
    qs = build_wall("hertz", p, E, nu)
    dt = time_step(p, qs)
    t_chain, run = best_time(lambda: chain_simulate(p, qs, dt=dt), repeat)
    t_end = float(np.nanmax(run.stop_time))
    t_qs, _ = best_time(lambda: chain_simulate(p, qs, t_end=t_end, dt=dt, stop_early=False),
                        repeat)
    rw = reduced_wall(qs, E, nu, 2000.0, plate_areal_density=plate_areal_density(p))
    t_red, _ = best_time(lambda: chain_simulate(p, rw, t_end=t_end, dt=dt, stop_early=False),
                         repeat)
    return {"points": int(E.size), "t_end": t_end, "wall_chain_stage_quasi_static": t_chain,
            "wall_quasi_static": t_qs, "wall_reduced": t_red, "ratio": t_red / t_qs}


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Run ``ssw bench dynamic`` (module docstring) and write its outputs under ``--output-dir``.

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
    out = Path(args.output_dir)
    out.mkdir(parents=True, exist_ok=True)
    res: dict[str, Any] = {}
    if "punch" in args.parts:
        res["punch"] = punch_part(out)
    if "static-limit" in args.parts:
        res["static_limit"] = static_limit_part()
    if "point" in args.parts:
        res["point"] = point_part()
    if "sweep-cost" in args.parts:
        res["sweep_cost"] = sweep_cost_part(args.repeat)
    write_json(out / "dynamic_bench.json", res, res)
    res["outputs"] = [str(out / "dynamic_bench.json")]
    return res


def human(res: dict[str, Any]) -> str:
    """The result of :func:`run` as text for the terminal.

    Parameters
    ----------
    res : dict
        The result of :func:`run`.

    Returns
    -------
    str
        One line per measurement.
    """
    lines = []
    if "punch" in res:
        r = res["punch"]
        lines.append("punch (nu 1/3)  a0: " + " ".join(f"{x:5.2f}" for x in r["a0"]))
        lines.append("  k FEM / VV:      " + " ".join(
            f"{a:.3f}/{b:.3f}" for a, b in zip(r["k"], r["k_veletsos_verbic"], strict=True)))
        lines.append("  c FEM / VV:      " + " ".join(
            f"{a:.3f}/{b:.3f}" for a, b in zip(r["c"], r["c_veletsos_verbic"], strict=True)))
        lines.append(f"  max |k/k_VV - 1| {r['max_k_error_vs_vv']:.3f}, |c/c_VV - 1| "
                     f"{r['max_c_error_vs_vv']:.3f}, |c/0.85 - 1| {r['max_c_error_vs_lysmer']:.3f}"
                     f"; {r['dofs']} dofs, {r['wall']:.0f} s")
    if "static_limit" in res:
        r = res["static_limit"]
        lines.append(f"density -> 0: FEM {1e3 * r['tof_fem_dynamic']:.6f} ms vs quasi-static "
                     f"pipeline {1e3 * r['tof_quasi_static_pipeline']:.6f} ms "
                     f"({r['relative_difference']:+.2e})")
    if "point" in res:
        r = res["point"]
        lines.append(f"FEM point (10 MPa, 2200 kg/m3, PLA): {r['wall']:.0f} s, {r['dofs']} dofs, "
                     f"{r['steps']} steps; error {100 * r['error']:+.3f} % (box "
                     f"{100 * r['error_box']:+.3f} %); energy balance "
                     f"{r['energy_balance_relative']:.1e}, radiated {r['radiated_share']:.3f}")
    if "sweep_cost" in res:
        r = res["sweep_cost"]
        lines.append(f"sweep of {r['points']}: quasi-static {r['wall_quasi_static']:.2f} s, "
                     f"reduced {r['wall_reduced']:.2f} s (x{r['ratio']:.2f}); chain stage "
                     f"{r['wall_chain_stage_quasi_static']:.2f} s")
    lines.append("outputs: " + ", ".join(res.get("outputs", [])))
    return "\n".join(lines)
