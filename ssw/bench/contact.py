"""``ssw bench contact``: work-precision of the contact FEM (mesh level -> dofs, error, time).

For each mesh level (``mesh_growth`` g, with ``mesh_size_contact = 5e-5 g`` so that the
graded zone starts at the same distance), one full no-plate curve (``steps`` increments)
is computed and compared over ``delta in [1e-6, delta_max]`` with Hertz (the issue's
target) and with the exact sphere of Sneddon (1965), the solution the FEM converges to.
The observed convergence rate is the least-squares slope of log(max error vs Sneddon)
against log(g); theory (piecewise-linear F(delta) between nodes entering contact) gives 2.
The domain defaults to 3 m (radius = depth), whose boundary effect (0.02 % at 1e-4 m)
stays below the discretization errors measured; ``--domain-study`` adds the boundary effect
of the domain size on F(delta_max) at the config's mesh, relative to a 10 m domain.
Writes ``contact_work_precision.csv`` and ``.png`` (and ``contact_domain.csv``) under the
output folder.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from ssw import hertz
from ssw.h5io import atomic_path, atomic_write_text

LEVELS = (0.4, 0.3, 0.2, 0.15, 0.1, 0.07)
#: Expected rate of the force error in the mesh growth (see the module docstring).
THEORY_RATE = 2.0


def register(kinds: argparse._SubParsersAction) -> None:
    from ssw.cli import add_json_flag

    p = kinds.add_parser("contact", help="work-precision of the contact FEM vs Hertz/Sneddon")
    p.add_argument("--levels", type=float, nargs="+", default=list(LEVELS),
                   help="mesh_growth values (element size / distance from the contact)")
    p.add_argument("--soil-nu", type=float, default=0.3, help="soil Poisson's ratio")
    p.add_argument("--steps", type=int, default=1000, help="increments per curve")
    p.add_argument("--repeat", type=int, default=3,
                   help="solves per level; the fastest wall time is kept (shared machines)")
    p.add_argument("--soil-radius", type=float, default=3.0,
                   help="domain radius = depth, m (0: the config's)")
    p.add_argument("--domain-study", action="store_true",
                   help="also measure the boundary effect of the domain size on the force")
    p.add_argument("--interfaces", action="store_true",
                   help="also compare the bonded, frictionless and unilateral interfaces")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    add_json_flag(p)
    p.set_defaults(func=run, human=human)


def level(
    g: float, nu: float, contact: dict[str, Any], radius: float, repeat: int = 1
) -> dict[str, Any]:
    """One mesh level: solve the no-plate curve and measure its errors and wall time
    (the fastest of ``repeat`` solves)."""
    from ssw.contact import solve_curve

    E = 50e6
    cfg = {**contact, "mesh_growth": g, "mesh_size_contact": 5e-5 * g}
    best = None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        curve, state = solve_curve((E, nu), None, 0.0, radius, cfg)
        wall = time.perf_counter() - t0
        state["solver"].destroy()
        if best is None or wall < best[0]:
            best = (wall, curve)
    wall, curve = best
    es = hertz.effective_modulus(E, nu)
    m = curve.delta >= 1e-6 * (1 - 1e-9)
    d = curve.delta[m]
    a_ref = np.linspace(0.2 * np.sqrt(radius * d[0]), 1.2 * np.sqrt(radius * d[-1]), 40000)
    d_ref, f_ref = hertz.sneddon_sphere(a_ref, es, radius)
    err_h = np.max(np.abs(curve.force[m] / hertz.force(d, es, radius) - 1))
    err_s = np.max(np.abs(curve.force[m] / np.interp(d, d_ref, f_ref) - 1))
    st = curve.stats
    return {
        "growth": g, "dofs": int(st["dofs"]), "elements": int(st["elements"]),
        "candidates": int(st["candidates"]), "err_hertz": float(err_h),
        "err_sneddon": float(err_s), "wall": wall,
        **{k: float(st[k]) for k in ("wall_mesh", "wall_assemble", "wall_factor",
                                     "wall_condense", "wall_lcp")},
    }


def run(args: argparse.Namespace) -> dict[str, Any]:
    from ssw.config import load_config

    cfg = load_config(args.config)
    contact = {**cfg["contact"], "steps": args.steps}
    if args.soil_radius > 0:
        contact.update(soil_radius=args.soil_radius, soil_depth=args.soil_radius,
                       mesh_size_max=args.soil_radius / 10)
    radius = float(cfg["indenter"]["radius"])
    rows = [level(g, args.soil_nu, contact, radius, args.repeat) for g in args.levels]
    domain = domain_study(cfg, args.soil_nu, radius, out_dir=Path(args.output_dir)) \
        if args.domain_study else None
    interfaces = interface_study(cfg, args.soil_nu, radius, out_dir=Path(args.output_dir)) \
        if args.interfaces else None
    g = np.array([r["growth"] for r in rows])
    e = np.array([r["err_sneddon"] for r in rows])
    rate = float(np.polyfit(np.log(g), np.log(e), 1)[0]) if len(rows) > 1 else float("nan")
    out = Path(args.output_dir)
    keys = list(rows[0])
    csv = ",".join(keys) + "\n" + "".join(
        ",".join(f"{r[k]:.6g}" for k in keys) + "\n" for r in rows)
    atomic_write_text(out / "contact_work_precision.csv", csv)
    _plot(rows, out / "contact_work_precision.png")
    ok = [r for r in rows if r["err_hertz"] <= 5e-3]
    best = min(ok, key=lambda r: r["wall"]) if ok else None
    return {
        "rows": rows, "observed_rate": rate, "theory_rate": THEORY_RATE,
        "fastest_within_0.5pct": best, "steps": args.steps, "soil_nu": args.soil_nu,
        "domain": domain, "interfaces": interfaces, "soil_radius": contact["soil_radius"],
        "csv": str(out / "contact_work_precision.csv"),
        "png": str(out / "contact_work_precision.png"),
    }


def domain_study(
    cfg: dict[str, Any], nu: float, radius: float, out_dir: Path,
    sizes: tuple[float, ...] = (0.1, 0.3, 1.0, 3.0, 10.0),
) -> list[dict[str, Any]]:
    """Boundary effect: F(delta_max) vs domain size L (radius = depth) at the config's mesh,
    relative to the largest L. Writes ``contact_domain.csv``."""
    from ssw.contact import solve_curve

    out = []
    for L in sizes:
        c = {**cfg["contact"], "steps": 10, "soil_radius": L, "soil_depth": L,
             "mesh_size_max": L / 10}
        curve, state = solve_curve((50e6, nu), None, 0.0, radius, c)
        state["solver"].destroy()
        out.append({"size": L, "force": float(curve.force[-1]), "dofs": int(curve.stats["dofs"])})
    for r in out:
        r["effect"] = r["force"] / out[-1]["force"] - 1
    atomic_write_text(out_dir / "contact_domain.csv", "size_m,force_N,dofs,effect\n" + "".join(
        f"{r['size']:g},{r['force']:.8g},{r['dofs']},{r['effect']:.4e}\n" for r in out))
    return out


def interface_study(
    cfg: dict[str, Any], nu: float, radius: float, out_dir: Path,
    plates: tuple[tuple[str, float], ...] = (("pla", 0.4e-3), ("pla", 0.1e-3), ("a36", 0.4e-3)),
) -> list[dict[str, Any]]:
    """Force at delta = 1e-6, 1e-5, 1e-4 m for each interface law, plates on 50 MPa soil,
    relative to the frictionless interface (the thesis's). Writes ``contact_interfaces.csv``."""
    from ssw.config import library
    from ssw.contact import solve_curve

    mats = library(cfg)
    out = []
    for key, t in plates:
        m = mats[key]
        res = {}
        for itf in ("bonded", "frictionless", "unilateral"):
            c = {**cfg["contact"], "steps": 100, "interface": itf}
            curve, state = solve_curve((50e6, nu), (m.E, m.nu), t, radius, c)
            state["solver"].destroy()
            res[itf] = curve.force[[0, 9, 99]]
        for itf, f in res.items():
            out.append({"plate": key, "thickness": t, "interface": itf,
                        **{f"F_{d}": float(v) for d, v in zip(("1e-6", "1e-5", "1e-4"), f,
                                                              strict=True)},
                        **{f"rel_{d}": float(v) for d, v in zip(
                            ("1e-6", "1e-5", "1e-4"), f / res["frictionless"] - 1, strict=True)}})
    keys = list(out[0])
    atomic_write_text(out_dir / "contact_interfaces.csv", ",".join(keys) + "\n" + "".join(
        ",".join(str(r[k]) if isinstance(r[k], str) else f"{r[k]:.6g}" for k in keys) + "\n"
        for r in out))
    return out


def _plot(rows: list[dict[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    w = [r["wall"] for r in rows]
    for key, lab in (("err_hertz", "vs Hertz"), ("err_sneddon", "vs Sneddon (exact sphere)")):
        ax[0].loglog([r["dofs"] for r in rows], [r[key] for r in rows], "o-", label=lab)
        ax[1].loglog(w, [r[key] for r in rows], "o-", label=lab)
    for a, xl in ((ax[0], "dofs"), (ax[1], "wall time per 1000-step curve (s)")):
        a.axhline(5e-3, color="k", ls=":", lw=1, label="0.5 % goal")
        a.set_xlabel(xl)
        a.set_ylabel("max relative force error, delta in [1e-6, 1e-4] m")
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=130)
    plt.close(fig)


def human(res: dict[str, Any]) -> str:
    lines = [f"{'growth':>7} {'dofs':>7} {'err vs Hertz':>13} {'err vs Sneddon':>15} "
             f"{'wall s':>7} (mesh/asm/factor/condense/lcp)"]
    for r in res["rows"]:
        lines.append(
            f"{r['growth']:7.3g} {r['dofs']:7d} {r['err_hertz']:13.2e} {r['err_sneddon']:15.2e} "
            f"{r['wall']:7.3f} ({r['wall_mesh']:.3f}/{r['wall_assemble']:.3f}/"
            f"{r['wall_factor']:.3f}/{r['wall_condense']:.3f}/{r['wall_lcp']:.3f})")
    lines.append(f"observed convergence rate (error vs Sneddon ~ growth^p): p = "
                 f"{res['observed_rate']:.2f} (theory {res['theory_rate']:.0f})")
    b = res["fastest_within_0.5pct"]
    if b:
        lines.append(f"fastest curve within 0.5 % of Hertz: growth {b['growth']:g}, "
                     f"{b['dofs']} dofs, {b['wall']:.3f} s for {res['steps']} increments")
    lines.append(f"(domain radius = depth = {res['soil_radius']:g} m)")
    for r in res["domain"] or []:
        lines.append(f"domain {r['size']:5g} m: F(delta_max) = {r['force']:.6g} N, boundary "
                     f"effect {100 * r['effect']:+.3f} % vs the largest")
    for r in res["interfaces"] or []:
        lines.append(f"{r['plate']} {r['thickness'] * 1e3:g} mm {r['interface']:>12}: F = "
                     f"{r['F_1e-6']:.4g}, {r['F_1e-5']:.4g}, {r['F_1e-4']:.4g} N at delta 1e-6, "
                     f"1e-5, 1e-4 m ({100 * r['rel_1e-6']:+.1f}, {100 * r['rel_1e-5']:+.1f}, "
                     f"{100 * r['rel_1e-4']:+.1f} % vs frictionless)")
    lines.append(f"wrote {res['csv']} and {res['png']}")
    return "\n".join(lines)
