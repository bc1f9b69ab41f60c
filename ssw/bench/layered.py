"""``ssw bench layered``: the layered oracle's convergence, its agreement with the FEM, speed.

Three parts (``--parts``, all by default), rigid sphere of the config (R = 9.53 mm), forces
compared over ``delta >= 1 um`` up to ``delta_max`` = 0.1 mm:

* ``convergence``: the oracle alone. No plate against Sneddon's exact sphere and Hertz for
  each ``--ratios`` (ring width / radius), with the observed order; 0.4 mm plates of the
  config's pla / al6061 / a36 on 10, 100 and 1000 MPa soils (nu 0.3), bonded and
  frictionless, at ring ratios 1/20, 1/40, 1/80 (the change 1/40 -> 1/80 and its
  Richardson estimate of the default's error, ``4/3`` of it for order 2) and with a ~30x
  denser Hankel quadrature (order 32, half-width panels, t_max 30, xi_low 1e-6).
* ``compare``: FEM (``ssw.contact.solve_curve``, the config's mesh, ``--compare-steps``
  increments; its curve is exact at each increment) against the oracle on the same
  plates, with the finite-size effects separated: the soil depth (oracle with a 1 m soil
  on a rigid base vs a half-space), the plate diameter (FEM with the study's 49.5 mm plate
  vs a ``--wide`` one), and what is left (FEM with the wide plate vs the 1 m deep oracle:
  the discretization errors plus the side rollers at 1 m). Also the FEM's own
  discretization error at its mesh: no plate vs Sneddon.
* ``speed``: wall time of a 1000-increment curve, fastest of ``--repeat``: the FEM
  (default engine, the study's geometry) cold (its condensed operators built, as for a
  geometry or Poisson's ratio no cache holds) and warm (operators reused: one more soil
  modulus), and the oracle (infinite plate on a half-space; it has nothing to reuse).

Writes ``layered_convergence.csv``, ``layered_plates.csv``, ``layered_compare.csv``,
``layered_speed.csv`` and ``layered_convergence.png`` under the output folder. Time it
with ``OPENBLAS_NUM_THREADS=1`` (as the workflow runs the contact jobs): the matrices are
small and threaded BLAS only contends on a shared machine.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from ssw import hertz
from ssw.h5io import atomic_write_text

RATIOS = (1 / 10, 1 / 20, 1 / 40, 1 / 80)
PLATES = ("pla", "al6061", "a36")
SOILS = (10e6, 100e6, 1000e6)
INTERFACES = ("frictionless", "bonded")
SOIL_NU = 0.3
THICKNESS = 0.4e-3
#: Plate diameter (m) of the FEM with a "wide" plate: its edge effect is below 5e-4 on the
#: scenes here (0.4 vs 0.8 m, steel on 10 MPa, the longest bending length).
WIDE = 0.4
#: Soil depth (m) of the FEM's sample (config contact.soil_depth), modelled in the oracle.
SOIL_DEPTH = 1.0
#: Lower end of the compared indentations (m), the thesis's delta_ref.
DELTA_MIN = 1e-6


def register(kinds: argparse._SubParsersAction) -> None:
    """Add the ``ssw bench layered`` command and its options.

    Parameters
    ----------
    kinds : argparse._SubParsersAction
        The ``ssw bench`` subcommands.
    """
    p = kinds.add_parser("layered", help="layered oracle: convergence, FEM agreement, speed")
    p.add_argument("--parts", nargs="+", choices=["convergence", "compare", "speed"],
                   default=["convergence", "compare", "speed"], help="parts to run")
    p.add_argument("--ratios", type=float, nargs="+", default=list(RATIOS),
                   help="ring width / radius of the no-plate convergence study")
    p.add_argument("--steps", type=int, default=1000, help="increments of the oracle's curves "
                   "and of the timed curves")
    p.add_argument("--compare-steps", type=int, default=20,
                   help="increments of the FEM curves compared")
    p.add_argument("--wide", type=float, default=WIDE, help="diameter (m) of the wide FEM plate")
    p.add_argument("--repeat", type=int, default=3, help="timed solves; the fastest is kept")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    p.set_defaults(func=run, human=human)


def _sneddon_at(delta: np.ndarray, E_star: float, radius: float) -> np.ndarray:
    """Sneddon's exact-sphere force (N) at the indentations ``delta`` (m), by inverting
    delta(a) on a dense grid of contact radii."""
    a = np.linspace(0.1 * np.sqrt(radius * delta.min()), 1.1 * np.sqrt(radius * delta.max()),
                    200_001)
    d_ref, f_ref = hertz.sneddon_sphere(a, E_star, radius)
    return np.interp(delta, d_ref, f_ref)


def _max_rel(a: np.ndarray, b: np.ndarray, delta: np.ndarray) -> float:
    m = delta >= DELTA_MIN * (1 - 1e-9)
    return float(np.max(np.abs(a[m] / b[m] - 1)))


def fem_curve(contact: dict[str, Any], soil: tuple[float, float],
              plate: tuple[float, float] | None, thickness: float, radius: float) -> Any:
    """The FEM's curve (``ssw.contact.solve_curve``), its solver released.

    Parameters
    ----------
    contact : dict
        The contact settings.
    soil : tuple of float
        The soil's Young's modulus (Pa) and Poisson's ratio.
    plate : tuple of float or None
        The plate's Young's modulus (Pa) and Poisson's ratio (None: no plate).
    thickness : float
        The plate's thickness, m.
    radius : float
        The indenter's radius, m.

    Returns
    -------
    ssw.curve.ForceCurve
        The force-indentation curve (N, m).
    """
    from ssw.contact import solve_curve

    curve, state = solve_curve(soil, plate, thickness, radius, contact)
    solver = state.get("solver") if isinstance(state, dict) else None
    if solver is not None and hasattr(solver, "destroy"):
        solver.destroy()
    return curve


def fem_halfspace_error(contact: dict[str, Any], radius: float) -> float:
    """The FEM's discretization error at its mesh: max relative force error of a no-plate
    curve (50 MPa, nu 0.3, the contact settings given, on a 3 m domain so that the
    boundary's effect, ~2e-4, stays out) against Sneddon's exact sphere.

    Parameters
    ----------
    contact : dict
        The contact settings.
    radius : float
        The indenter's radius, m.

    Returns
    -------
    float
        The error, relative.

    References
    ----------
    Sneddon, I. N. (1965). The relation between load and penetration in the axisymmetric
    Boussinesq problem for a punch of arbitrary profile. Int. J. Eng. Sci. 3, 47-57.
    """
    E = 50e6
    big = {**contact, "soil_radius": 3.0, "soil_depth": 3.0, "mesh_size_max": 0.3}
    curve = fem_curve(big, (E, SOIL_NU), None, 0.0, radius)
    ref = _sneddon_at(curve.delta, float(hertz.effective_modulus(E, SOIL_NU)), radius)
    return _max_rel(curve.force, ref, curve.delta)


def convergence_halfspace(ratios: list[float], radius: float, steps: int) -> list[dict]:
    """No plate: the oracle's force error vs Sneddon and Hertz per ring ratio.

    Parameters
    ----------
    ratios : list of float
        Ring width over radius.
    radius : float
        The indenter's radius, m.
    steps : int
        Increments of the curve.

    Returns
    -------
    list of dict
        Per ratio: ``rings``, the force and contact-radius errors (relative), the stated
        error and ``wall`` (s).
    """
    from ssw.contact.layered import LayeredSettings, increments, solve_stack
    from ssw.contact.layered_kernel import plate_on_soil

    E = 50e6
    E_star = float(hertz.effective_modulus(E, SOIL_NU))
    stack = plate_on_soil(None, 0.0, (E, SOIL_NU), "frictionless")
    deltas = increments(1e-4, steps)
    ref = _sneddon_at(deltas, E_star, radius)
    a_ref = np.linspace(0.1 * np.sqrt(radius * deltas[0]), 1.1 * np.sqrt(radius * deltas[-1]),
                        200_001)
    rows = []
    for rho in ratios:
        t0 = time.perf_counter()
        curve, _ = solve_stack(stack, radius, deltas, LayeredSettings(ring_ratio=rho))
        wall = time.perf_counter() - t0
        a_exact = np.interp(deltas, hertz.sneddon_sphere(a_ref, E_star, radius)[0], a_ref)
        rows.append({
            "ring_ratio": rho, "rings": curve.stats["rings"],
            "err_sneddon": _max_rel(curve.force, ref, deltas),
            "err_hertz": _max_rel(curve.force, hertz.force(deltas, E_star, radius), deltas),
            "err_radius": _max_rel(curve.contact_radius, a_exact, deltas),
            "stated": LayeredSettings(ring_ratio=rho).force_error, "wall": wall,
        })
    return rows


def convergence_plates(mats: dict, radius: float, steps: int) -> list[dict]:
    """Plates: self-convergence in the ring ratio and the quadrature's error, per scene.

    Parameters
    ----------
    mats : dict
        The materials library.
    radius : float
        The indenter's radius, m.
    steps : int
        Increments of the curves.

    Returns
    -------
    list of dict
        Per scene: the changes between ring ratios and the quadrature's error (relative).
    """
    from ssw.contact.layered import LayeredSettings, increments, solve_stack
    from ssw.contact.layered_kernel import plate_on_soil
    from ssw.contact.layered_rings import Quadrature

    deltas = increments(1e-4, steps)
    dense = Quadrature(order=32, growth=1.25, width=0.5, t_max=30.0, xi_low=1e-6)
    rows = []
    for key in PLATES:
        for E in SOILS:
            for iface in INTERFACES:
                stack = plate_on_soil((mats[key].E, mats[key].nu), THICKNESS, (E, SOIL_NU),
                                      iface)
                f = {rho: solve_stack(stack, radius, deltas, LayeredSettings(ring_ratio=rho))[0]
                     for rho in (1 / 20, 1 / 40, 1 / 80)}
                fq = solve_stack(stack, radius, deltas, LayeredSettings(quadrature=dense))[0]
                d40 = _max_rel(f[1 / 40].force, f[1 / 80].force, deltas)
                rows.append({
                    "plate": key, "soil_E": E, "interface": iface,
                    "change_20_40": _max_rel(f[1 / 20].force, f[1 / 40].force, deltas),
                    "change_40_80": d40, "richardson_40": 4.0 / 3.0 * d40,
                    "quadrature": _max_rel(f[1 / 40].force, fq.force, deltas),
                    "xi_nodes": f[1 / 40].stats["xi_nodes"], "xi_nodes_dense": fq.stats["xi_nodes"],
                })
    return rows


def compare(cfg: dict[str, Any], mats: dict, radius: float, steps: int, wide: float,
            scenes: list[tuple[str, float, str]] | None = None) -> dict[str, Any]:
    """FEM vs oracle per scene, with the finite-size effects separated (module docstring).

    Parameters
    ----------
    cfg : dict
        The study config.
    mats : dict
        The materials library.
    radius : float
        The indenter's radius, m.
    steps : int
        Increments of the FEM curves.
    wide : float
        The wide plate's diameter, m.
    scenes : list of tuple or None
        ``(plate key, soil E in Pa, interface)`` (None: every plate, soil and interface).

    Returns
    -------
    dict
        The error budget (relative), the rows per scene and the residual finite size.
    """
    from ssw.contact.layered import LayeredSettings, solve_curve

    contact = {**cfg["contact"], "steps": steps, "delta_max": 1e-4}
    contact.pop("delta_reach", None)
    depth = float(contact.get("soil_depth", SOIL_DEPTH))
    eps_fem = fem_halfspace_error(contact, radius)
    scenes = scenes or [(k, E, i) for k in PLATES for E in SOILS for i in INTERFACES]
    rows = []
    for key, E, iface in scenes:
        plate = (mats[key].E, mats[key].nu)
        c = {**contact, "interface": iface}
        o_hs = solve_curve((E, SOIL_NU), plate, THICKNESS, radius, c)
        o_1m = solve_curve((E, SOIL_NU), plate, THICKNESS, radius, c,
                           LayeredSettings(soil_depth=depth))
        f_study = fem_curve(c, (E, SOIL_NU), plate, THICKNESS, radius)
        f_wide = fem_curve({**c, "plate_diameter": wide}, (E, SOIL_NU), plate, THICKNESS, radius)
        signed = _signed_range(f_study.delta)
        rows.append({
            "plate": key, "soil_E": E, "interface": iface,
            "depth_effect": signed(o_1m.force, o_hs.force),
            "diameter_effect": signed(f_study.force, f_wide.force),
            "fem_wide_vs_oracle": signed(f_wide.force, o_1m.force),
            "fem_study_vs_oracle": signed(f_study.force, o_1m.force),
            "fem_study_vs_halfspace_oracle": signed(f_study.force, o_hs.force),
        })
    res = residual(contact, mats, radius, wide)
    eps_wide = max(abs(v) for r in res for k in ("plate_x2", "soil_radius_x2") for v in r[k])
    eps_oracle = LayeredSettings().force_error
    return {"fem_error": eps_fem, "oracle_error": eps_oracle, "wide_error": eps_wide,
            "tolerance": eps_fem + eps_oracle + eps_wide,
            "max_wide_vs_oracle": max(abs(v) for r in rows for v in r["fem_wide_vs_oracle"]),
            "wide": wide, "soil_depth": depth, "steps": steps, "rows": rows, "residual": res}


def residual(contact: dict[str, Any], mats: dict, radius: float,
             wide: float) -> list[dict[str, Any]]:
    """What is left of the finite geometry with the wide plate: the FEM's force with the
    plate twice as wide, and with the soil's radius (the side rollers) doubled, relative to
    the wide plate on the study's soil; steel on 10 MPa (the longest bending length).

    Parameters
    ----------
    contact : dict
        The contact settings.
    mats : dict
        The materials library.
    radius : float
        The indenter's radius, m.
    wide : float
        The wide plate's diameter, m.

    Returns
    -------
    list of dict
        Per interface: the signed ranges ``plate_x2`` and ``soil_radius_x2`` (relative).
    """
    plate, soil = (mats["a36"].E, mats["a36"].nu), (10e6, SOIL_NU)
    rows = []
    for iface in INTERFACES:
        c = {**contact, "interface": iface, "plate_diameter": wide}
        base = fem_curve(c, soil, plate, THICKNESS, radius)
        signed = _signed_range(base.delta)
        wider = fem_curve({**c, "plate_diameter": 2 * wide}, soil, plate, THICKNESS, radius)
        r2 = 2 * float(c["soil_radius"])
        side = fem_curve({**c, "soil_radius": r2}, soil, plate, THICKNESS, radius)
        rows.append({"interface": iface, "plate_x2": signed(wider.force, base.force),
                     "soil_radius_x2": signed(side.force, base.force)})
    return rows


def _signed_range(delta: np.ndarray) -> Any:
    """``f(a, b) -> (min, max)`` of ``a / b - 1`` over ``delta >= DELTA_MIN``."""
    m = delta >= DELTA_MIN * (1 - 1e-9)

    def signed(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
        r = a[m] / b[m] - 1
        return float(r.min()), float(r.max())

    return signed


def _fresh_store() -> Any:
    """A memory-only operator store of the FEM (``ssw.contact.operators``), so that its
    operators are built again: the cost of a scene no cache has seen. None if the FEM has
    no such store (then its default, disk-backed one is used)."""
    try:
        from ssw.contact.operators import OperatorStore
    except ImportError:
        return None
    return OperatorStore(directory=None)


def fem_timed(contact: dict[str, Any], soil: tuple[float, float],
              plate: tuple[float, float] | None, thickness: float, radius: float,
              store: Any) -> float:
    """Wall time (s) of one FEM curve with the operator store ``store`` (None: default).

    Parameters
    ----------
    contact : dict
        The contact settings.
    soil : tuple of float
        The soil's Young's modulus (Pa) and Poisson's ratio.
    plate : tuple of float or None
        The plate's Young's modulus (Pa) and Poisson's ratio (None: no plate).
    thickness : float
        The plate's thickness, m.
    radius : float
        The indenter's radius, m.
    store : object or None
        The operator store.

    Returns
    -------
    float
        The wall time, s.
    """
    from ssw.contact import solve_curve

    t0 = time.perf_counter()
    _, state = solve_curve(soil, plate, thickness, radius, contact, store)
    wall = time.perf_counter() - t0
    solver = state.get("solver") if isinstance(state, dict) else None
    if solver is not None and hasattr(solver, "destroy"):
        solver.destroy()
    return wall


def speed(cfg: dict[str, Any], mats: dict, radius: float, steps: int,
          repeat: int) -> list[dict]:
    """Wall time (s) of a curve, fastest of ``repeat``: the FEM (default engine, the study's
    geometry) cold (its operators built: a geometry or Poisson's ratio no cache holds) and
    warm (operators in memory: one more soil modulus of a study), the oracle (infinite plate
    on a half-space; nothing to reuse between soils) at the default and at ring ratio 1/20.

    Parameters
    ----------
    cfg : dict
        The study config.
    mats : dict
        The materials library.
    radius : float
        The indenter's radius, m.
    steps : int
        Increments per curve.
    repeat : int
        Timings; the fastest is kept.

    Returns
    -------
    list of dict
        Per plate: the wall times (s) and the speed-ups.
    """
    from ssw.contact.layered import LayeredSettings, solve_curve

    contact = {**cfg["contact"], "steps": steps, "delta_max": 1e-4}
    contact.pop("delta_reach", None)
    rows = []
    for key, E in (("none", 50e6), ("pla", 100e6), ("a36", 10e6)):
        plate = None if key == "none" else (mats[key].E, mats[key].nu)
        t = 0.0 if key == "none" else THICKNESS
        soil = (E, SOIL_NU)
        row: dict[str, Any] = {"plate": key, "soil_E": E}
        row["fem_cold"] = min(fem_timed(contact, soil, plate, t, radius, _fresh_store())
                              for _ in range(max(1, repeat)))
        warm = _fresh_store()
        fem_timed(contact, soil, plate, t, radius, warm)
        row["fem_warm"] = min(fem_timed(contact, (1.1 * E, SOIL_NU), plate, t, radius, warm)
                              for _ in range(max(1, repeat)))
        for name, settings in (("layered", LayeredSettings()),
                               ("layered_1_20", LayeredSettings(ring_ratio=1 / 20))):
            best = np.inf
            for _ in range(max(1, repeat)):
                t0 = time.perf_counter()
                solve_curve(soil, plate, t, radius, contact, settings)
                best = min(best, time.perf_counter() - t0)
            row[name] = best
        row["speedup_cold"] = row["fem_cold"] / row["layered"]
        row["speedup_warm"] = row["fem_warm"] / row["layered"]
        rows.append(row)
    return rows


def _csv(rows: list[dict]) -> str:
    def cell(v: Any) -> str:
        if isinstance(v, str):
            return v
        if isinstance(v, tuple):
            return ";".join(f"{x:.4e}" for x in v)
        return f"{v:.6g}"

    keys = list(rows[0])
    return ",".join(keys) + "\n" + "".join(",".join(cell(r[k]) for k in keys) + "\n"
                                           for r in rows)


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Run ``ssw bench layered`` (module docstring) and write its outputs under ``--output-dir``.

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
    from ssw.config import library, load_config

    cfg = load_config(args.config)
    mats = library(cfg)
    radius = float(cfg["indenter"]["radius"])
    out = Path(args.output_dir)
    res: dict[str, Any] = {"radius": radius, "steps": args.steps}
    if "convergence" in args.parts:
        rows = convergence_halfspace(sorted(args.ratios, reverse=True), radius, args.steps)
        rho = np.array([r["ring_ratio"] for r in rows])
        err = np.array([r["err_sneddon"] for r in rows])
        res["halfspace"] = rows
        res["observed_order"] = float(np.polyfit(np.log(rho), np.log(err), 1)[0]) \
            if len(rows) > 1 else float("nan")
        res["plates"] = convergence_plates(mats, radius, args.steps)
        atomic_write_text(out / "layered_convergence.csv", _csv(rows))
        atomic_write_text(out / "layered_plates.csv", _csv(res["plates"]))
        _plot(rows, res["plates"], out / "layered_convergence.png")
    if "compare" in args.parts:
        res["compare"] = compare(cfg, mats, radius, args.compare_steps, args.wide)
        atomic_write_text(out / "layered_compare.csv", _csv(res["compare"]["rows"]))
    if "speed" in args.parts:
        res["speed"] = speed(cfg, mats, radius, args.steps, args.repeat)
        atomic_write_text(out / "layered_speed.csv", _csv(res["speed"]))
    res["output_dir"] = str(out)
    return res


def _plot(rows: list[dict], plates: list[dict], path: Path) -> None:
    from ssw.plotting import pyplot, save_png

    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    rho = [r["ring_ratio"] for r in rows]
    ax[0].loglog(rho, [r["err_sneddon"] for r in rows], "o-", label="no plate vs Sneddon")
    ax[0].loglog(rho, [r["stated"] for r in rows], "k:", label="stated error 0.32 ratio^2")
    ax[0].set_xlabel("ring width / radius")
    ax[0].set_ylabel("max relative force error, delta >= 1 um")
    ax[0].legend(fontsize=8)
    ax[0].grid(True, which="both", alpha=0.3)
    lab = [f"{p['plate']} {p['soil_E'] / 1e6:g} {p['interface'][0]}" for p in plates]
    x = np.arange(len(plates))
    ax[1].semilogy(x, [p["richardson_40"] for p in plates], "o", label="ring error at 1/40")
    ax[1].semilogy(x, [max(p["quadrature"], 1e-16) for p in plates], "s",
                   label="quadrature vs ~30x the nodes")
    ax[1].set_xticks(x, lab, rotation=90, fontsize=7)
    ax[1].set_ylabel("relative force error (plates, 0.4 mm)")
    ax[1].legend(fontsize=8)
    ax[1].grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    save_png(fig, path)


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
    for r in res.get("halfspace", []):
        lines.append(f"no plate, ring ratio {r['ring_ratio']:.4g} ({r['rings']} rings): force "
                     f"error vs Sneddon {r['err_sneddon']:.2e} (stated {r['stated']:.1e}), vs "
                     f"Hertz {r['err_hertz']:.2e}, contact radius {r['err_radius']:.2e}, "
                     f"{r['wall']:.3f} s")
    if "observed_order" in res:
        lines.append(f"observed order {res['observed_order']:.2f} (theory 2)")
    for p in res.get("plates", []):
        lines.append(f"{p['plate']:6} {p['soil_E'] / 1e6:6g} MPa {p['interface']:12}: change "
                     f"1/20->1/40 {p['change_20_40']:.1e}, 1/40->1/80 {p['change_40_80']:.1e} "
                     f"(error at 1/40 ~{p['richardson_40']:.1e}), quadrature "
                     f"{p['quadrature']:.1e}")
    if "compare" in res:
        c = res["compare"]
        lines.append(f"FEM error at its mesh (no plate vs Sneddon): {c['fem_error']:.2e}; "
                     f"oracle's stated error {c['oracle_error']:.1e}; residual finite size "
                     f"with the {c['wide']:g} m plate {c['wide_error']:.1e}: tolerance "
                     f"{c['tolerance']:.2e}; max |FEM wide / oracle - 1| = "
                     f"{c['max_wide_vs_oracle']:.2e} ({c['steps']} increments)")

        def pct(v: tuple[float, float]) -> str:
            return f"[{100 * v[0]:+.3f}, {100 * v[1]:+.3f}] %"

        for r in c["residual"]:
            lines.append(f"residual finite size, a36 on 10 MPa {r['interface']}: plate "
                         f"{c['wide']:g} -> {2 * c['wide']:g} m {pct(r['plate_x2'])}, soil "
                         f"radius x2 {pct(r['soil_radius_x2'])}")
        for r in c["rows"]:
            lines.append(
                f"{r['plate']:6} {r['soil_E'] / 1e6:6g} MPa {r['interface']:12}: FEM "
                f"{c['wide']:g} m plate vs oracle (1 m soil) {pct(r['fem_wide_vs_oracle'])}; "
                f"49.5 mm plate {pct(r['fem_study_vs_oracle'])} (diameter effect "
                f"{pct(r['diameter_effect'])}, depth effect {pct(r['depth_effect'])})")
    for r in res.get("speed", []):
        lines.append(f"speed {r['plate']:5} on {r['soil_E'] / 1e6:g} MPa: FEM cold "
                     f"{r['fem_cold']:.3f} s, warm {r['fem_warm']:.3f} s; layered "
                     f"{r['layered']:.3f} s (x{r['speedup_cold']:.1f} cold, "
                     f"x{r['speedup_warm']:.2f} warm), at ring ratio 1/20 "
                     f"{r['layered_1_20']:.3f} s")
    lines.append(f"wrote CSVs under {res['output_dir']}")
    return "\n".join(lines)
