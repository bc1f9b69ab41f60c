"""A sphere-plate-soil contact scene: its exact force-indentation curve.

``solve_scene`` is the stage's Python API: a :class:`ssw.config.Scene` in, a
:class:`ssw.curve.ForceCurve` out (force on the rigid sphere vs its indentation).

Two engines compute the same curve (to round-off; tests/test_contact_engines.py):

* ``substructured`` (default): the plate and the soil condensed once per mesh and Poisson's
  ratio at unit E (:mod:`ssw.contact.operators`, cached), a dense system of a few hundred
  unknowns per scene, and the exact piecewise-affine path of the contact LCP in the
  indentation (:mod:`ssw.contact.parametric`), sampled at the increments;
* ``monolithic``: the whole u-p matrix factored with PETSc (MUMPS where the build has it,
  :mod:`ssw.contact.petsc_solver`), condensed onto the candidates
  (:mod:`ssw.contact.condense`) and an LCP solved at every increment
  (:mod:`ssw.contact.contact_lcp`): the independent check.
"""

from __future__ import annotations

import functools
import time
from typing import Any

import numpy as np

from ssw.config import Scene
from ssw.contact.assembly import (
    INTERFACES,
    System,
    assemble,
    geometric_tolerance,
    top_surface_weights,
)
from ssw.contact.condense import Condensed
from ssw.contact.contact_lcp import edge_radius, solve_lcp, sphere_gap
from ssw.contact.mesh import Mesh, MeshSettings, build_mesh, mesh_settings
from ssw.contact.operators import OperatorStore, default_store, geometry_of, scene_lcp
from ssw.contact.parametric import trace
from ssw.contact.petsc_solver import LUSolver, comm_size, nd_order
from ssw.curve import ForceCurve
from ssw.errors import ConfigError, SolverError
from ssw.materials import Material

#: The solvers of a scene (module docstring).
ENGINES = ("substructured", "monolithic")
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
    "reach_energy": ("number", 0.0, False, None),
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
    through.

    Parameters
    ----------
    contact_cfg : dict
        The contact settings (SI).

    Returns
    -------
    dict
        The filled settings.

    Raises
    ------
    ConfigError
        If a setting is unknown in kind or out of its range.
    """
    cfg = {**DEFAULTS, **contact_cfg}
    if cfg["interface"] not in INTERFACES:
        raise ConfigError("contact.interface", cfg["interface"], " | ".join(INTERFACES))
    # the soil's boundaries (ssw.sample: a finite block; default the half-space box)
    for key, allowed in (("soil_base", ("bonded", "sliding")),
                         ("soil_lateral", ("mould", "free"))):
        if key in cfg and cfg[key] not in allowed:
            raise ConfigError(f"contact.{key}", cfg[key], " | ".join(allowed))
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


def condense(
    sysm: System, solver: LUSolver, mesh: Mesh, radius: float, r_cand: float, interface: str,
    r_start: float,
) -> tuple[Condensed, np.ndarray]:
    """Condensed constraints of the monolithic engine: sphere candidates are the top nodes
    with r <= r_cand (those with r <= r_start condensed at once), plus, for the unilateral
    interface, the interface pairs off the axis. Also returns the top nodes beyond the
    candidates with r < R/2 (checked for penetration at the end).

    Parameters
    ----------
    sysm : System
        The assembled system.
    solver : LUSolver
        Its factorization.
    mesh : Mesh
        The mesh (m).
    radius : float
        Sphere radius (m).
    r_cand : float
        Radius of the candidate zone (m).
    interface : str
        The plate-soil interface.
    r_start : float
        Radius within which candidates are condensed at once (m).

    Returns
    -------
    cond : Condensed
        The condensed constraints.
    beyond : numpy.ndarray
        Top nodes beyond the candidates with ``r < R/2``.
    """
    tol = geometric_tolerance(sysm.nodes, sysm.tri)
    top_body = 1 if mesh.plate_radius > 0 else 0
    top_elems = np.flatnonzero(sysm.body == top_body)
    weight = top_surface_weights(sysm.nodes, sysm.tri, top_elems, mesh.top, tol)
    top = np.flatnonzero(weight > 0)
    top = top[np.argsort(sysm.nodes[top, 0])]
    cand = top[sysm.nodes[top, 0] <= r_cand]
    outside = top[(sysm.nodes[top, 0] > r_cand) & (sysm.nodes[top, 0] < 0.5 * radius)]
    _check_resolution(int(np.count_nonzero(sysm.nodes[cand, 0] <= r_cand)))
    if np.any(sysm.udof[cand, 1] < 0):
        raise ConfigError("contact.candidate_factor", r_cand, "a zone inside the free surface")
    pairs = sysm.iface[sysm.nodes[sysm.iface[:, 0], 0] > tol] if interface == "unilateral" \
        else np.zeros((0, 2), dtype=np.int64)
    i_dofs = np.stack([sysm.udof[pairs[:, 1], 1], sysm.udof[pairs[:, 0], 1]], axis=1)
    k0 = int(np.searchsorted(sysm.nodes[cand, 0], r_start, side="right"))
    cond = Condensed(solver, sysm.ndof, sysm.udof[cand, 1], sysm.nodes[cand, 0], weight[cand],
                     i_dofs, max(k0, 4))
    return cond, outside


def _check_resolution(n_nodes: int) -> None:
    """ConfigError unless the Hertz contact zone of the deepest increment holds >= 4 nodes."""
    if n_nodes < 4:
        raise ConfigError("contact.mesh_size_contact", n_nodes,
                          "a finer mesh: at least 4 nodes inside the candidate contact zone")


class MeshCache(OperatorStore):
    """What a batch of scenes shares: the condensed operators (an
    :class:`~ssw.contact.operators.OperatorStore`, backed by the disk cache), and for the
    monolithic engine the last mesh built and its node elimination order.

    Scenes that differ only in materials (a set's soils under one plate) share the mesh
    and the nested-dissection order: gmsh and the ordering are deterministic, so reusing
    them gives the same numbers as building them again.

    Parameters
    ----------
    directory : str or pathlib.Path or None
        The disk cache folder; ``"env"``: :func:`ssw.contact.operators.cache_dir`; None: memory
        only.
    """

    def __init__(self, directory: Any = "env") -> None:
        super().__init__(directory)
        self.key: tuple | None = None
        self.mesh: Mesh | None = None
        self.graph: tuple[int, bytes] | None = None
        self.perm: np.ndarray | None = None

    def mesh_for(self, plate_thickness: float, plate_radius: float,
                 settings: MeshSettings) -> Mesh:
        """The mesh of a plate and settings, rebuilt only when they change.

        Parameters
        ----------
        plate_thickness : float
            Plate thickness (m).
        plate_radius : float
            Plate radius (m).
        settings : MeshSettings
            The mesh settings (m).

        Returns
        -------
        Mesh
            The mesh.
        """
        key = (float(plate_thickness), float(plate_radius), settings)
        if key != self.key or self.mesh is None:
            self.mesh = build_mesh(plate_thickness, plate_radius, settings)
            self.key, self.graph, self.perm = key, None, None
        return self.mesh

    def order_nodes(self, rows: np.ndarray, cols: np.ndarray, n: int) -> np.ndarray:
        """:func:`ssw.contact.petsc_solver.nd_order`, remembered for the last graph.

        Parameters
        ----------
        rows : numpy.ndarray
            Graph row indices.
        cols : numpy.ndarray
            Graph column indices.
        n : int
            Number of nodes.

        Returns
        -------
        numpy.ndarray
            The node permutation, (n,).
        """
        import hashlib

        graph = (n, hashlib.sha1(rows.tobytes() + cols.tobytes()).digest())
        if graph != self.graph or self.perm is None:
            self.perm, self.graph = nd_order(rows, cols, n), graph
        return self.perm.copy()


def _validate(soil: tuple[float, float], plate: tuple[float, float] | None,
              plate_thickness: float, radius: float) -> None:
    if plate_thickness < 0:
        raise ConfigError("plate_thickness", plate_thickness, "a thickness >= 0 m")
    if plate_thickness > 0 and plate is None:
        raise ConfigError("plate", plate, "(E, nu) of the plate when plate_thickness > 0")
    _check_material("soil", *soil)
    if plate is not None:
        _check_material("plate", *plate)
    if not radius > 0:
        raise ConfigError("indenter_radius", radius, "a radius > 0 m")


def solve_curve(
    soil: tuple[float, float], plate: tuple[float, float] | None, plate_thickness: float,
    radius: float, contact_cfg: dict[str, Any], cache: MeshCache | OperatorStore | None = None,
    *, engine: str = "substructured",
) -> tuple[ForceCurve, dict[str, Any]]:
    """Force-indentation curve of a rigid sphere on a plate (or none) on a soil.

    Parameters
    ----------
    soil : tuple of float
        ``(E, nu)`` of the soil, Pa and -.
    plate : tuple of float or None
        ``(E, nu)`` of the plate, Pa and -, or None with ``plate_thickness == 0``.
    plate_thickness : float
        The plate's thickness, m.
    radius : float
        The sphere's radius, m.
    contact_cfg : dict
        The ``contact`` config section (defaults: ``ssw.contact.scene.DEFAULTS``).
    cache : MeshCache or ssw.contact.operators.OperatorStore or None
        The operators (and, monolithic, the mesh) shared by a batch of scenes; None: the
        process's store (:func:`ssw.contact.operators.default_store`, disk-backed).
    engine : str
        ``substructured`` (default) or ``monolithic`` (module docstring).

    Returns
    -------
    curve : ssw.curve.ForceCurve
        The curve (inputs and stats filled except the scene's labels).
    state : dict
        The condensed problem and the final contact forces (for tests).
    """
    cfg = settings_of(contact_cfg)
    if cfg.get("subgrade_E") is not None:  # a lift: its subgrade relative to this soil
        cfg["subgrade_ratio"] = float(cfg["subgrade_E"]) / float(soil[0])
    t_start = time.perf_counter()
    if engine not in ENGINES:
        raise ConfigError("engine", engine, " | ".join(ENGINES))
    _validate(soil, plate, plate_thickness, radius)
    deltas = indentation_steps(float(cfg["delta_max"]), int(cfg["steps"]), cfg.get("delta_reach"))
    pe = plate if plate is not None else soil
    inputs = {
        "soil_E": soil[0], "soil_nu": soil[1],
        "plate_E": None if plate_thickness == 0 else pe[0],
        "plate_nu": None if plate_thickness == 0 else pe[1],
        "plate_thickness": plate_thickness, "indenter_radius": radius, **cfg,
        "fem_engine": engine,
    }
    if engine == "monolithic":
        curve, state = _monolithic(soil, pe, plate_thickness, radius, cfg, deltas,
                                   cache if isinstance(cache, MeshCache) else None, t_start)
        return ForceCurve(curve.delta, curve.force, curve.contact_radius, inputs, curve.stats,
                          curve.pressure), state
    store = cache if cache is not None else default_store()
    has_plate = plate_thickness > 0
    geom = geometry_of(cfg, plate_thickness, radius, float(deltas[-1]), cfg["interface"])
    layout = store.layout(geom)
    _check_resolution(int(np.count_nonzero(
        layout.r <= float(cfg["candidate_factor"]) * np.sqrt(radius * deltas[-1]))))
    soil_op = store.body(geom, "soil", soil[1])
    plate_op = store.body(geom, "plate", pe[1]) if has_plate else None
    built = store.pop_cost()
    t_ops = time.perf_counter()
    lcp = scene_lcp(layout, plate_op, soil_op, soil[0], pe[0] if has_plate else None,
                    cfg["interface"], radius)
    t_cond = time.perf_counter()
    path, how = trace(lcp.W, lcp.q0, lcp.q1, float(deltas[-1]))
    ms = lcp.n_sphere
    lam = path.forces(deltas)
    gaps = np.clip(path.gaps(deltas)[:, :ms], 0.0, None)
    active = path.active[path.piece_of(deltas)][:, :ms]
    force = lam[:, :ms].sum(axis=1)
    a = edge_radii(lcp.r, gaps, active)
    keep, p = _pressure_profiles(lcp, lam, deltas.size, int(cfg["pressure_profiles"]))
    if np.any(path.active[:, ms - 1]):
        raise SolverError(
            f"the contact zone reached the last candidate node (r = {lcp.r[-1]:.4g} m): "
            "raise contact.candidate_factor")
    tie_max = _axis_tie_max(lcp, path, float(force[-1]))
    t_lcp = time.perf_counter()
    body_stats = (soil_op.stats, plate_op.stats if plate_op is not None else {})
    stats = _substructured_stats(layout, lcp, path, how, body_stats, built,
                                 (t_start, t_ops, t_cond, t_lcp))
    if tie_max is not None:
        stats["tie_force_max"] = tie_max
    curve = ForceCurve(
        delta=deltas, force=force, contact_radius=a, inputs=inputs, stats=stats,
        pressure={"r": lcp.r, "delta": deltas[keep], "p": p},
    )
    return curve, {"lcp": lcp, "path": path, "lam": lam[-1], "store": store,
                   "geometry": geom}


def _substructured_stats(layout: Any, lcp: Any, path: Any, how: dict[str, Any],
                         body_stats: tuple[dict[str, Any], dict[str, Any]],
                         built: dict[str, float], times: tuple[float, float, float, float]
                         ) -> dict[str, Any]:
    """A substructured curve's stats: its sizes, how its path was found (``how``), the
    operators built (``built``) and the wall-clock times (s) of its stages from ``times =
    (start, operators ready, scene condensed, path traced)``; ``body_stats`` the soil's and
    the plate's operator stats (``{}`` without a plate)."""
    st_s, st_p = body_stats
    t_start, t_ops, t_cond, t_lcp = times
    return {
        "nodes": layout.nodes, "elements": layout.elements,
        "dofs": int(st_s.get("dofs", 0)) + int(st_p.get("dofs", 0)),
        "candidates": int(lcp.q0.size), "sphere_candidates": lcp.n_sphere, "interface_dofs":
        int(layout.iface_r.size), "scene_dofs": int(lcp.dofs), "breakpoints": path.pieces,
        "prefix_path": how["prefix"], "ranks": 1,
        "operators_built": built["count"], "backward_error": max(
            float(st_s.get("backward_error", 0.0)), float(st_p.get("backward_error", 0.0))),
        "wall_mesh": built["wall_mesh"], "wall_assemble": built["wall_assemble"],
        "wall_factor": built["wall_factor"], "wall_condense": t_cond - t_ops,
        "wall_lcp": t_lcp - t_cond, "wall_total": t_lcp - t_start,
    }


def _pressure_profiles(lcp: Any, lam: np.ndarray, steps: int, profiles: int
                       ) -> tuple[np.ndarray, np.ndarray]:
    """The steps whose pressure profile a curve keeps (``profiles`` of its ``steps``,
    evenly spread) and the candidates' pressures there (Pa): their forces ``lam`` (N) over
    their surface weights (m^2)."""
    ms = lcp.n_sphere
    keep = np.unique(np.linspace(0, steps - 1, profiles).round().astype(int))
    p = lam[keep, :ms] / np.where(lcp.weight > 0, lcp.weight, np.inf)
    if lcp.r[0] == 0.0:  # the axis vertex of a P2 edge has zero weight; dp/dr = 0
        p[:, 0] = p[:, 1]
    return keep, p


def _axis_tie_max(lcp: Any, path: Any, force_end: float) -> float | None:
    """The largest force (N) the plate pulls on the soil's axis node along the path (an
    unilateral interface; None for the others); SolverError when it is a tension beyond
    round-off of the curve's last force ``force_end`` (N): the plate would lift off."""
    if lcp.tie is None:
        return None
    # affine per piece: its extremes are at the breakpoints (0 at delta = 0)
    tie_max = float(np.max(path.forces(path.breaks[1:]) @ lcp.tie))
    if tie_max > 1e-9 * max(force_end, 1e-300):
        raise SolverError(
            f"the unilateral interface's axis tie is in tension ({tie_max:.3g} N): the "
            "plate would lift off at the axis; the model does not hold")
    return tie_max


def edge_radii(r: np.ndarray, gap: np.ndarray, active: np.ndarray) -> np.ndarray:
    """:func:`ssw.contact.contact_lcp.edge_radius` of many states at once.

    ``r`` (ms,) sorted; ``gap``, ``active`` (n, ms): per state, the gaps (m) and the active
    sphere candidates. Returns (n,) m.

    Parameters
    ----------
    r : numpy.ndarray
        Radii of the sphere candidates (m), sorted, (ms,).
    gap : numpy.ndarray
        Gaps (m), (n, ms).
    active : numpy.ndarray
        Active candidates (bool), (n, ms).

    Returns
    -------
    numpy.ndarray
        Contact radii (m), (n,).

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, Cambridge University Press, eq. (3.42).
    """
    n, ms = active.shape
    any_act = active.any(axis=1)
    k = ms - 1 - np.argmax(active[:, ::-1], axis=1)
    k1, k2 = np.minimum(k + 1, ms - 1), np.minimum(k + 2, ms - 1)
    rows = np.arange(n)
    s1, s2 = np.cbrt(gap[rows, k1] ** 2), np.cbrt(gap[rows, k2] ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = r[k1] - s1 * (r[k2] - r[k1]) / (s2 - s1)
    a = np.clip(a, r[k], r[k1])
    a = np.where((k + 2 >= ms) | (s2 <= s1), r[k], a)
    return np.where(any_act, a, 0.0)


def _monolithic(
    soil: tuple[float, float], pe: tuple[float, float], plate_thickness: float, radius: float,
    cfg: dict[str, Any], deltas: np.ndarray, cache: MeshCache | None, t_start: float,
) -> tuple[ForceCurve, dict[str, Any]]:
    """The monolithic engine: one PETSc LU of the whole model, an LCP per increment."""
    plate_radius = 0.5 * float(cfg["plate_diameter"])
    if cache is None:
        mesh, order_nodes = build_mesh(plate_thickness, plate_radius, mesh_settings(cfg)), nd_order
    else:
        mesh = cache.mesh_for(plate_thickness, plate_radius, mesh_settings(cfg))
        order_nodes = cache.order_nodes
    t_mesh = time.perf_counter()
    sysm = assemble(mesh, (soil[0], pe[0]), (soil[1], pe[1]), cfg["interface"], order_nodes)
    t_asm = time.perf_counter()
    solver = LUSolver(sysm.rows, sysm.cols, sysm.vals, sysm.ndof, sysm.scale, solver="auto")
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
    tol = LCP_TOL * float(deltas[-1]) / deltas.size
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
        "solves": cond.solves, "lcp_pivots": pivots, "ranks": comm_size(),
        "backward_error": solver.backward_error,
        "wall_mesh": t_mesh - t_start, "wall_assemble": t_asm - t_mesh,
        "wall_factor": t_fact - t_asm, "wall_condense": t_cond - t_fact + cond.wall,
        "wall_lcp": t_lcp - t_cond - cond.wall, "wall_total": t_lcp - t_start,
    }
    curve = ForceCurve(
        delta=deltas, force=force, contact_radius=a, inputs={}, stats=stats,
        pressure={"r": cond.r[:ms], "delta": deltas[keep],
                  "p": np.array(profiles)[:, :ms]},
    )
    return curve, {"cond": cond, "lam": lam, "solver": solver, "system": sysm, "mesh": mesh}


def indentation_steps(delta_max: float, steps: int, delta_reach: float | None = None) -> np.ndarray:
    """Indentations (m) of the increments: one uniform step ``h = delta_max / steps`` (the
    thesis's 1000 x 0.1 um) from ``h`` to ``delta_max``, and on, with the same step, to
    ``delta_reach`` when it is deeper (``contact.delta_mode: chain``; the last increment
    ends exactly there and may be shorter).

    The curve is exact at any indentation, so its samples are spread with one density over
    the whole range: a least-squares fit weights every part of its range alike (1000
    increments to 0.1 mm and 1000 more beyond, two densities, made the fitted K jump where
    the chain's reach crosses 0.1 mm), and every multiple of ``h`` (the thesis's reference
    indentation 1 um among them) is a sample, not an interpolation.

    Parameters
    ----------
    delta_max : float
        Indentation of the uniform part (m), > 0.
    steps : int
        Number of increments to ``delta_max``, >= 1.
    delta_reach : float or None
        Indentation to continue to (m); None: stop at ``delta_max``.

    Returns
    -------
    numpy.ndarray
        Indentations (m).
    """
    h = float(delta_max) / int(steps)
    d = h * np.arange(1, int(steps) + 1)
    if delta_reach is not None and float(delta_reach) > float(delta_max) * (1 + 1e-12):
        reach = float(delta_reach)
        n = int(np.floor(reach / h * (1 + 1e-12)))
        d = h * np.arange(1, n + 1)
        if reach - d[-1] > 1e-9 * h:
            d = np.concatenate([d, [reach]])
        else:
            d[-1] = reach
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
    """Strain energy (J) of the state under contact forces ``lam`` (N): ``x^T K x / 2`` with
    the monolithic engine's stiffness, ``lam^T W lam / 2`` with the substructured one's
    condensed compliance (Clapeyron).

    Parameters
    ----------
    state : dict
        The engine's state.
    lam : numpy.ndarray
        Contact forces (N).

    Returns
    -------
    float
        Strain energy (J).
    """
    if "cond" in state:
        x = state["cond"].X @ lam
        return 0.5 * float(x @ state["solver"].matvec(x))
    W = state["lcp"].W
    return 0.5 * float(lam @ W @ lam)


def scene_plate(scene: Any, materials: dict[str, Any]) -> tuple[float, float] | None:
    """The ``(E Pa, nu)`` of a scene's plate from the material library (None: no plate);
    ConfigError naming ``plate_material`` when the library has no such material.

    Parameters
    ----------
    scene : Scene
        The study scene.
    materials : dict
        The materials library (SI).

    Returns
    -------
    tuple of float or None
        ``(E, nu)`` (Pa, -), or None.

    Raises
    ------
    ConfigError
        If the library has no such material.
    """
    if scene.plate_thickness <= 0:
        return None
    if scene.plate_material not in materials:
        raise ConfigError("plate_material", scene.plate_material,
                          f"a material of the library: {', '.join(sorted(materials))}")
    m = materials[scene.plate_material]
    return (m.E, m.nu)


def solve_scene(
    scene: Scene, contact_cfg: dict[str, Any], indenter_radius: float,
    materials: dict[str, Material], cache: MeshCache | None = None,
    *, engine: str = "substructured",
) -> ForceCurve:
    """Force-indentation curve of one scene of a study.

    Parameters
    ----------
    scene : ssw.config.Scene
        Plate material key, thickness (m, 0 = no plate), soil E (Pa) and nu.
    contact_cfg : dict
        The config's ``contact`` section.
    indenter_radius : float
        The rigid sphere's radius, m.
    materials : dict
        The material library of the study (key -> Material).
    cache : MeshCache or None
        A mesh and operator cache shared by the scenes of a batch (None: the process's).
    engine : str
        ``substructured`` (default) or ``monolithic`` (the module docstring).

    Returns
    -------
    ForceCurve
        The curve (N, m), with the scene's inputs.
    """
    if scene.sample is not None:  # a finite block: the FEM's soil domain is the block
        contact_cfg = scene.sample.contact_settings(contact_cfg)
    plate = scene_plate(scene, materials)
    plate_key = scene.plate_material if scene.plate_thickness > 0 else "none"
    if scene.soil_model is not None or scene.plate_model is not None:  # ssw.contact.plastic
        from ssw.contact.plastic import scene_curve

        return scene_curve(scene, contact_cfg, indenter_radius, plate)
    curve, state = solve_curve((scene.soil_E, scene.soil_nu), plate, scene.plate_thickness,
                               indenter_radius, contact_cfg, cache, engine=engine)
    if "solver" in state:
        state["solver"].destroy()
    inputs = {**curve.inputs, "plate_material": plate_key, "scene_id": scene.scene_id,
              "material_set": _material_set_of(materials)}
    return ForceCurve(curve.delta, curve.force, curve.contact_radius, inputs, curve.stats,
                      curve.pressure)


def _material_set_of(materials: dict[str, Material]) -> str:
    """Name of the set of the shipped library equal to ``materials`` ("custom" if none);
    remembered per library (reading the YAML library costs ~15 ms, a scene a few)."""
    try:
        key = tuple(sorted(materials.items()))
        hash(key)
    except TypeError:
        return _find_material_set(materials)
    return _material_set_cached(key)


@functools.lru_cache(maxsize=16)
def _material_set_cached(key: tuple) -> str:
    return _find_material_set(dict(key))


def _find_material_set(materials: dict[str, Material]) -> str:
    from ssw.materials import load_library, material_set

    for name in load_library():
        if material_set(name) == materials:
            return name
    return "custom"
