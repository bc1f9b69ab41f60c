"""A sphere-plate-soil contact scene: mesh, assemble, factor once, condense, step the LCP.

``solve_scene`` is the stage's Python API: a :class:`ssw.config.Scene` in, a
:class:`ssw.curve.ForceCurve` out (force on the rigid sphere vs its indentation).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ssw.config import Scene
from ssw.contact.assembly import INTERFACES, System, assemble
from ssw.contact.condense import Condensed
from ssw.contact.contact_lcp import edge_radius, solve_lcp, sphere_gap
from ssw.contact.mesh import Mesh, MeshSettings, build_mesh
from ssw.contact.petsc_solver import LUSolver, comm_size, nd_order
from ssw.curve import ForceCurve
from ssw.errors import ConfigError, SolverError
from ssw.materials import Material

#: Defaults of the ``contact`` config section (also in the schema, with the measurements
#: that chose them).
DEFAULTS: dict[str, Any] = {
    "delta_max": 1.0e-4,
    "steps": 1000,
    "interface": "frictionless",
    "plate_diameter": 49.5e-3,
    "soil_radius": 1.0,
    "soil_depth": 1.0,
    "mesh_size_contact": 5.0e-6,
    "mesh_growth": 0.1,
    "mesh_size_max": 0.1,
    "plate_layers": 4,
    "candidate_factor": 1.5,
    "pressure_profiles": 5,
}
#: Gap tolerance of the LCP, relative to the increment size.
LCP_TOL = 1e-9
#: Sphere candidates condensed at once: r <= INITIAL_ZONE sqrt(R delta_max); the rest on
#: demand (a plate shrinks the contact zone well below the Hertz radius).
INITIAL_ZONE = 0.3


#: Numeric settings and their allowed ranges, as in the schema (``contact`` section):
#: key -> (kind, lower bound, lower bound included, upper bound or None).
RANGES: dict[str, tuple[str, float, bool, float | None]] = {
    "delta_max": ("number", 0.0, False, None),
    "steps": ("integer", 1, True, None),
    "plate_diameter": ("number", 0.0, False, None),
    "jobs_per_group": ("integer", 1, True, None),
    "soil_radius": ("number", 0.0, False, None),
    "soil_depth": ("number", 0.0, False, None),
    "mesh_size_contact": ("number", 0.0, False, None),
    "mesh_growth": ("number", 0.0, False, 1.0),
    "mesh_size_max": ("number", 0.0, False, None),
    "plate_layers": ("integer", 1, True, None),
    "candidate_factor": ("number", 1.0, True, None),
    "pressure_profiles": ("integer", 0, True, None),
    "delta_reach": ("number", 0.0, False, None),
}


def _allowed(kind: str, lo: float, closed: bool, hi: float | None) -> str:
    what = "an integer" if kind == "integer" else "a finite number"
    text = f"{what} {'>=' if closed else '>'} {lo:g}"
    return text + (f" and <= {hi:g}" if hi is not None else "")


def settings_of(contact_cfg: dict[str, Any]) -> dict[str, Any]:
    """The contact settings with defaults filled in and checked against the schema's
    ranges (:data:`RANGES`; ConfigError naming the field otherwise). Other keys pass
    through."""
    cfg = {**DEFAULTS, **contact_cfg}
    if cfg["interface"] not in INTERFACES:
        raise ConfigError("contact.interface", cfg["interface"], " | ".join(INTERFACES))
    for key, (kind, lo, closed, hi) in RANGES.items():
        if key not in cfg:
            continue
        value = cfg[key]
        try:
            x = float(value)
            ok = not isinstance(value, bool) and np.isfinite(x) and (
                x >= lo if closed else x > lo) and (hi is None or x <= hi) and (
                kind != "integer" or x == int(x))
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise ConfigError(f"contact.{key}", value, _allowed(kind, lo, closed, hi))
    return cfg


def _check_material(name: str, E: float, nu: float) -> None:
    if not E > 0:
        raise ConfigError(f"{name}_E", E, "a Young's modulus > 0 Pa")
    if not -1.0 < nu <= 0.5:
        raise ConfigError(f"{name}_nu", nu, "a Poisson's ratio in (-1, 0.5]")


def mesh_settings(cfg: dict[str, Any]) -> MeshSettings:
    """Mesh settings of a (filled) contact config."""
    return MeshSettings(
        soil_radius=float(cfg["soil_radius"]),
        soil_depth=float(cfg["soil_depth"]),
        size_contact=float(cfg["mesh_size_contact"]),
        growth=float(cfg["mesh_growth"]),
        size_max=float(cfg["mesh_size_max"]),
        plate_layers=int(cfg["plate_layers"]),
    )


def top_surface_weights(mesh_nodes: np.ndarray, tri: np.ndarray, top_elems: np.ndarray,
                        top: float, tol: float) -> np.ndarray:
    """``int N_j 2 pi r ds`` (m^2) over the top surface for every node (0 off the surface)."""
    w = np.zeros(len(mesh_nodes))
    t6 = tri[top_elems]
    for a, b, m in ((0, 1, 3), (1, 2, 4), (2, 0, 5)):
        e = t6[:, [a, b, m]]
        on = np.all(np.abs(mesh_nodes[e, 1] - top) < tol, axis=1)
        e = e[on]
        ra, rb = mesh_nodes[e[:, 0], 0], mesh_nodes[e[:, 1], 0]
        length = np.abs(rb - ra)
        s, gw = np.polynomial.legendre.leggauss(4)
        s, gw = 0.5 * (s + 1.0), 0.5 * gw
        n = np.stack([(1 - s) * (1 - 2 * s), s * (2 * s - 1), 4 * s * (1 - s)], axis=1)
        r = ra[:, None] * (1 - s) + rb[:, None] * s  # (ne, nq)
        contrib = np.einsum("q,eq,qi->ei", gw, 2 * np.pi * r * length[:, None], n)
        np.add.at(w, e, contrib)
    return w


def condense(
    sysm: System, solver: LUSolver, mesh: Mesh, radius: float, r_cand: float, interface: str,
    r_start: float,
) -> tuple[Condensed, np.ndarray]:
    """Condensed constraints: sphere candidates are the top nodes with r <= r_cand (those
    with r <= r_start condensed at once), plus, for the unilateral interface, the interface
    pairs off the axis. Also returns the top nodes beyond the candidates with r < R/2
    (checked for penetration at the end)."""
    tol = 1e-9 * mesh.soil_radius
    top_body = 1 if mesh.plate_radius > 0 else 0
    top_elems = np.flatnonzero(sysm.body == top_body)
    weight = top_surface_weights(sysm.nodes, sysm.tri, top_elems, mesh.top, tol)
    top = np.flatnonzero(weight > 0)
    top = top[np.argsort(sysm.nodes[top, 0])]
    cand = top[sysm.nodes[top, 0] <= r_cand]
    outside = top[(sysm.nodes[top, 0] > r_cand) & (sysm.nodes[top, 0] < 0.5 * radius)]
    if len(cand) < 4:
        raise ConfigError("contact.mesh_size_contact", len(cand),
                          "a finer mesh: at least 4 nodes inside the candidate contact zone")
    if np.any(sysm.udof[cand, 1] < 0):
        raise ConfigError("contact.candidate_factor", r_cand, "a zone inside the free surface")
    pairs = sysm.iface[sysm.nodes[sysm.iface[:, 0], 0] > tol] if interface == "unilateral" \
        else np.zeros((0, 2), dtype=np.int64)
    i_dofs = np.stack([sysm.udof[pairs[:, 1], 1], sysm.udof[pairs[:, 0], 1]], axis=1)
    k0 = int(np.searchsorted(sysm.nodes[cand, 0], r_start, side="right"))
    cond = Condensed(solver, sysm.ndof, sysm.udof[cand, 1], sysm.nodes[cand, 0], weight[cand],
                     i_dofs, max(k0, 4))
    return cond, outside


class MeshCache:
    """The last mesh built and its node elimination order, for a batch of scenes.

    Scenes that differ only in materials (a set's soils under one plate) share the mesh
    and the nested-dissection order: gmsh and the ordering are deterministic, so reusing
    them gives the same numbers as building them again, without their ~0.1 s.
    """

    def __init__(self) -> None:
        self.key: tuple | None = None
        self.mesh: Mesh | None = None
        self.graph: tuple[int, bytes] | None = None
        self.perm: np.ndarray | None = None
        self.hits = 0

    def mesh_for(self, plate_thickness: float, plate_radius: float,
                 settings: MeshSettings) -> Mesh:
        key = (float(plate_thickness), float(plate_radius), settings)
        if key != self.key or self.mesh is None:
            self.mesh = build_mesh(plate_thickness, plate_radius, settings)
            self.key, self.graph, self.perm = key, None, None
        else:
            self.hits += 1
        return self.mesh

    def order_nodes(self, rows: np.ndarray, cols: np.ndarray, n: int) -> np.ndarray:
        """:func:`nd_order`, remembered for the last graph."""
        import hashlib

        graph = (n, hashlib.sha1(rows.tobytes() + cols.tobytes()).digest())
        if graph != self.graph or self.perm is None:
            self.perm, self.graph = nd_order(rows, cols, n), graph
        return self.perm.copy()


def solve_curve(
    soil: tuple[float, float], plate: tuple[float, float] | None, plate_thickness: float,
    radius: float, contact_cfg: dict[str, Any], cache: MeshCache | None = None,
) -> tuple[ForceCurve, dict[str, Any]]:
    """Force-indentation curve of a rigid sphere on a plate (or none) on a soil.

    Parameters
    ----------
    soil : (E Pa, nu) of the soil.
    plate : (E Pa, nu) of the plate, or None with ``plate_thickness == 0``.
    plate_thickness : m.
    radius : m, sphere radius.
    contact_cfg : the ``contact`` config section (defaults: :data:`DEFAULTS`).
    cache : reuse the mesh (and its ordering) of the previous call with the same geometry
        and mesh settings (a batch of scenes); None builds it.

    Returns
    -------
    (curve, state) : the curve (inputs and stats filled except the scene's labels) and a
    dict with the condensed problem, the final contact forces and the solver (for tests).
    """
    cfg = settings_of(contact_cfg)
    t_start = time.perf_counter()
    if plate_thickness < 0:
        raise ConfigError("plate_thickness", plate_thickness, "a thickness >= 0 m")
    if plate_thickness > 0 and plate is None:
        raise ConfigError("plate", plate, "(E, nu) of the plate when plate_thickness > 0")
    _check_material("soil", *soil)
    if plate is not None:
        _check_material("plate", *plate)
    if not radius > 0:
        raise ConfigError("indenter_radius", radius, "a radius > 0 m")
    delta_max, steps = float(cfg["delta_max"]), int(cfg["steps"])
    deltas = indentation_steps(delta_max, steps, cfg.get("delta_reach"))
    plate_radius = 0.5 * float(cfg["plate_diameter"])
    if cache is None:
        mesh, order_nodes = build_mesh(plate_thickness, plate_radius, mesh_settings(cfg)), nd_order
    else:
        mesh = cache.mesh_for(plate_thickness, plate_radius, mesh_settings(cfg))
        order_nodes = cache.order_nodes
    t_mesh = time.perf_counter()
    pe = plate if plate is not None else soil
    sysm = assemble(mesh, (soil[0], pe[0]), (soil[1], pe[1]), cfg["interface"], order_nodes)
    t_asm = time.perf_counter()
    solver = LUSolver(sysm.rows, sysm.cols, sysm.vals, sysm.ndof, sysm.scale)
    t_fact = time.perf_counter()
    a_ref = np.sqrt(radius * deltas[-1])
    r_cand = float(cfg["candidate_factor"]) * a_ref
    cond, outside = condense(sysm, solver, mesh, radius, r_cand, cfg["interface"],
                             INITIAL_ZONE * a_ref)
    t_cond = time.perf_counter()

    n_inc = deltas.size
    force = np.empty(n_inc)
    a = np.empty(n_inc)
    keep = np.unique(np.linspace(0, n_inc - 1, int(cfg["pressure_profiles"])).round().astype(int))
    profiles = []
    tol = LCP_TOL * delta_max / steps
    active = np.zeros(len(cond.W), dtype=bool)
    pivots = 0
    lcp_cache: dict = {}
    for k, d in enumerate(deltas):
        g0_all = sphere_gap(cond.r, radius, d)
        while True:
            ms = cond.n_sphere
            g0 = np.concatenate([g0_all[:ms], np.zeros(len(cond.W) - ms)])
            lam, active, piv = solve_lcp(cond.W, g0, active, tol, lcp_cache)
            pivots += piv
            need = cond.violated(g0_all, lam, tol)
            if not need:
                break
            cond.extend(need)
            active = np.concatenate([active[:ms], np.zeros(cond.n_sphere - ms, bool),
                                     active[ms:]])
        force[k] = lam[:ms].sum()
        gap = np.clip(g0_all + cond.sphere_gap_change(lam), 0.0, None)
        act = np.zeros(len(cond.r), dtype=bool)
        act[:ms] = active[:ms]
        a[k] = edge_radius(cond.r, gap, act)
        if k in keep:
            p = np.zeros(len(cond.r))
            p[:ms] = lam[:ms] / cond.weight[:ms]
            if cond.r[0] == 0.0:  # the axis vertex of a P2 edge has zero weight; dp/dr = 0
                p[0] = p[1]
            profiles.append(p)
    t_lcp = time.perf_counter()
    _check_zone(cond, sysm, outside, lam, radius, deltas[-1], tol)
    stats = {
        "nodes": len(sysm.nodes), "elements": len(sysm.tri), "dofs": sysm.ndof,
        "nnz_coo": len(sysm.vals), "candidates": len(cond.W), "sphere_candidates": ms,
        "solves": cond.solves,
        "lcp_pivots": pivots, "ranks": comm_size(),
        "wall_mesh": t_mesh - t_start, "wall_assemble": t_asm - t_mesh,
        "wall_factor": t_fact - t_asm, "wall_condense": t_cond - t_fact + cond.wall,
        "wall_lcp": t_lcp - t_cond - cond.wall, "wall_total": t_lcp - t_start,
    }
    inputs = {
        "soil_E": soil[0], "soil_nu": soil[1],
        "plate_E": None if plate_thickness == 0 else pe[0],
        "plate_nu": None if plate_thickness == 0 else pe[1],
        "plate_thickness": plate_thickness, "indenter_radius": radius, **cfg,
    }
    curve = ForceCurve(
        delta=deltas, force=force, contact_radius=a, inputs=inputs, stats=stats,
        pressure={"r": cond.r[:ms], "delta": deltas[keep],
                  "p": np.array(profiles)[:, :ms]},
    )
    return curve, {"cond": cond, "lam": lam, "solver": solver, "system": sysm, "mesh": mesh}


def indentation_steps(delta_max: float, steps: int, delta_reach: float | None = None) -> np.ndarray:
    """Indentations (m) of the increments: ``steps`` equal ones to ``delta_max`` (the
    thesis's 1000 x 0.1 um) then, when ``delta_reach > delta_max`` (``contact.delta_mode``
    chain), ``steps`` equal ones on to ``delta_reach``: the small-indentation resolution of
    the thesis is kept and the curve reaches what the chain presses in."""
    d = delta_max * np.arange(1, steps + 1) / steps
    if delta_reach is not None and float(delta_reach) > delta_max * (1 + 1e-12):
        ext = delta_max + (float(delta_reach) - delta_max) * np.arange(1, steps + 1) / steps
        d = np.concatenate([d, ext])
    return d


def _check_zone(cond: Condensed, sysm: System, outside: np.ndarray, lam: np.ndarray,
                radius: float, delta: float, tol: float) -> None:
    """Raise SolverError if the contact reached the last candidate or any top node beyond."""
    if cond.n_sphere == len(cond.r) and lam[cond.n_sphere - 1] > 0:
        raise SolverError(
            f"the contact zone reached the last candidate node (r = {cond.r[-1]:.4g} m): "
            "raise contact.candidate_factor"
        )
    if len(outside):
        x = cond.X[sysm.udof[outside, 1]] @ lam
        g = sphere_gap(sysm.nodes[outside, 0], radius, delta) - x
        if np.any(g < -tol):
            raise SolverError(
                f"the sphere penetrates the surface beyond the candidate zone (r = "
                f"{sysm.nodes[outside[g < -tol][0], 0]:.4g} m): raise contact.candidate_factor"
            )


def strain_energy(state: dict[str, Any], lam: np.ndarray) -> float:
    """Strain energy (J) ``x^T K x / 2`` of the state under contact forces ``lam`` (N)."""
    x = state["cond"].X @ lam
    return 0.5 * float(x @ state["solver"].matvec(x))


def solve_scene(
    scene: Scene, contact_cfg: dict[str, Any], indenter_radius: float,
    materials: dict[str, Material], cache: MeshCache | None = None,
) -> ForceCurve:
    """Force-indentation curve of one scene of a study.

    Parameters
    ----------
    scene : plate material key, thickness (m, 0 = no plate), soil E (Pa) and nu.
    contact_cfg : the config's ``contact`` section.
    indenter_radius : m, the rigid sphere's radius.
    materials : the material library of the study (key -> Material).
    cache : a :class:`MeshCache` shared by the scenes of a batch (None: none).
    """
    plate = None
    plate_key = scene.plate_material if scene.plate_thickness > 0 else "none"
    if scene.plate_thickness > 0:
        if scene.plate_material not in materials:
            raise ConfigError("plate_material", scene.plate_material,
                              f"a material of the library: {', '.join(sorted(materials))}")
        m = materials[scene.plate_material]
        plate = (m.E, m.nu)
    curve, state = solve_curve((scene.soil_E, scene.soil_nu), plate, scene.plate_thickness,
                               indenter_radius, contact_cfg, cache)
    state["solver"].destroy()
    inputs = {**curve.inputs, "plate_material": plate_key, "scene_id": scene.scene_id,
              "material_set": _material_set_of(materials)}
    return ForceCurve(curve.delta, curve.force, curve.contact_radius, inputs, curve.stats,
                      curve.pressure)


def _material_set_of(materials: dict[str, Material]) -> str:
    """Name of the set of the shipped library equal to ``materials`` ("custom" if none)."""
    from ssw.materials import load_library, material_set

    for name in load_library():
        if material_set(name) == materials:
            return name
    return "custom"
