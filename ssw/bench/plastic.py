"""``ssw bench contact --plastic`` (= ``ssw bench plastic``): the cost of an elasto-plastic
loading-unloading curve, against its error.

A rigid sphere (the config's indenter) on a von Mises half-space (E, nu, Y given; default
PCF 08: 38 MPa, 0.34, Y = its catalogue compressive strength 1.4 MPa), loaded to
``delta_max`` in ``--plastic-steps`` increments and unloaded in as many (up to where the
sphere leaves the surface), one core, on meshes scaled to the contact radius ``a`` at
``delta_max`` (:func:`ssw.contact.plastic.contact_mesh`, the plastic wall's meshes):

* timed: element ``a / --plastic-fine`` at the contact, growth ``--plastic-growth``, a
  domain of 40 ``a``;
* reference: element ``a / 32``, growth 0.1, a domain of 60 ``a`` (converged: from growth
  0.15 and 40 ``a`` to it the residual indentation moves 3 %, from it to ``a / 64`` 0.15 %;
  ``--no-reference`` skips it), the same increments.

Reports the wall times, increments, Newton iterations, factorizations (new and reused),
dofs, first yield (and Johnson's), residual indentation and dissipated work of both, and
the timed curve's error against the reference (largest force difference over the path
relative to the peak force, residual indentation, dissipated work, first yield); writes
``plastic_bench.json`` and ``plastic_curve.png`` (both curves, the elastic Hertz law and
the first yield) under the output folder.

``--plastic-study``: the curve a study config's ``ssw contact --soil-model`` solves (its
domain, mesh growth and increments, ``--plastic-steps`` of ``--plastic-delta-max``, loaded
and unloaded), wall and CPU time, on the path's meshes (the default of ``ssw contact``:
:func:`ssw.contact.plastic.scene_meshes`, its elastic part on a mesh of its own) and on
the elastic engine's mesh (``--plastic-mesh study``), each against the reference: the
elastic engine's mesh with its growth and its element at the contact halved (on the
thesis config's 0.1 to 0.05 the force moves 1.1e-3 of the peak at most and the residual
indentation 1.7e-3; from 0.07 to 0.05, 6e-4 and 4e-4: converged to a few 1e-4), the same
increments (600 against 2400 on one mesh: 7e-6 of the peak force, residual indentation
2e-4); and each against exact solutions (:func:`elastic_error`: first yield against
Johnson's, the increments before it against Hertz and Sneddon); ``plastic_study.json``.
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
    """Add the ``ssw bench plastic`` command and its options.

    Parameters
    ----------
    kinds : argparse._SubParsersAction
        The ``ssw bench`` subcommands.
    """
    p = kinds.add_parser("plastic", help="cost of an elasto-plastic loading-unloading curve "
                         "(= contact --plastic)")
    add_arguments(p)
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    p.set_defaults(func=run_plastic, human=human, plastic=True)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the plastic curve's options (``--plastic``, ``--plastic-E`` Pa, ``--plastic-Y``
    Pa, ``--plastic-delta-max`` m, the timed mesh's, ...) to a parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The parser of ``ssw bench plastic`` or ``ssw bench contact``.
    """
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
    p.add_argument("--plastic-growth", type=float, default=0.2,
                   help="element growth of the timed mesh")
    p.add_argument("--plastic-fine", type=float, default=8.0,
                   help="contact radius / element size at the contact of the timed mesh")
    p.add_argument("--no-reference", dest="plastic_reference", action="store_false",
                   help="skip the converged reference curve")
    p.add_argument("--plastic-study", action="store_true",
                   help="time the config's own plastic curve (what ssw contact --soil-model "
                   "solves: the config's domain, growth and increments) on the path's mesh "
                   "and on the elastic engine's mesh, against the config's mesh refined "
                   "(growth and contact element halved; the slow part)")


#: The reference mesh: contact radius / element size, growth, domain / contact radius.
REFERENCE_MESH = (32.0, 0.1, 60.0)


def run_plastic(args: argparse.Namespace) -> dict[str, Any]:
    """Time the plastic curve (module docstring) and write ``plastic_bench.json`` and
    ``plastic_curve.png`` under ``--output-dir`` (``--plastic-study``: :func:`run_study`).

    Parameters
    ----------
    args : argparse.Namespace
        The command's options (:func:`add_arguments`).

    Returns
    -------
    dict
        The timings (wall and CPU s), the errors against the reference mesh, Johnson's
        first yield and Hertz (relative; forces N), and the files written.
    """
    if getattr(args, "plastic_study", False):
        return run_study(args)
    from ssw.config import load_config
    from ssw.constitutive import VonMises
    from ssw.contact.plastic import contact_mesh, johnson_first_yield, solve_path, summary
    from ssw.contact.scene import indentation_steps

    cfg = load_config(args.config)
    radius = float(cfg["indenter"]["radius"])
    E, nu, Y = float(args.plastic_E), float(args.plastic_nu), float(args.plastic_Y)
    d_max = float(args.plastic_delta_max)
    deltas = indentation_steps(d_max, int(args.plastic_steps))
    mesh = contact_mesh(radius, d_max, fine=float(args.plastic_fine),
                        growth=float(args.plastic_growth))
    t0 = time.perf_counter()
    curve = solve_path(mesh, E, nu, VonMises(Y), radius, deltas, unload=True)
    wall = time.perf_counter() - t0
    Fy, _ = johnson_first_yield(E, nu, Y, radius)
    st = curve.stats
    res = {"soil_E": E, "soil_nu": nu, "yield_stress": Y, "indenter_radius": radius,
           "mesh": f"a/{args.plastic_fine:g}, growth {args.plastic_growth:g}, domain 40 a",
           **summary(curve), "johnson_first_yield_force": Fy, "wall": wall, **st,
           "wall_per_factorization": st["wall_total"] / max(st["factorizations"], 1)}
    ref = None
    if args.plastic_reference:
        fine, growth, domain = REFERENCE_MESH
        ref_mesh = contact_mesh(radius, d_max, fine=fine, growth=growth, domain=domain)
        t0 = time.perf_counter()
        ref = solve_path(ref_mesh, E, nu, VonMises(Y), radius, deltas, unload=True)
        ref_wall = time.perf_counter() - t0
        n = min(ref.force.size, curve.force.size)
        same = np.allclose(ref.delta[:n], curve.delta[:n], rtol=1e-9, atol=0.0)
        res["reference"] = {"mesh": f"a/{fine:g}, growth {growth:g}, domain {domain:g} a",
                            **summary(ref), "wall": ref_wall, **ref.stats}
        res["error"] = {
            "force_max_rel": float(np.max(np.abs(curve.force[:n] - ref.force[:n]))
                                   / np.max(ref.force)) if same else None,
            "residual_indentation_rel": _rel(curve.residual_indentation,
                                             ref.residual_indentation),
            "dissipated_work_rel": _rel(curve.dissipated_work, ref.dissipated_work),
            "first_yield_force_rel": _rel(curve.first_yield_force, ref.first_yield_force)}
    out = Path(args.output_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "plastic_bench.json", res, {
        "E": E, "nu": nu, "Y": Y, "radius": radius, "delta_max": d_max,
        "steps": int(args.plastic_steps), "fine": args.plastic_fine,
        "growth": args.plastic_growth, "reference_mesh": REFERENCE_MESH})
    _plot(curve, ref, E, nu, radius, Fy, res, out / "plastic_curve.png")
    res["outputs"] = [str(out / "plastic_bench.json"), str(out / "plastic_curve.png")]
    res["plastic"] = True
    return res


def _timed(fn: Any) -> tuple[Any, float, float]:
    """``fn()`` with its wall and CPU (user + sys of this process) time, s."""
    w0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w0, time.process_time() - c0


def curve_error(curve: Any, ref: Any) -> dict[str, Any]:
    """A plastic path's error against a reference path of the same increments: the force
    at the indentations both hold (loading and unloading branches), relative to the
    reference's peak force (max and rms) and, on loading above 5 % of the peak, relative to
    the force itself; the residual indentation, the dissipated work, the peak force and the
    first yield force (relative).

    Parameters
    ----------
    curve : ssw.contact.plastic.PlasticCurve
        The path.
    ref : ssw.contact.plastic.PlasticCurve
        The reference path.

    Returns
    -------
    dict
        ``force_max_rel``, ``force_rms_rel``, ``force_pointwise_max``,
        ``force_pointwise_rms``, ``points``, ``residual_indentation_rel``,
        ``dissipated_work_rel``, ``force_peak_rel``, ``first_yield_force_rel``.
    """
    peak = float(np.max(ref.force))
    diff, rel = [], []
    for b in (0, 1):
        dc, fc = curve.delta[curve.branch == b], curve.force[curve.branch == b]
        dr, fr = ref.delta[ref.branch == b], ref.force[ref.branch == b]
        order = np.argsort(dc)
        j = np.clip(np.searchsorted(dc[order], dr), 0, max(dc.size - 1, 0))
        both = np.isclose(dc[order][j], dr, rtol=1e-9, atol=0.0) if dc.size else dr < 0
        e = fc[order][j][both] - fr[both]
        diff.append(e)
        if b == 0:
            big = fr[both] > 0.05 * peak
            rel.append(e[big] / fr[both][big])
    e, r = np.concatenate(diff), np.concatenate(rel)
    return {"force_max_rel": float(np.max(np.abs(e)) / peak),
            "force_rms_rel": float(np.sqrt(np.mean(e * e)) / peak),
            "force_pointwise_max": float(np.max(np.abs(r))) if r.size else None,
            "force_pointwise_rms": float(np.sqrt(np.mean(r * r))) if r.size else None,
            "points": int(e.size),
            "residual_indentation_rel": _rel(curve.residual_indentation,
                                             ref.residual_indentation),
            "dissipated_work_rel": _rel(curve.dissipated_work, ref.dissipated_work),
            "force_peak_rel": _rel(float(np.max(curve.force)), peak),
            "first_yield_force_rel": _rel(curve.first_yield_force, ref.first_yield_force)}


def elastic_error(curve: Any, E: float, nu: float, radius: float, johnson: float
                  ) -> dict[str, Any]:
    """A von Mises path's error against exact solutions: its first yield force against
    Johnson's (``johnson``, N; :func:`ssw.contact.plastic.johnson_first_yield`) and its
    loading increments before first yield against the rigid sphere's elastic force,
    Hertz's and Sneddon's exact sphere (:func:`ssw.hertz.sneddon_sphere`; largest
    relative deviation and the force at which it occurs, N).

    Parameters
    ----------
    curve : ssw.contact.plastic.PlasticCurve
        The path.
    E : float
        The sample's Young's modulus, Pa.
    nu : float
        The sample's Poisson's ratio.
    radius : float
        The sphere's radius, m.
    johnson : float
        Johnson's first yield force, N.

    Returns
    -------
    dict
        ``first_yield_vs_johnson``, ``elastic_vs_hertz_max``, ``elastic_vs_sneddon_max``
        (relative), ``elastic_vs_sneddon_at`` (N), ``elastic_increments``.
    """
    from ssw.roots import find_root

    Es = hertz.effective_modulus(E, nu)
    d_y = curve.first_yield_delta
    m = (curve.branch == 0) & (curve.delta < (np.inf if d_y is None else d_y))
    d, f = curve.delta[m], curve.force[m]
    out: dict[str, Any] = {"first_yield_vs_johnson": _rel(curve.first_yield_force, johnson),
                           "elastic_increments": int(d.size)}
    if d.size:
        a = find_root(lambda x: hertz.sneddon_sphere(x, Es, radius)[0] - d,
                      np.full(d.size, 1e-9 * radius), np.full(d.size, 0.5 * radius)).x
        e_s = f / hertz.sneddon_sphere(a, Es, radius)[1] - 1.0
        out.update(elastic_vs_hertz_max=float(np.max(np.abs(
            f / hertz.force(d, Es, radius) - 1.0))),
            elastic_vs_sneddon_max=float(np.max(np.abs(e_s))),
            elastic_vs_sneddon_at=float(f[np.argmax(np.abs(e_s))]))
    return out


def run_study(args: argparse.Namespace) -> dict[str, Any]:
    """``--plastic-study``: the config's plastic curve timed on the path's mesh and on the
    elastic engine's mesh, each against the config's mesh refined (growth and element at
    the contact halved, the elastic engine's mesh kind; the increments the same). SI.

    Parameters
    ----------
    args : argparse.Namespace
        The command's options (:func:`add_arguments`).

    Returns
    -------
    dict
        Per mesh (``path``, ``study``, ``reference``): its size, timings (s) and errors;
        written to ``plastic_study.json`` under ``--output-dir``.
    """
    from ssw.config import load_config
    from ssw.constitutive import VonMises
    from ssw.contact.plastic import johnson_first_yield, solve_plastic_scene, summary

    cfg = load_config(args.config)
    radius = float(cfg["indenter"]["radius"])
    E, nu, Y = float(args.plastic_E), float(args.plastic_nu), float(args.plastic_Y)
    contact = {**cfg.get("contact", {}), "delta_max": float(args.plastic_delta_max),
               "steps": int(args.plastic_steps), "delta_mode": "fixed"}
    model = VonMises(Y)

    def path(mesh: str, cc: dict[str, Any]) -> Any:
        return solve_plastic_scene((E, nu), model, radius, cc, unload=True, mesh=mesh)

    res: dict[str, Any] = {"soil_E": E, "soil_nu": nu, "yield_stress": Y,
                           "indenter_radius": radius, "delta_max": contact["delta_max"],
                           "steps": contact["steps"], "study": True, "plastic": True,
                           "johnson_first_yield_force": johnson_first_yield(E, nu, Y, radius)[0]}
    curves = {}
    for mesh in ("path", "study"):
        c, wall, cpu = _timed(lambda m=mesh: path(m, contact))
        curves[mesh] = c
        res[mesh] = {**summary(c), "wall": wall, "cpu": cpu, **c.stats,
                     "exact": elastic_error(c, E, nu, radius, res["johnson_first_yield_force"])}
    if args.plastic_reference:
        fine = {**contact, "mesh_growth": 0.5 * float(cfg["contact"]["mesh_growth"]),
                "mesh_size_contact": 0.5 * float(cfg["contact"]["mesh_size_contact"])}
        ref, wall, cpu = _timed(lambda: path("study", fine))
        res["reference"] = {**summary(ref), "wall": wall, "cpu": cpu, **ref.stats,
                            "mesh_growth": fine["mesh_growth"],
                            "mesh_size_contact": fine["mesh_size_contact"],
                            "exact": elastic_error(ref, E, nu, radius,
                                                   res["johnson_first_yield_force"])}
        for mesh, c in curves.items():
            res[mesh]["error"] = curve_error(c, ref)
    out = Path(args.output_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "plastic_study.json", res, {
        "E": E, "nu": nu, "Y": Y, "radius": radius, "contact": contact,
        "reference": bool(args.plastic_reference)})
    res["outputs"] = [str(out / "plastic_study.json")]
    return res


def _rel(x: float | None, ref: float | None) -> float | None:
    return None if x is None or not ref else float(x / ref - 1.0)


def _plot(curve: Any, ref: Any, E: float, nu: float, radius: float, Fy: float,
          res: dict[str, Any], path: Path) -> None:
    from ssw.plotting import pyplot, save_png

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.2))
    d = np.linspace(0, curve.delta.max(), 200)
    ax.plot(d * 1e6, hertz.force(d, hertz.effective_modulus(E, nu), radius), "k:",
            label="elastic (Hertz)")
    for c, tag, ls in ((curve, "timed mesh", "-"), (ref, "reference mesh", "--")):
        if c is None:
            continue
        for b, lab in ((0, "loading"), (1, "unloading")):
            m = c.branch == b
            ax.plot(c.delta[m] * 1e6, c.force[m], ls, label=f"{tag}, {lab}")
    ax.axhline(Fy, color="gray", lw=0.8, ls="--", label="first yield (Johnson)")
    ax.set_xlabel("indentation (um)")
    ax.set_ylabel("force (N)")
    ax.set_title(f"von Mises: {res['increments']} increments in {res['wall']:.1f} s, one core",
                 fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save_png(fig, path)


def human(res: dict[str, Any]) -> str:
    """The result of :func:`run_plastic` as text for the terminal.

    Parameters
    ----------
    res : dict
        The result of :func:`run_plastic`.

    Returns
    -------
    str
        One line per measurement.
    """
    def g(x: Any) -> str:
        return "none" if x is None else f"{x:.4g}"

    if res.get("study"):
        lines = []
        for mesh in ("path", "study", "reference"):
            if mesh not in res:
                continue
            r = res[mesh]
            x = r["exact"]
            text = (f"{mesh} mesh: {r['dofs']} dofs ({r['near_elements']} of {r['elements']} "
                    f"elements near"
                    + (f"; its elastic part's {r['elastic_dofs']}" if "elastic_dofs" in r
                       else "")
                    + f"), {r['increments']} increments, wall {r['wall']:.2f} s, "
                    f"CPU {r['cpu']:.2f} s; residual indentation "
                    f"{g(r['residual_indentation'])} m, first yield "
                    f"{g(r['first_yield_force'])} N ({g(x['first_yield_vs_johnson'])} of "
                    f"Johnson's), below it ({x['elastic_increments']} increments) within "
                    f"{g(x.get('elastic_vs_hertz_max'))} of Hertz and "
                    f"{g(x.get('elastic_vs_sneddon_max'))} of Sneddon")
            if "error" in r:
                e = r["error"]
                text += (f"\n  error: force max {g(e['force_max_rel'])} rms "
                         f"{g(e['force_rms_rel'])} of the peak, pointwise max "
                         f"{g(e['force_pointwise_max'])}, residual indentation "
                         f"{g(e['residual_indentation_rel'])}, dissipated "
                         f"{g(e['dissipated_work_rel'])}, first yield "
                         f"{g(e['first_yield_force_rel'])}")
            lines.append(text)
        return "\n".join(lines)

    text = (f"plastic curve ({res['mesh']}): {res['increments']} increments ({res['dofs']} "
            f"dofs), {res['newton_iterations']} Newton iterations, {res['factorizations']} "
            f"factorizations ({res['lu_reused']} reused), {res['wall']:.2f} s; first yield "
            f"{g(res['first_yield_force'])} N (Johnson {res['johnson_first_yield_force']:.4g}"
            f" N), residual indentation {g(res['residual_indentation'])} m, dissipated "
            f"{res['dissipated_work']:.4g} J")
    if res.get("reference"):
        r, e = res["reference"], res["error"]
        text += (f"\nreference ({r['mesh']}, {r['dofs']} dofs): {r['wall']:.2f} s; error of "
                 f"the timed curve: force {g(e['force_max_rel'])} of the peak, residual "
                 f"indentation {g(e['residual_indentation_rel'])}, dissipated "
                 f"{g(e['dissipated_work_rel'])}, first yield {g(e['first_yield_force_rel'])}")
    return text
