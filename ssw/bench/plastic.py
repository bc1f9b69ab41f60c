"""``ssw bench contact --plastic`` (= ``ssw bench plastic``): the cost of an elasto-plastic
loading-unloading curve.

A rigid sphere (the config's indenter) on a von Mises half-space (E, nu, Y given; default
PCF 08: 38 MPa, 0.34, Y = its catalogue compressive strength 1.4 MPa), loaded to
``delta_max`` in ``--plastic-steps`` increments and unloaded in as many (up to where the
sphere leaves the surface), on the config's contact mesh (``--mesh-growth`` coarsens it),
one core. Reports the wall time, increments, Newton iterations, factorizations, dofs, first
yield (and Johnson's), residual indentation and dissipated work; writes
``plastic_bench.json`` and ``plastic_curve.png`` (the curve with the elastic Hertz law and
the first yield) under the output folder.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from ssw import hertz
from ssw.h5io import write_json


def register(kinds: argparse._SubParsersAction) -> None:
    from ssw.cli import add_json_flag

    p = kinds.add_parser("plastic", help="cost of an elasto-plastic loading-unloading curve "
                         "(= contact --plastic)")
    add_arguments(p)
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    add_json_flag(p)
    p.set_defaults(func=run_plastic, human=human, plastic=True)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--plastic", action="store_true",
                   help="time an elasto-plastic loading-unloading curve instead")
    p.add_argument("--plastic-steps", type=int, default=250,
                   help="loading increments (as many again to unload)")
    p.add_argument("--plastic-E", type=float, default=38e6, help="soil E, Pa (plastic)")
    p.add_argument("--plastic-nu", type=float, default=0.34, help="soil nu (plastic)")
    p.add_argument("--plastic-Y", type=float, default=1.4e6,
                   help="von Mises yield stress, Pa (plastic)")
    p.add_argument("--plastic-delta-max", type=float, default=1e-4,
                   help="indentation at the end of loading, m (plastic)")
    p.add_argument("--plastic-growth", type=float, default=None,
                   help="mesh growth of the plastic curve (default: the config's)")


def run_plastic(args: argparse.Namespace) -> dict[str, Any]:
    from ssw.config import load_config
    from ssw.constitutive import VonMises
    from ssw.contact.plastic import johnson_first_yield, solve_plastic_scene, summary

    cfg = load_config(args.config)
    contact = {**cfg["contact"], "steps": int(args.plastic_steps),
               "delta_max": float(args.plastic_delta_max), "delta_mode": "fixed"}
    contact.pop("delta_reach", None)
    if args.plastic_growth is not None:
        contact["mesh_growth"] = args.plastic_growth
        contact["mesh_size_contact"] = 5e-5 * args.plastic_growth
    radius = float(cfg["indenter"]["radius"])
    E, nu, Y = float(args.plastic_E), float(args.plastic_nu), float(args.plastic_Y)
    t0 = time.perf_counter()
    curve = solve_plastic_scene((E, nu), VonMises(Y), radius, contact, unload=True)
    wall = time.perf_counter() - t0
    Fy, _ = johnson_first_yield(E, nu, Y, radius)
    st = curve.stats
    res = {"soil_E": E, "soil_nu": nu, "yield_stress": Y, "indenter_radius": radius,
           "mesh_growth": contact.get("mesh_growth"), **summary(curve),
           "johnson_first_yield_force": Fy, "wall": wall, **st,
           "wall_per_factorization": st["wall_total"] / max(st["factorizations"], 1)}
    out = Path(args.output_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "plastic_bench.json", res, {"contact": contact, "E": E, "nu": nu,
                                                  "Y": Y, "radius": radius})
    _plot(curve, E, nu, radius, Fy, res, out / "plastic_curve.png")
    res["outputs"] = [str(out / "plastic_bench.json"), str(out / "plastic_curve.png")]
    res["plastic"] = True
    return res


def _plot(curve: Any, E: float, nu: float, radius: float, Fy: float, res: dict[str, Any],
          path: Path) -> None:
    from ssw.plotting import pyplot, save_png

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.2))
    d = np.linspace(0, curve.delta.max(), 200)
    ax.plot(d * 1e6, hertz.force(d, hertz.effective_modulus(E, nu), radius), "k:",
            label="elastic (Hertz)")
    for b, lab in ((0, "loading"), (1, "unloading")):
        m = curve.branch == b
        ax.plot(curve.delta[m] * 1e6, curve.force[m], "-", label=f"von Mises, {lab}")
    ax.axhline(Fy, color="gray", lw=0.8, ls="--", label="first yield (Johnson)")
    ax.set_xlabel("indentation (um)")
    ax.set_ylabel("force (N)")
    ax.set_title(f"{res['increments']} increments in {res['wall']:.1f} s, one core",
                 fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save_png(fig, path)


def human(res: dict[str, Any]) -> str:
    def g(x: Any) -> str:
        return "none" if x is None else f"{x:.4g}"

    return (f"plastic curve: {res['increments']} increments ({res['dofs']} dofs), "
            f"{res['newton_iterations']} Newton iterations, {res['factorizations']} "
            f"factorizations, {res['wall']:.2f} s ({res['wall_per_factorization'] * 1e3:.1f} "
            f"ms per factorization); first yield {g(res['first_yield_force'])} N (Johnson "
            f"{res['johnson_first_yield_force']:.4g} N), residual indentation "
            f"{g(res['residual_indentation'])} m, dissipated {res['dissipated_work']:.4g} J")
