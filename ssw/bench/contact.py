"""``ssw bench contact``: work-precision and cost of the contact FEM, and of the ``fem`` wall.

Reference cost, timed in the same run: one sparse LU (scipy's SuperLU, its default COLAMD
ordering) of the 65 536-dof five-point Laplacian of a 256 x 256 grid. Every wall time is
the best of ``--repeat`` (a shared machine's noise only adds time).

Tables:

* ``levels`` (per mesh growth ``g``, ``mesh_size_contact = 5e-5 g``): one no-plate curve
  (``steps`` increments to ``delta_max``, nu 0.3, 3 m domain) against Hertz and the exact
  sphere of Sneddon (1965): max and rms relative errors over ``delta in [1e-6, delta_max]``;
  the wall time cold (mesh, assembly, factorization and condensation of the operators, then
  the scene) and warm (operators in memory: the scene's dense condensation and LCP path).
  The observed convergence rate is the slope of log(max error vs Sneddon) in log g
  (theory 2: F(delta) is piecewise linear between nodes entering the contact).
* ``goals``: the study's default curves (the config's contact settings, 1000 increments):
  no plate for nu 0.1, 0.3, 0.5 (error vs Hertz over [1e-6, 1e-4] m) and the 0.4 mm PLA
  plate, cold and warm, as multiples of the reference LU (the goal: <= 0.5).
* ``engines`` (``--engines``): the monolithic engine on the same curves.
* ``wall`` (``--wall``): the ``fem`` wall over the thesis's Set 3 sweep (E 10..1000 MPa x
  nu 0.1/0.3/0.5): build time cold (operators per nu) and warm, and the TOF of the exact
  law against the same law tabulated on 400 uniform cells (linear in F) and as the
  ``table`` wall's F/d^1.5 table: what a resampled representation would cost.
* ``domain`` (``--domain-study``) and ``interfaces`` (``--interfaces``) as before.

Writes ``contact_work_precision.csv`` and ``.png``, ``contact_bench.json`` under the output
folder.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from ssw import hertz
from ssw.bench import best_time
from ssw.h5io import atomic_write_text, write_json

LEVELS = (0.4, 0.3, 0.2, 0.15, 0.1, 0.07)
#: Expected rate of the force error in the mesh growth (see the module docstring).
THEORY_RATE = 2.0
#: Grid of the reference LU (five-point Laplacian, N^2 dofs).
LAPLACE_N = 256


def register(kinds: argparse._SubParsersAction) -> None:
    """Add the ``ssw bench contact`` command and its options.

    Parameters
    ----------
    kinds : argparse._SubParsersAction
        The ``ssw bench`` subcommands.
    """
    p = kinds.add_parser("contact", help="work-precision and cost of the contact FEM")
    p.add_argument("--levels", type=float, nargs="+", default=list(LEVELS),
                   help="mesh_growth values (element size / distance from the contact)")
    p.add_argument("--soil-nu", type=float, default=0.3, help="soil Poisson's ratio (levels)")
    p.add_argument("--steps", type=int, default=1000, help="increments per curve")
    p.add_argument("--repeat", type=int, default=3,
                   help="timings per measurement; the fastest is kept (shared machines)")
    p.add_argument("--soil-radius", type=float, default=3.0,
                   help="domain radius = depth of the levels, m (0: the config's)")
    p.add_argument("--engines", action="store_true",
                   help="also time the monolithic engine on the goal curves")
    p.add_argument("--wall", action="store_true",
                   help="also measure the fem wall over the Set 3 sweep (cost, TOF)")
    p.add_argument("--domain-study", action="store_true",
                   help="also measure the boundary effect of the domain size on the force")
    p.add_argument("--sample", action="store_true",
                   help="finite samples: cost and force of a curve on blocks against the "
                   "half-space box (contact_sample.csv)")
    p.add_argument("--interfaces", action="store_true",
                   help="also compare the bonded, frictionless and unilateral interfaces")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    from ssw.bench.plastic import add_arguments

    add_arguments(p)
    p.set_defaults(func=run, human=human)


def reference_lu(repeat: int) -> dict[str, Any]:
    """Seconds of one SuperLU factorization of the 256 x 256 five-point Laplacian.

    Parameters
    ----------
    repeat : int
        Timings; the fastest is kept.

    Returns
    -------
    dict
        ``dofs``, ``wall`` (s) and ``solver``.
    """
    import scipy.sparse as sp
    from scipy.sparse.linalg import splu

    n = LAPLACE_N
    T = sp.diags_array([-1.0, 2.0, -1.0], offsets=[-1, 0, 1], shape=(n, n))
    eye = sp.eye_array(n)
    A = (sp.kron(eye, T) + sp.kron(T, eye)).tocsc()
    t, _ = best_time(lambda: splu(A), repeat)
    return {"dofs": n * n, "wall": t, "solver": "scipy.sparse.linalg.splu (SuperLU, COLAMD)"}


def _curve(soil: tuple[float, float], plate: Any, t: float, radius: float,
           contact: dict[str, Any], cold: bool, store: Any = None, engine: str = "substructured"
           ) -> Any:
    from ssw.contact import solve_curve
    from ssw.contact.operators import OperatorStore

    if engine == "monolithic":
        curve, state = solve_curve(soil, plate, t, radius, contact, engine=engine)
        state["solver"].destroy()
        return curve
    st = OperatorStore(None) if cold else store
    curve, _ = solve_curve(soil, plate, t, radius, contact, st)
    return curve


def _errors(curve: Any, E: float, nu: float, radius: float, lo: float = 1e-6
            ) -> dict[str, float]:
    """Max and rms relative force errors vs Hertz and Sneddon on ``delta >= lo``."""
    es = hertz.effective_modulus(E, nu)
    m = curve.delta >= lo * (1 - 1e-9)
    d, F = curve.delta[m], curve.force[m]
    a_ref = np.linspace(0.2 * np.sqrt(radius * d[0]), 1.2 * np.sqrt(radius * d[-1]), 40000)
    d_ref, f_ref = hertz.sneddon_sphere(a_ref, es, radius)
    eh = F / hertz.force(d, es, radius) - 1
    es_ = F / np.interp(d, d_ref, f_ref) - 1
    return {"err_hertz": float(np.max(np.abs(eh))), "err_sneddon": float(np.max(np.abs(es_))),
            "rms_sneddon": float(np.sqrt(np.mean(es_**2)))}


def level(g: float, nu: float, contact: dict[str, Any], radius: float, repeat: int = 1
          ) -> dict[str, Any]:
    """One mesh level (module docstring).

    Parameters
    ----------
    g : float
        The mesh growth (element size over distance from the contact).
    nu : float
        The soil's Poisson's ratio.
    contact : dict
        The contact settings.
    radius : float
        The indenter's radius, m.
    repeat : int
        Timings; the fastest is kept.

    Returns
    -------
    dict
        The mesh's size, its force errors (relative), and its cold and warm wall times and
        stage times, s.
    """
    from ssw.contact.operators import OperatorStore

    E = 50e6
    cfg = {**contact, "mesh_growth": g, "mesh_size_contact": 5e-5 * g}
    t_cold, curve = best_time(lambda: _curve((E, nu), None, 0.0, radius, cfg, True), repeat)
    store = OperatorStore(None)
    _curve((E, nu), None, 0.0, radius, cfg, False, store)
    t_warm, _ = best_time(lambda: _curve((E, nu), None, 0.0, radius, cfg, False, store), repeat)
    st = curve.stats
    return {
        "growth": g, "dofs": int(st["dofs"]), "elements": int(st["elements"]),
        "candidates": int(st["candidates"]), **_errors(curve, E, nu, radius),
        "wall": t_cold, "wall_warm": t_warm,
        **{k: float(st[k]) for k in ("wall_mesh", "wall_assemble", "wall_factor",
                                     "wall_condense", "wall_lcp")},
    }


def goals(cfg: dict[str, Any], radius: float, repeat: int, lu: float, engines: bool
          ) -> list[dict[str, Any]]:
    """The benchmark's curves (module docstring), cold and warm, relative to the reference LU.

    Parameters
    ----------
    cfg : dict
        The study config.
    radius : float
        The indenter's radius, m.
    repeat : int
        Timings; the fastest is kept.
    lu : float
        The reference LU's wall time, s.
    engines : bool
        Also time the monolithic engine.

    Returns
    -------
    list of dict
        One row per curve: cold and warm wall times (s, and over ``lu``), stage times (s),
        errors (relative).
    """
    from ssw.config import library
    from ssw.contact.operators import OperatorStore

    contact = {**cfg["contact"], "steps": 1000, "delta_mode": "fixed"}
    contact.pop("delta_reach", None)
    pla = library(cfg)["pla"]
    cases = [(f"no plate, nu {nu:g}", (50e6, nu), None, 0.0) for nu in (0.1, 0.3, 0.5)]
    cases.append(("PLA 0.4 mm, nu 0.3", (50e6, 0.3), (pla.E, pla.nu), 0.4e-3))
    rows = []
    for name, soil, plate, t in cases:
        t_cold, curve = best_time(lambda s=soil, p=plate, t=t: _curve(s, p, t, radius, contact,
                                                                  True), repeat)
        store = OperatorStore(None)
        _curve(soil, plate, t, radius, contact, False, store)
        t_warm, warm = best_time(lambda s=soil, p=plate, t=t, st=store: _curve(
            s, p, t, radius, contact, False, st), repeat)
        row = {"case": name, "cold": t_cold, "warm": t_warm,
               "cold_per_lu": t_cold / lu, "warm_per_lu": t_warm / lu,
               "stats_wall_total_warm": float(warm.stats["wall_total"]),
               **{k: float(curve.stats[k]) for k in ("wall_mesh", "wall_assemble",
                                                     "wall_factor", "wall_condense",
                                                     "wall_lcp")}}
        if plate is None:
            row["err_hertz"] = _errors(curve, *soil, radius)["err_hertz"]
        if engines:
            t_mono, mono = best_time(lambda s=soil, p=plate, t=t: _curve(
                s, p, t, radius, contact, True, engine="monolithic"), repeat)
            row["monolithic"] = t_mono
            row["monolithic_per_lu"] = t_mono / lu
            row["engines_max_rel_diff"] = float(np.max(np.abs(curve.force / mono.force - 1)))
        rows.append(row)
    return rows


def wall_study(cfg: dict[str, Any], repeat: int) -> dict[str, Any]:
    """The fem wall on the Set 3 sweep: cost and TOF of its representations.

    Parameters
    ----------
    cfg : dict
        The study config.
    repeat : int
        Timings; the fastest is kept.

    Returns
    -------
    dict
        Wall times (s) and TOF differences of the representations.
    """
    from ssw.chain.params import ChainParams
    from ssw.chain.wall_table import TableWall, _resample
    from ssw.contact.operators import OperatorStore
    from ssw.curve import ForceCurve
    from ssw.tof import api
    from ssw.walls.fem import PiecewiseLinearWall, fem_wall

    params = ChainParams.from_config(cfg)
    E = np.arange(10e6, 1000e6 + 1, 10e6)
    nus = (0.1, 0.3, 0.5)
    EE, NN = np.meshgrid(E, nus)
    EE, NN = EE.ravel(), NN.ravel()
    contact = cfg["contact"]
    t_cold, _ = best_time(lambda: fem_wall(params, EE, NN, contact=contact,
                                       operators=OperatorStore(None)), 1)
    store = OperatorStore(None)
    fem_wall(params, EE, NN, contact=contact, operators=store)
    t_warm, wall = best_time(lambda: fem_wall(params, EE, NN, contact=contact, operators=store),
                         repeat)
    t_tof, tof = best_time(lambda: api.tof(EE, NN, params, "fem", contact=contact,
                                       operators=store), repeat)
    _, run = api.peaks(EE, NN, params, "fem", contact=contact, operators=store)
    # the same law resampled: 400 uniform cells up to d_exact, linear in F
    cells = 400
    grid = wall.d_exact[:, None] * np.linspace(0.0, 1.0, cells + 1)[None, :]
    F = np.stack([wall.force(grid[:, j]) for j in range(cells + 1)], axis=1)
    b = np.diff(F, axis=1) / np.diff(grid, axis=1)
    a = F[:, :-1] - b * grid[:, :-1]
    a, b = np.column_stack([a, a[:, -1]]), np.column_stack([b, b[:, -1]])
    U = np.column_stack([np.zeros(len(E) * 3), np.cumsum(
        0.5 * (F[:, 1:] + F[:, :-1]) * np.diff(grid, axis=1), axis=1)])
    grid_wall = PiecewiseLinearWall(grid, a, b, U, wall.d_exact.copy(), wall.force_error)
    from ssw.chain.dense import dense_peaks
    from ssw.chain.integrate import simulate

    def tof_of(w: Any) -> np.ndarray:
        r = simulate(params, w)
        return dense_peaks(r).tof

    tof_grid = tof_of(grid_wall)
    rows = [_resample(ForceCurve(g[1:], f[1:], np.zeros(cells), {}), 1.0)
            for g, f in zip(grid, F, strict=True)]
    h, gtab, fl, ne = (np.array(x) for x in zip(*rows, strict=True))
    tof_table = tof_of(TableWall(h, gtab, fl, ne))
    return {
        "scenes": int(EE.size), "build_cold": t_cold, "build_warm": t_warm,
        "build_warm_per_scene": t_warm / EE.size, "tof_sweep": t_tof,
        "pieces_max": int(wall.d.shape[1] - 1),
        "peak_over_d_exact_max": float(np.max(run.peak_wall_indentation / wall.d_exact)),
        "tof_diff_grid400_linear": float(np.max(np.abs(tof_grid / tof - 1))),
        "tof_diff_table400_f_over_d15": float(np.max(np.abs(tof_table / tof - 1))),
        "force_error": wall.force_error,
    }


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Run ``ssw bench contact`` (module docstring) and write its outputs under ``--output-dir``.

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
    from ssw.config import load_config

    if getattr(args, "plastic", False):
        from ssw.bench.plastic import run_plastic

        return run_plastic(args)

    cfg = load_config(args.config)
    if getattr(args, "sample", False):
        out = Path(args.output_dir)
        rows = sample_study(cfg, float(cfg["indenter"]["radius"]), args.steps, args.repeat,
                            out)
        result = {"sample": rows, "steps": args.steps,
                  "csv": str(out / "contact_sample.csv")}
        write_json(out / "contact_sample.json", result, result)
        return result
    contact = {**cfg["contact"], "steps": args.steps, "delta_mode": "fixed"}
    contact.pop("delta_reach", None)
    if args.soil_radius > 0:
        contact.update(soil_radius=args.soil_radius, soil_depth=args.soil_radius,
                       mesh_size_max=args.soil_radius / 10)
    radius = float(cfg["indenter"]["radius"])
    lu = reference_lu(args.repeat)
    rows = [level(g, args.soil_nu, contact, radius, args.repeat) for g in args.levels]
    goal_rows = goals(cfg, radius, args.repeat, lu["wall"], args.engines)
    wall = wall_study(cfg, args.repeat) if args.wall else None
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
    result = {
        "reference_lu": lu, "rows": rows, "goals": goal_rows, "wall": wall,
        "observed_rate": rate, "theory_rate": THEORY_RATE,
        "fastest_within_0.5pct": best, "steps": args.steps, "soil_nu": args.soil_nu,
        "domain": domain, "interfaces": interfaces, "soil_radius": contact["soil_radius"],
        "csv": str(out / "contact_work_precision.csv"),
        "png": str(out / "contact_work_precision.png"),
    }
    write_json(out / "contact_bench.json", result, result)
    return result


def domain_study(
    cfg: dict[str, Any], nu: float, radius: float, out_dir: Path,
    sizes: tuple[float, ...] = (0.1, 0.3, 1.0, 3.0, 10.0),
) -> list[dict[str, Any]]:
    """Boundary effect: F(delta_max) vs domain size L (radius = depth) at the config's mesh,
    relative to the largest L. Writes ``contact_domain.csv``.

    Parameters
    ----------
    cfg : dict
        The study config.
    nu : float
        The soil's Poisson's ratio.
    radius : float
        The indenter's radius, m.
    out_dir : pathlib.Path
        The output folder.
    sizes : tuple of float
        The domain sizes ``L``, m.

    Returns
    -------
    list of dict
        Per size: ``size`` (m), ``force`` (N), ``dofs`` and ``effect`` (relative).
    """
    out = []
    for L in sizes:
        c = {**cfg["contact"], "steps": 10, "soil_radius": L, "soil_depth": L,
             "mesh_size_max": L / 10, "delta_mode": "fixed"}
        curve = _curve((50e6, nu), None, 0.0, radius, c, True)
        out.append({"size": L, "force": float(curve.force[-1]), "dofs": int(curve.stats["dofs"])})
    for r in out:
        r["effect"] = r["force"] / out[-1]["force"] - 1
    atomic_write_text(out_dir / "contact_domain.csv", "size_m,force_N,dofs,effect\n" + "".join(
        f"{r['size']:g},{r['force']:.8g},{r['dofs']},{r['effect']:.4e}\n" for r in out))
    return out


def sample_study(
    cfg: dict[str, Any], radius: float, steps: int, repeat: int, out_dir: Path,
    blocks: tuple[tuple[float, str], ...] = ((0.06, "bonded"), (0.04, "bonded"),
                                             (0.02, "bonded"), (0.02, "sliding")),
) -> list[dict[str, Any]]:
    """A curve (``steps`` increments to 0.1 mm; PCF 08: 38 MPa, nu 0.34; no plate and the
    0.4 mm PLA plate) on the half-space box and on 130 x 180 mm foam blocks (ssw.sample):
    cold (mesh, operators, path: a fresh store) and warm (operators in memory) seconds,
    best of ``repeat``; the dofs; the force at 0.1 mm relative to the half-space's. Writes
    ``contact_sample.csv``.

    Parameters
    ----------
    cfg : dict
        The study config.
    radius : float
        The indenter's radius, m.
    steps : int
        Increments per curve.
    repeat : int
        Timings; the fastest is kept.
    out_dir : pathlib.Path
        The output folder.
    blocks : tuple of (float, str)
        The blocks: height (m) and base contact (``bonded`` or ``sliding``).

    Returns
    -------
    list of dict
        Per plate and sample: ``plate_thickness`` (m), ``sample``, ``dofs``, ``cold`` and
        ``warm`` (s), ``force_rel``.
    """
    import gc

    from ssw.bench import best_time
    from ssw.config import library
    from ssw.contact.operators import OperatorStore
    from ssw.sample import Sample, equivalent_radius

    pla = library(cfg)["pla"]
    c0 = {**cfg["contact"], "steps": steps, "delta_max": 1e-4, "delta_mode": "fixed"}
    out = []
    for plate, t in ((None, 0.0), ((pla.E, pla.nu), 0.4e-3)):
        half = None
        for block in (None, *blocks):
            smp = None if block is None else Sample(block[0], equivalent_radius(0.13, 0.18),
                                                    block[1], "free")
            c = c0 if smp is None else smp.contact_settings(c0)
            def solve(c=c, plate=plate, t=t, store=None):
                return _curve((38e6, 0.34), plate, t, radius, c, store is None, store)

            gc.collect()  # the previous blocks' operators: not this curve's time
            cold, curve = best_time(solve, repeat)
            store = OperatorStore(None)
            solve(store=store)
            gc.collect()
            warm, _ = best_time(lambda s=store, f=solve: f(store=s), repeat)
            half = curve if half is None else half
            out.append({"plate_thickness": t, "sample": "half-space" if smp is None
                        else smp.key, "dofs": int(curve.stats["dofs"]), "cold": cold,
                        "warm": warm, "force_rel": float(curve.force[-1] / half.force[-1])})
    keys = list(out[0])
    atomic_write_text(out_dir / "contact_sample.csv", ",".join(keys) + "\n" + "".join(
        ",".join(str(r[k]) if isinstance(r[k], str) else f"{r[k]:.6g}" for k in keys) + "\n"
        for r in out))
    return out


def interface_study(
    cfg: dict[str, Any], nu: float, radius: float, out_dir: Path,
    plates: tuple[tuple[str, float], ...] = (("pla", 0.4e-3), ("pla", 0.1e-3), ("a36", 0.4e-3)),
) -> list[dict[str, Any]]:
    """Force at delta = 1e-6, 1e-5, 1e-4 m for each interface law, plates on 50 MPa soil,
    relative to the frictionless interface (the thesis's). Writes ``contact_interfaces.csv``.

    Parameters
    ----------
    cfg : dict
        The study config.
    nu : float
        The soil's Poisson's ratio.
    radius : float
        The indenter's radius, m.
    out_dir : pathlib.Path
        The output folder.
    plates : tuple of (str, float)
        The plates: material key and thickness, m.

    Returns
    -------
    list of dict
        Per plate and interface: the forces ``F_<delta>`` (N) and ``rel_<delta>``, their
        relative differences from the frictionless ones.
    """
    from ssw.config import library
    from ssw.contact.operators import OperatorStore

    mats = library(cfg)
    store = OperatorStore(None)
    out = []
    for key, t in plates:
        m = mats[key]
        res = {}
        for itf in ("bonded", "frictionless", "unilateral"):
            c = {**cfg["contact"], "steps": 100, "interface": itf, "delta_mode": "fixed"}
            curve = _curve((50e6, nu), (m.E, m.nu), t, radius, c, False, store)
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
    from ssw.plotting import pyplot, save_png

    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    for key, lab in (("err_hertz", "vs Hertz"), ("err_sneddon", "vs Sneddon (exact sphere)")):
        ax[0].loglog([r["dofs"] for r in rows], [r[key] for r in rows], "o-", label=lab)
        ax[1].loglog([r["wall"] for r in rows], [r[key] for r in rows], "o-",
                     label=f"{lab}, cold")
        ax[1].loglog([r["wall_warm"] for r in rows], [r[key] for r in rows], "s--",
                     label=f"{lab}, operators cached")
    for a, xl in ((ax[0], "dofs"), (ax[1], "wall time per curve (s)")):
        a.axhline(5e-3, color="k", ls=":", lw=1, label="0.5 % goal")
        a.set_xlabel(xl)
        a.set_ylabel("max relative force error, delta in [1e-6, delta_max] m")
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=7)
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
    if res.get("plastic"):
        from ssw.bench.plastic import human as plastic_human

        return plastic_human(res)
    lu = res["reference_lu"]
    lines = [f"reference: one LU of the {lu['dofs']}-dof 2-D Laplacian ({lu['solver']}): "
             f"{lu['wall']:.3f} s",
             f"{'growth':>7} {'dofs':>7} {'err Hertz':>10} {'err Sneddon':>12} {'rms Sn.':>9} "
             f"{'cold s':>7} {'warm s':>7} (cold: mesh/asm/factor/condense/lcp)"]
    for r in res["rows"]:
        lines.append(
            f"{r['growth']:7.3g} {r['dofs']:7d} {r['err_hertz']:10.2e} {r['err_sneddon']:12.2e} "
            f"{r['rms_sneddon']:9.2e} {r['wall']:7.3f} {r['wall_warm']:7.4f} "
            f"({r['wall_mesh']:.3f}/{r['wall_assemble']:.3f}/{r['wall_factor']:.3f}/"
            f"{r['wall_condense']:.3f}/{r['wall_lcp']:.3f})")
    lines.append(f"observed convergence rate (error vs Sneddon ~ growth^p): p = "
                 f"{res['observed_rate']:.2f} (theory {res['theory_rate']:.0f})")
    lines.append("goal curves (config mesh, 1000 increments; x = multiples of the reference LU):")
    for r in res["goals"]:
        extra = f", {100 * r['err_hertz']:.3f} % from Hertz" if "err_hertz" in r else ""
        mono = (f", monolithic {r['monolithic']:.3f} s ({r['monolithic_per_lu']:.2f} x, "
                f"max diff {r['engines_max_rel_diff']:.1e})") if "monolithic" in r else ""
        lines.append(f"  {r['case']:>20}: cold {r['cold']:.3f} s ({r['cold_per_lu']:.2f} x), "
                     f"warm {r['warm']:.4f} s ({r['warm_per_lu']:.3f} x){extra}{mono}")
    w = res["wall"]
    if w:
        lines.append(
            f"fem wall, {w['scenes']} scenes: build cold {w['build_cold']:.2f} s, warm "
            f"{w['build_warm']:.3f} s ({1e3 * w['build_warm_per_scene']:.2f} ms/scene), "
            f"TOF sweep {w['tof_sweep']:.2f} s; peak/d_exact <= {w['peak_over_d_exact_max']:.2f}; "
            f"TOF vs the exact law: 400-cell linear table {w['tof_diff_grid400_linear']:.1e}, "
            f"F/d^1.5 table {w['tof_diff_table400_f_over_d15']:.1e}")
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
