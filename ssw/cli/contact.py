"""``ssw contact`` and ``ssw contact-plot``: Stage I force-indentation curves.

* ``ssw contact --soil-E E --soil-nu NU [--plate-material NAME | --plate-E E --plate-nu NU]
  --plate-thickness T [--interface bonded|frictionless|unilateral] [--delta-max D]
  [--steps N] [--output FILE.h5] [--config C] [--json]``; or ``ssw contact --scene ID``
  to take a scene of the config's sets. SI units. With ``--json`` prints ``{"delta": [...],
  "force": [...], "contact_radius": [...], ...}`` with every input.
* ``ssw contact-plot CURVES... --output F.png [--label-by material|thickness]``: force vs
  indentation of several curves with the Hertz law of their soil (the thesis's Figs 5, 6).
"""

from __future__ import annotations

import argparse
from typing import Any

from ssw.cli import add_json_flag
from ssw.errors import ConfigError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "contact",
        help="force-indentation curve of the rigid sphere on a plate on a soil (FEM)",
        description="Axisymmetric FEM (gmsh + PETSc) of a rigid frictionless sphere pressed "
        "into a plate (or none) on an elastic soil; writes a contact_curve HDF5. SI units.",
    )
    p.add_argument("--scene", help="a scene id of the config's sets (instead of the below)")
    p.add_argument("--soil-E", type=float, help="soil Young's modulus, Pa")
    p.add_argument("--soil-nu", type=float, help="soil Poisson's ratio, (-1, 0.5]")
    p.add_argument("--plate-material", help="plate material key of the config's library")
    p.add_argument("--plate-E", type=float, help="plate Young's modulus, Pa (custom plate)")
    p.add_argument("--plate-nu", type=float, help="plate Poisson's ratio (custom plate)")
    p.add_argument("--plate-thickness", type=float, help="plate thickness, m (0: no plate)")
    p.add_argument("--interface", choices=["bonded", "frictionless", "unilateral"],
                   help="plate-soil interface (default: contact.interface of the config)")
    p.add_argument("--delta-max", type=float, help="final indentation, m (contact.delta_max)")
    p.add_argument("--steps", type=int, help="indentation increments (contact.steps)")
    p.add_argument("--mesh-growth", type=float,
                   help="element size / distance from the contact (contact.mesh_growth)")
    p.add_argument("--output", help="curve file to write (HDF5)")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    add_json_flag(p)
    p.set_defaults(func=run, human=_human)

    q = sub.add_parser(
        "contact-plot",
        help="plot force vs indentation of contact curves with Hertz (thesis Figs 5, 6)",
    )
    q.add_argument("curves", nargs="+", help="contact curve files (HDF5)")
    q.add_argument("--output", required=True, help="PNG file")
    q.add_argument("--label-by", choices=["material", "thickness"], default="material")
    q.add_argument("--title", default="", help="figure title")
    add_json_flag(q)
    q.set_defaults(func=run_plot)


def _scene(args: argparse.Namespace, cfg: dict[str, Any], mats: dict) -> Any:
    from ssw.config import Scene, all_scenes
    from ssw.materials import Material

    if args.scene:
        scenes = all_scenes(cfg)
        if args.scene not in scenes:
            raise ConfigError("--scene", args.scene, "a scene id of the config's sets")
        return scenes[args.scene], mats
    for name in ("soil_E", "soil_nu", "plate_thickness"):
        if getattr(args, name) is None:
            raise ConfigError(f"--{name.replace('_', '-')}", None, "a value (or --scene)")
    t = args.plate_thickness
    if t > 0 and args.plate_material is None:
        if args.plate_E is None or args.plate_nu is None:
            raise ConfigError("--plate-material", None,
                              "a material key, or --plate-E and --plate-nu, when T > 0")
        mats = {**mats, "custom": Material("custom", "custom plate", args.plate_E,
                                           args.plate_nu, 1.0, "command line")}
        key = "custom"
    else:
        key = args.plate_material or "none"
    return Scene(key if t > 0 else "none", float(t), float(args.soil_E),
                 float(args.soil_nu)), mats


def run(args: argparse.Namespace) -> dict[str, Any] | None:
    from ssw.config import library, load_config
    from ssw.contact import solve_scene
    from ssw.contact.petsc_solver import comm_rank
    from ssw.curve import write_curve

    cfg = load_config(args.config)
    contact = dict(cfg.get("contact", {}))
    if args.mesh_growth is not None:
        contact["mesh_growth"] = args.mesh_growth
        contact["mesh_size_contact"] = 5e-5 * args.mesh_growth  # same graded zone start
    for key in ("interface", "delta_max", "steps"):
        if getattr(args, key) is not None:
            contact[key] = getattr(args, key)
    mats = library(cfg)
    scene, mats = _scene(args, cfg, mats)
    curve = solve_scene(scene, contact, float(cfg["indenter"]["radius"]), mats)
    inputs = {**curve.inputs, "material_set": cfg.get("material_set", "realistic")}
    if scene.plate_material == "custom":
        inputs["material_set"] = "custom"
    if comm_rank() != 0:  # under mpiexec, rank 0 alone writes and reports
        return None
    if args.output:
        from dataclasses import replace

        write_curve(args.output, replace(curve, inputs=inputs))
    return {
        **inputs,
        "delta": curve.delta.tolist(), "force": curve.force.tolist(),
        "contact_radius": curve.contact_radius.tolist(), "output": args.output,
        "stats": curve.stats,
    }


def _human(res: dict[str, Any]) -> str:
    st = res["stats"]
    return (
        f"scene {res['scene_id']}: F({res['delta'][-1]:.4g} m) = "
        f"{res['force'][-1]:.6g} N, contact radius {res['contact_radius'][-1]:.4g} m\n"
        f"{st['dofs']} dofs, {st['elements']} elements, {st['candidates']} contact candidates, "
        f"{len(res['delta'])} increments, wall {st['wall_total']:.3f} s "
        f"(mesh {st['wall_mesh']:.3f}, assemble {st['wall_assemble']:.3f}, "
        f"factor {st['wall_factor']:.3f}, condense {st['wall_condense']:.3f}, "
        f"LCP {st['wall_lcp']:.3f})" + (f"\nwrote {res['output']}" if res["output"] else "")
    )


def run_plot(args: argparse.Namespace) -> dict[str, Any]:
    from ssw.contact.figures import plot_curves
    from ssw.curve import read_curve

    curves = [read_curve(p) for p in args.curves]
    plot_curves(curves, args.output, label_by=args.label_by, title=args.title)
    return {"output": args.output, "curves": len(curves)}
