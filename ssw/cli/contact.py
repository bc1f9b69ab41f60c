"""``ssw contact`` and ``ssw contact-plot``: Stage I force-indentation curves.

* ``ssw contact --soil-E E --soil-nu NU [--plate-material NAME | --plate-E E --plate-nu NU]
  --plate-thickness T [--interface bonded|frictionless|unilateral] [--delta-max D]
  [--steps N] [--output FILE.h5] [--config C] [--json]``; or ``ssw contact --scene ID``
  to take a scene of the config's sets. SI units. With ``--json`` prints ``{"delta": [...],
  "force": [...], "contact_radius": [...], ...}`` with every input.
* ``ssw contact --scene ID [--scene ID ...] --output-dir DIR [--config C] [--json]``, or
  ``ssw contact --family NAME --output-dir DIR``: a batch of scenes in one process (the
  workflow's contact jobs solve a plate family, :func:`ssw.workflow.families`: the imports
  are paid once), solved in turn; each ``DIR/ID.h5`` is written atomically as soon as its
  scene is done, so an interrupted batch leaves only complete curve files. Prints
  (``--json``) ``{"scenes": [...], "outputs": [...], "curves": [{scene_id, output,
  force_max, ...}]}``.
* ``ssw contact-plot CURVES... --output F.png [--label-by material|thickness]``: force vs
  indentation of several curves with the Hertz law of their soil (the thesis's Figs 5, 6).
"""

from __future__ import annotations

import argparse
from typing import Any

from ssw.cli import add_json_flag
from ssw.cli._soil import add_plate_model_options, add_soil_model_options
from ssw.errors import ConfigError


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``ssw contact``, ``ssw contact-plot`` subcommands to the command line.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``ssw`` parser.
    """
    p = sub.add_parser(
        "contact",
        help="force-indentation curve of the rigid sphere on a plate on a soil (FEM)",
        description="Axisymmetric FEM (gmsh + PETSc) of a rigid frictionless sphere pressed "
        "into a plate (or none) on an elastic soil; writes a contact_curve HDF5. SI units.",
    )
    p.add_argument("--scene", action="append",
                   help="a scene id of the config's sets (instead of the below); repeat it "
                   "for a batch solved in one process (with --output-dir)")
    p.add_argument("--family",
                   help="every scene of a plate family of the config (ssw.workflow.families: "
                   "one plate material and thickness, or noplate), with --output-dir")
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
    p.add_argument("--engine", choices=["fem", "layered"], default="fem",
                   help="fem: the axisymmetric FEM (default); layered: the semi-analytic "
                   "oracle, an infinite plate on a half-space (ssw.contact.layered)")
    add_soil_model_options(p)
    add_plate_model_options(p)
    p.add_argument("--plastic-mesh", choices=["path", "study"], default="path",
                   help="mesh of a plastic curve: path (default; the config's domain and "
                   "growth, its element at the contact point scaled to the path's contact "
                   "radius, ssw.contact.plastic.path_mesh_settings) | study (the elastic "
                   "engine's mesh as configured)")
    p.add_argument("--unload", action="store_true",
                   help="with --soil-model: lift the sphere back after loading (residual "
                   "indentation, dissipated work)")
    p.add_argument("--output", help="curve file to write (HDF5), one scene")
    p.add_argument("--output-dir",
                   help="folder of the curve files of the --scene batch (ID.h5 each)")
    p.add_argument("--config",
                   help="study config YAML (default: ./config/config.yaml, else ssw's defaults)")
    from ssw.cli._sample import add_sample_options

    add_sample_options(p)
    add_json_flag(p)
    p.set_defaults(func=run, human=_human)

    q = sub.add_parser(
        "contact-plot",
        help="plot force vs indentation of contact curves with Hertz (thesis Figs 5, 6)",
    )
    q.add_argument("curves", nargs="+", help="contact curve files (HDF5)")
    q.add_argument("--output", required=True, help="PNG file")
    q.add_argument("--label-by", choices=["material", "thickness"], default="material",
                   help="label the curves by plate material or thickness")
    q.add_argument("--title", default="", help="figure title")
    add_json_flag(q)
    q.set_defaults(func=run_plot)


def _config_scenes(cfg: dict[str, Any], ids: list[str]) -> list[Any]:
    """The config's scenes of ``ids`` (ConfigError naming the unknown ones)."""
    from ssw.config import all_scenes

    scenes = all_scenes(cfg)
    unknown = [i for i in ids if i not in scenes]
    if unknown:
        raise ConfigError("--scene", unknown[0] if len(unknown) == 1 else unknown,
                          "scene ids of the config's sets")
    return [scenes[i] for i in ids]


def _scene(args: argparse.Namespace, cfg: dict[str, Any], mats: dict) -> Any:
    from ssw.cli._sample import sample_of
    from ssw.config import Scene
    from ssw.materials import Material

    if args.scene:
        if sample_of(args) is not None:
            raise ConfigError("--sample-thickness", args.sample_thickness,
                              "sample flags for a scene given by flags, not with --scene")
        return _config_scenes(cfg, args.scene)[0], mats
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
                 float(args.soil_nu), sample=sample_of(args)), mats


def run(args: argparse.Namespace) -> dict[str, Any] | None:
    """``ssw contact``: the force-indentation curve of the rigid sphere on a plate on a soil (FEM),
    one scene or a batch of them.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw contact --help``).

    Returns
    -------
    dict of str to Any or None
        The curve (indentation, m; force, N; contact radius, m), its file and statistics,
        or the batch's curves and files; None on an MPI rank other than 0.

    Raises
    ------
    ssw.errors.ConfigError
        When ``--family`` names no plate family of the config, or comes with
        ``--scene``.
    """
    from ssw.config import library, load_config
    from ssw.contact.petsc_solver import comm_rank
    from ssw.curve import write_curve

    solve_scene = _engine(args)

    cfg = load_config(args.config)
    if args.family is not None:
        from ssw.workflow import families

        fams = families(cfg)
        if args.family not in fams:
            raise ConfigError("--family", args.family,
                              f"a plate family of the config: {', '.join(fams)}")
        if args.scene:
            raise ConfigError("--scene", args.scene, "not with --family")
        args.scene = fams[args.family]
    if args.scene:
        args.scene = list(dict.fromkeys(args.scene))  # a repeated id is solved once
    if args.output_dir is not None or (args.scene and len(args.scene) > 1):
        _check_batch_args(args)
    contact = dict(cfg.get("contact", {}))
    if args.mesh_growth is not None:
        contact["mesh_growth"] = args.mesh_growth
        contact["mesh_size_contact"] = 5e-5 * args.mesh_growth  # same graded zone start
    for key in ("interface", "delta_max", "steps"):
        if getattr(args, key) is not None:
            contact[key] = getattr(args, key)
    if args.delta_max is not None or not args.scene:
        contact["delta_mode"] = "fixed"  # --delta-max, and scenes given by flags, reach it
    mats = library(cfg)
    if args.soil_model is not None or args.unload or args.soil_yield_stress is not None \
            or args.soil_material is not None or args.plate_model is not None:
        return _run_plastic(args, cfg, contact, mats)
    if args.output_dir is not None:
        return _run_batch(args, cfg, contact, mats)
    scene, mats = _scene(args, cfg, mats)
    if comm_rank() != 0:  # under mpiexec, rank 0 alone solves (one scene is serial work)
        return None
    contact["delta_reach"] = scene_reach([scene], cfg, contact, mats)[0]
    curve = solve_scene(scene, contact, float(cfg["indenter"]["radius"]), mats)
    inputs = {**curve.inputs, "material_set": cfg.get("material_set", "realistic")}
    if scene.plate_material == "custom":
        inputs["material_set"] = "custom"
    if args.output:
        from dataclasses import replace

        write_curve(args.output, replace(curve, inputs=inputs))
    return {
        **inputs,
        "delta": curve.delta.tolist(), "force": curve.force.tolist(),
        "contact_radius": curve.contact_radius.tolist(), "output": args.output,
        "stats": curve.stats,
    }


#: Increments of a plastic curve when neither --steps nor the config sets them (every
#: increment is a Newton solve; the elastic path's 1000 are samples of an exact path).
PLASTIC_STEPS = 100


def _run_plastic(args: argparse.Namespace, cfg: dict[str, Any], contact: dict[str, Any],
                 mats: dict) -> dict[str, Any]:
    """The elasto-plastic curve of a sphere on a plastic sample, or through a yielding plate,
    on the half-space box or a finite block (loading, and with --unload unloading): the
    curve, first yield, residual indentation (and under a plate the sample's and the
    plate's dent), dissipated work."""
    from dataclasses import replace

    from ssw.cli._soil import plate_model_of, soil_model_of
    from ssw.contact.plastic import scene_path, summary, write_plastic_curve
    from ssw.contact.scene import scene_plate

    if args.soil_model is None and args.plate_model is None:
        raise ConfigError("--soil-model", None, "a model (von-mises) with --unload or "
                          "--soil-yield-stress (or --plate-model)")
    if args.scene or args.output_dir is not None:
        raise ConfigError("--scene", args.scene, "soil flags with --soil-model (one scene)")
    model = soil_model_of(args, cfg) if args.soil_model is not None else None
    if args.steps is None and "steps" not in cfg.get("contact", {}):
        contact["steps"] = PLASTIC_STEPS
    radius = float(cfg["indenter"]["radius"])
    if args.plate_thickness is None:
        args.plate_thickness = 0.0  # the sample bare unless a plate is given
    scene, mats = _scene(args, cfg, mats)  # the plate and sample of the flags
    scene = replace(scene, soil_model=model,
                    plate_model=plate_model_of(args, mats, scene.plate_material))
    if scene.sample is not None:
        contact = scene.sample.contact_settings(contact)
    curve, inputs = scene_path(scene, contact, radius, scene_plate(scene, mats),
                               unload=bool(args.unload), mesh=args.plastic_mesh)
    inputs.update(soil_model_key=model.key if model is not None else "elastic",
                  plate_model_key=(scene.plate_model.key if scene.plate_model is not None
                                   else None), unload=args.unload,
                  sample=scene.sample.to_dict() if scene.sample is not None else None)
    if args.output:
        write_plastic_curve(args.output, curve, inputs)
    return {**inputs, **summary(curve), "delta": curve.delta.tolist(),
            "force": curve.force.tolist(), "branch": curve.branch.tolist(),
            "contact_radius": curve.contact_radius.tolist(),
            "dissipated": curve.dissipated.tolist(),
            "plastic_volume": curve.plastic_volume.tolist(),
            "iterations": curve.iterations.tolist(), "output": args.output,
            "stats": curve.stats, "plastic": True}


def scene_reach(scenes: list[Any], cfg: dict[str, Any], contact: dict[str, Any],
                mats: dict) -> list[float]:
    """Final indentation (m) of each scene's curve (``contact.delta_reach`` of the solver).

    ``contact.delta_mode`` ``fixed``: ``delta_max`` for all (the thesis's 0.1 mm).
    ``energy``: ``max(delta_max, reach)``, ``reach`` the indentation at which a Hertz
    half-space of the softer of the scene's soil and plate stores ``contact.reach_energy``
    (:func:`ssw.fit.range.energy_reach`: a function of the scene alone, not of the device).
    ``chain``: ``max(delta_max, needed)``, with ``needed`` what the device's chain reaches
    at its last contact on that scene (:func:`ssw.fit.range.scenes_delta_max`, one batched
    chain run). The thesis's 0.1 mm stops short of the 0.2-0.6 mm a 20-bead chain presses
    into soils below ~700 MPa, and the chain's TOF would rest on an extrapolated curve.

    Parameters
    ----------
    scenes : list of ssw.config.Scene
        The scenes (soil E, Pa; nu; plate material and thickness, m).
    cfg : dict of str to Any
        The study config (the indenter's radius, m; the chain for ``chain``).
    contact : dict of str to Any
        The ``contact:`` settings (``delta_max``, m; ``delta_mode``; ``reach_energy``, J).
    mats : dict
        The materials library (key to Material: the plates' E, Pa, and nu).

    Returns
    -------
    list of float
        m, each scene's final indentation.
    """
    d0 = float(contact.get("delta_max", 1.0e-4))
    mode = contact.get("delta_mode", "fixed")
    if mode == "fixed" or not scenes:
        return [d0] * len(scenes)
    plates = [mats[s.plate_material] if s.plate_thickness > 0 else None for s in scenes]
    if mode == "energy":
        from ssw.fit.range import energy_reach

        reach = energy_reach([s.soil_E for s in scenes], [s.soil_nu for s in scenes],
                             [p.E if p else None for p in plates],
                             [p.nu if p else None for p in plates],
                             float(cfg["indenter"]["radius"]),
                             float(contact.get("reach_energy", 0.01)))
        return [max(d0, float(r)) for r in reach]
    from ssw.fit.range import scenes_delta_max

    need = scenes_delta_max([s.soil_E for s in scenes], [s.soil_nu for s in scenes],
                            [p.E if p else None for p in plates],
                            [p.nu if p else None for p in plates], cfg)
    return [max(d0, float(n)) for n in need]


def _check_batch_args(args: argparse.Namespace) -> None:
    """A batch: scene ids of the config and a folder, nothing that names one scene."""
    if not args.scene:
        raise ConfigError("--scene", None, "one or more scene ids of the config with --output-dir")
    if args.output is not None:
        raise ConfigError("--output", args.output,
                          "one --scene only; the curves of several go to --output-dir")
    if args.output_dir is None:
        raise ConfigError("--output-dir", None, "a folder for the curves of several --scene")
    given = [f"--{k.replace('_', '-')}" for k in ("soil_E", "soil_nu", "plate_material",
                                                   "plate_E", "plate_nu", "plate_thickness")
             if getattr(args, k) is not None]
    if given:
        raise ConfigError(given[0], getattr(args, given[0][2:].replace("-", "_")),
                          "no scene flags with a --scene batch (the config defines the scenes)")


def _run_batch(args: argparse.Namespace, cfg: dict[str, Any], contact: dict[str, Any],
               mats: dict) -> dict[str, Any] | None:
    """Solve the --scene batch in turn; write each curve (atomically) as soon as it is done."""
    import sys
    import time
    from pathlib import Path

    from ssw.contact.batch import gather, solve_batch
    from ssw.contact.petsc_solver import comm_rank, comm_size
    from ssw.errors import SswError

    solve_scene = _engine(args)
    scenes = _config_scenes(cfg, args.scene)  # every id checked before the first solve
    reach = scene_reach(scenes, cfg, contact, mats)
    out_dir = Path(args.output_dir)
    material_set = cfg.get("material_set", "realistic")
    rank, size = comm_rank(), comm_size()  # under mpiexec: operator groups over the ranks
    tag = f"rank {rank}: " if size > 1 else ""

    def progress(j: int, n: int, scene: Any, curve: Any, out: Path) -> None:
        print(f"{tag}[{j + 1}/{n}] {scene.scene_id}: F = {curve.force[-1]:.6g} N, "
              f"solve {curve.stats['wall_total']:.3f} s -> {out}", file=sys.stderr, flush=True)

    t0 = time.perf_counter()
    try:
        mine = solve_batch(scenes, reach, contact, float(cfg["indenter"]["radius"]), mats,
                           out_dir, material_set, solve_scene, rank=rank, size=size,
                           progress=progress)
    except SswError:
        print(f"ssw contact: {tag}a scene of the batch failed", file=sys.stderr, flush=True)
        raise
    curves = gather(mine, size)
    if curves is None:
        return None
    order = {s.scene_id: i for i, s in enumerate(scenes)}
    curves.sort(key=lambda c: order[c["scene_id"]])
    return {"scenes": [c["scene_id"] for c in curves], "outputs": [c["output"] for c in curves],
            "output_dir": str(out_dir), "curves": curves, "material_set": material_set,
            "ranks": size, "wall_batch": time.perf_counter() - t0}


def _engine(args: argparse.Namespace) -> Any:
    """``solve_scene`` of the chosen engine: the FEM or the layered oracle."""
    if getattr(args, "engine", "fem") == "layered":
        from ssw.contact.layered import solve_scene
    else:
        from ssw.contact import solve_scene
    return solve_scene


def _human(res: dict[str, Any]) -> str:
    if res.get("engine") == "layered":
        from ssw.contact.layered import describe

        return describe(res)
    if res.get("plastic"):
        def g(x: Any, unit: str) -> str:
            return "none" if x is None else f"{x:.6g} {unit}"

        plate = (f" under a {res['plate_model_key']} plate" if res.get("plate_model_key")
                 else "")
        dents = (f" (interface {g(res['interface_residual_indentation'], 'm')}, plate "
                 f"thinning {g(res['plate_thinning'], 'm')})" if res.get("plate_model_key")
                 else "")
        return (f"{res['soil_model_key']} on E = {res['soil_E']:.6g} Pa, nu = "
                f"{res['soil_nu']:.4g}{plate}: F_max = {res['force_max']:.6g} N, first yield "
                f"at {g(res['first_yield_force'], 'N')}, residual indentation "
                f"{g(res['residual_indentation'], 'm')}{dents}, dissipated work "
                f"{res['dissipated_work']:.6g} J; {res['stats']['increments']} increments, "
                f"{res['stats']['newton_iterations']} Newton iterations, wall "
                f"{res['stats']['wall_total']:.3f} s"
                + (f"\nwrote {res['output']}" if res["output"] else ""))
    if "curves" in res:  # a batch
        rows = [f"{c['scene_id']}: F = {c['force_max']:.6g} N, solve {c['wall_total']:.3f} s"
                for c in res["curves"]]
        return "\n".join([*rows, f"{len(rows)} scenes in {res['wall_batch']:.3f} s, "
                           f"curves in {res['output_dir']}"])
    st = res["stats"]
    if "newton_iterations" in st:  # a scene with a soil model (ssw.contact.plastic)
        return (f"scene {res['scene_id']}: F({res['delta'][-1]:.4g} m) = "
                f"{res['force'][-1]:.6g} N; {st['dofs']} dofs, {st['increments']} increments, "
                f"{st['newton_iterations']} Newton iterations, wall {st['wall_total']:.3f} s"
                + (f"\nwrote {res['output']}" if res["output"] else ""))
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
    """``ssw contact-plot``: force against indentation of contact curves beside Hertz's (thesis Figs
    5, 6).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (its flags: ``ssw contact-plot --help``).

    Returns
    -------
    dict of str to Any
        The figure's path (``output``) and the number of curves.
    """
    from ssw.contact.figures import plot_curves
    from ssw.curve import read_curve

    curves = [read_curve(p) for p in args.curves]
    plot_curves(curves, args.output, label_by=args.label_by, title=args.title)
    return {"output": args.output, "curves": len(curves)}
