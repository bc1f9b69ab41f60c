"""Axisymmetric (r, z) mesh of a plate on a soil sample, built with the gmsh Python API.

The soil sample occupies ``0 <= r <= soil_radius``, ``-soil_depth <= z <= 0``; the plate (if
``plate_thickness > 0``) occupies ``0 <= r <= plate_radius``, ``0 <= z <= plate_thickness``.
The sphere touches the top surface at ``(0, top)``. Element sizes grow linearly with the
distance ``d`` from that point, ``h(d) = clip(growth * d, size_contact, size_max)`` (a gmsh
Distance + Threshold field), so that every contact radius between ``size_contact / growth``
and the largest is resolved by about ``1 / growth`` elements. The plate is a structured
(transfinite) band graded the same way: along r a geometric progression of ratio
``1 + growth`` from ``size_contact`` at the axis, through the thickness a progression of
the same ratio from ``size_contact`` at the loaded top face, with at least ``plate_layers``
layers. Elements are 6-node (quadratic) triangles.

Two refinements serve a plastic path's elastic part (:mod:`ssw.contact.plastic_mesh`);
both are off by default, and a mesh without them is the one the settings always gave:

* a plateau (``near_size > 0``): the mesh of the element ``near_size`` at the contact
  point, ``clip(growth d, near_size, size_max)``, made finer within ``near_size /
  near_growth`` of it, where the elements grow as ``near_growth`` times the distance from
  ``size_contact`` on: ``h(d) = min(clip(growth d, near_size, size_max), max(near_growth d,
  size_contact))`` there (gmsh Thresholds, the inner one cut off at the plateau's edge by
  a step);
* spots (``spot_size > 0``): about each point of ``spot_points`` (radius, depth below the
  loaded surface) the element is ``spot_size`` within ``spot_radius``, growing by
  ``spot_growth`` of the distance beyond (a gmsh Min with the rest).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.contact.elements import triangle_jacobian
from ssw.errors import MeshError

#: gmsh element type of the 6-node triangle.
GMSH_TRIANGLE6 = 9


@dataclass(frozen=True)
class MeshSettings:
    """Domain and mesh density. Lengths in m.

    Parameters
    ----------
    soil_radius : float
        m, radius of the soil sample (rollers on ``r = soil_radius``).
    soil_depth : float
        m, depth of the soil sample (fixed bottom).
    size_contact : float
        m, element size at the contact point.
    growth : float
        -, element size / distance from the contact point.
    size_max : float
        m, largest element size.
    plate_layers : int
        Elements through the plate thickness.
    base : str
        Bottom: ``bonded`` (u = 0) | ``sliding`` (u_z = 0) on a rigid base.
    lateral : str
        Side: ``mould`` (rollers, u_r = 0) | ``free`` (traction-free).
    subgrade_depth : float
        m, a lift of this thickness on a subgrade below (0: none).
    subgrade_ratio : float
        -, the subgrade's E over the lift's.
    subgrade_nu : float
        -, the subgrade's Poisson's ratio.
    near_size : float
        m, the element at the contact point outside a plateau (0: none).
    near_growth : float
        -, element size / distance within the plateau.
    spot_size : float
        m, element size in spots (balls about points; 0: none).
    spot_points : tuple
        ``((r, depth), ...)`` in m (depth below the loaded surface): the spots' centres.
    spot_radius : float
        m, the spots' radius (``spot_size`` within it).
    spot_growth : float
        -, element size / distance beyond a spot.
    """

    soil_radius: float  # m, radius of the soil sample (rollers on r = soil_radius)
    soil_depth: float  # m, depth of the soil sample (fixed bottom)
    size_contact: float  # m, element size at the contact point
    growth: float  # element size / distance from the contact point, -
    size_max: float  # m, largest element size
    plate_layers: int  # elements through the plate thickness
    base: str = "bonded"  # bottom: bonded (u = 0) | sliding (u_z = 0) on a rigid base
    lateral: str = "mould"  # side: mould (rollers, u_r = 0) | free (traction-free)
    subgrade_depth: float = 0.0  # m, a lift of this thickness on a subgrade below (0: none)
    subgrade_ratio: float = 1.0  # subgrade E / the lift's E
    subgrade_nu: float = 0.0  # the subgrade's Poisson's ratio
    near_size: float = 0.0  # m, the element at the contact point outside a plateau (0: none)
    near_growth: float = 0.0  # element size / distance within the plateau, -
    spot_size: float = 0.0  # m, element size in spots (balls about points; 0: none)
    spot_points: tuple = ()  # ((r m, depth m below the loaded surface), ...): the spots
    spot_radius: float = 0.0  # m, the spots' radius (spot_size within it)
    spot_growth: float = 0.0  # element size / distance beyond a spot, -


@dataclass(frozen=True)
class Mesh:
    """A quadratic triangle mesh of the (r, z) half-plane section.

    ``nodes`` (n, 2) m; ``tri`` (ne, 6) node indices (3 vertices then the midsides of edges
    01, 12, 20); ``body`` (ne,) 0 = soil, 1 = plate; ``top`` is the z of the loaded surface.

    Parameters
    ----------
    nodes : numpy.ndarray
        (n, 2) m, the nodes' ``(r, z)``.
    tri : numpy.ndarray
        (ne, 6) node indices: 3 vertices, then the midsides of edges 01, 12, 20.
    body : numpy.ndarray
        (ne,) 0 = soil, 1 = plate.
    top : float
        m, the z of the loaded surface.
    plate_radius : float
        m, radius of the plate (0: none).
    soil_radius : float
        m, radius of the soil sample.
    soil_depth : float
        m, depth of the soil sample.
    base : str
        Bottom condition: ``bonded`` | ``sliding``.
    lateral : str
        Side condition: ``mould`` | ``free``.
    subgrade : numpy.ndarray or None
        (ne,) bool, the soil elements of the subgrade (below the lift); None: no subgrade.
    subgrade_ratio : float
        -, the subgrade's E over the lift's.
    subgrade_nu : float
        -, the subgrade's Poisson's ratio.
    """

    nodes: np.ndarray
    tri: np.ndarray
    body: np.ndarray
    top: float
    plate_radius: float
    soil_radius: float
    soil_depth: float
    base: str = "bonded"
    lateral: str = "mould"
    # (ne,) bool, the soil elements of the subgrade (below the lift); None: no subgrade;
    # its E relative to the lift's and its Poisson's ratio
    subgrade: np.ndarray | None = None
    subgrade_ratio: float = 1.0
    subgrade_nu: float = 0.0

    @property
    def vertices(self) -> np.ndarray:
        """Indices of the nodes that are element vertices (carry a pressure dof)."""
        return np.unique(self.tri[:, :3])


def _progression_nodes(length: float, first: float, ratio: float) -> int:
    """Nodes of a geometric progression of first size ``first`` and ``ratio`` over ``length``."""
    n_seg = np.log1p(length * (ratio - 1.0) / first) / np.log(ratio)
    return int(np.ceil(n_seg)) + 1


def _transfinite_plate(gmsh, t: float, rp: float, s: MeshSettings) -> None:
    """Structured plate graded from the contact point (see the module docstring)."""
    ratio = 1.0 + s.growth
    n_r = _progression_nodes(rp, s.size_contact, ratio)
    n_z = max(_progression_nodes(t, s.size_contact, ratio), s.plate_layers + 1)
    plate = [tag for _, tag in gmsh.model.getEntities(2)
             if gmsh.model.getBoundingBox(2, tag)[1] > -0.5 * t]
    if len(plate) != 1:
        raise MeshError(f"expected one plate surface, found {len(plate)}")
    for _, c in gmsh.model.getBoundary([(2, plate[0])], oriented=False):
        xmin, _, _, xmax, _, _ = gmsh.model.getBoundingBox(1, c)
        start = gmsh.model.getValue(0, gmsh.model.getAdjacencies(1, c)[1][0], [])
        if abs(xmax - xmin) < 0.5 * t:  # through the thickness: fine at the top
            coef = ratio if start[1] > 0.5 * t else -ratio
            gmsh.model.mesh.setTransfiniteCurve(c, n_z, "Progression", coef)
        else:  # along r: fine at the axis
            coef = ratio if start[0] < 0.5 * t else -ratio
            gmsh.model.mesh.setTransfiniteCurve(c, n_r, "Progression", coef)
    gmsh.model.mesh.setTransfiniteSurface(plate[0])


def build_mesh(plate_thickness: float, plate_radius: float, s: MeshSettings) -> Mesh:
    """Mesh the soil sample and (if ``plate_thickness > 0``) the plate on top of it.

    Parameters
    ----------
    plate_thickness : float
        The plate's thickness, m; 0 for no plate.
    plate_radius : float
        Half the plate diameter, m.
    s : MeshSettings
        Domain and density settings.

    Returns
    -------
    Mesh
        With conforming nodes on the plate-soil interface (the solver duplicates them for
        the frictionless and unilateral interfaces).
    """
    import gmsh

    if plate_thickness > 0 and plate_radius >= s.soil_radius:
        raise MeshError(
            f"plate radius {plate_radius} m must be smaller than soil_radius {s.soil_radius} m"
        )
    initialized_here = not gmsh.isInitialized()
    if initialized_here:
        gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.add("ssw_contact")
        return _build(gmsh, plate_thickness, plate_radius, s)
    except MeshError:
        raise
    except Exception as exc:  # gmsh raises plain Exceptions
        raise MeshError(f"gmsh failed to mesh the scene: {exc}") from exc
    finally:
        gmsh.model.remove()
        if initialized_here:
            gmsh.finalize()


def _build(gmsh, t: float, rp: float, s: MeshSettings) -> Mesh:
    occ = gmsh.model.occ
    h = float(s.subgrade_depth)
    if h > 0 and not h < s.soil_depth:
        raise MeshError(f"the lift ({h} m) must be thinner than the soil domain "
                        f"({s.soil_depth} m)")
    if h > 0:  # a lift on a subgrade: two soil regions sharing the line z = -h
        soil = occ.addRectangle(0.0, -h, 0.0, s.soil_radius, h)
        sub = occ.addRectangle(0.0, -s.soil_depth, 0.0, s.soil_radius, s.soil_depth - h)
        others = [(2, sub)]
    else:
        soil = occ.addRectangle(0.0, -s.soil_depth, 0.0, s.soil_radius, s.soil_depth)
        others = []
    if t > 0:
        others.append((2, occ.addRectangle(0.0, 0.0, 0.0, rp, t)))
    if others:
        occ.fragment([(2, soil)], others)
    occ.synchronize()
    top = float(t)

    # graded sizes from the contact point
    pt = occ.addPoint(0.0, top, 0.0)
    occ.synchronize()
    field = gmsh.model.mesh.field
    dist = field.add("Distance")
    field.setNumbers(dist, "PointsList", [pt])
    thr = field.add("Threshold")
    field.setNumber(thr, "InField", dist)
    field.setNumber(thr, "SizeMin", s.size_contact)
    field.setNumber(thr, "SizeMax", s.size_max)
    field.setNumber(thr, "DistMin", s.size_contact / s.growth)
    field.setNumber(thr, "DistMax", s.size_max / s.growth)
    background = _refinements(occ, field, dist, thr, top, s)
    field.setAsBackgroundMesh(background)
    for opt in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
        gmsh.option.setNumber(f"Mesh.{opt}", 0)
    gmsh.option.setNumber("Mesh.Algorithm", 6)  # Frontal-Delaunay

    if t > 0:
        _transfinite_plate(gmsh, t, rp, s)
    gmsh.model.mesh.generate(2)
    gmsh.model.mesh.setOrder(2)

    tags, coords, _ = gmsh.model.mesh.getNodes()
    xyz = coords.reshape(-1, 3)[:, :2]
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    tris, bodies = [], []
    for dim, tag in gmsh.model.getEntities(2):
        etypes, _, enodes = gmsh.model.mesh.getElements(dim, tag)
        for et, en in zip(etypes, enodes, strict=True):
            if et != GMSH_TRIANGLE6:
                raise MeshError(f"unexpected gmsh element type {et} (want 6-node triangles)")
            conn = index[np.asarray(en, dtype=np.int64).reshape(-1, 6)]
            ymin = gmsh.model.getBoundingBox(dim, tag)[1]
            is_plate = t > 0 and ymin > -0.5 * t
            tris.append(conn)
            bodies.append(np.full(len(conn), 1 if is_plate else 0, dtype=np.int8))
    tri = np.concatenate(tris)
    used = np.unique(tri)
    renum = np.full(len(xyz), -1, dtype=np.int64)
    renum[used] = np.arange(len(used))
    nodes = xyz[used].copy()
    tri = renum[tri]
    _check_orientation(nodes, tri)
    body = np.concatenate(bodies)
    subgrade = None
    if h > 0:
        zc = nodes[tri[:, :3], 1].mean(axis=1)
        subgrade = (body == 0) & (zc < -h)
    return Mesh(nodes, tri, body, top, rp if t > 0 else 0.0,
                s.soil_radius, s.soil_depth, s.base, s.lateral, subgrade, s.subgrade_ratio,
                s.subgrade_nu)



def _refinements(occ, field, dist: int, thr: int, top: float, s: MeshSettings) -> int:
    """The background field of the refinements (module docstring), from the distance field
    ``dist`` to the contact point and its threshold ``thr`` (whose bounds the plateau
    changes); ``thr`` itself when both are off. ``top``: the loaded surface's height, m."""
    background = thr
    if s.near_size > 0:  # a finer grading inside a plateau (module docstring)
        # outside: the mesh of the element near_size at the contact point
        field.setNumber(thr, "SizeMin", s.near_size)
        field.setNumber(thr, "DistMin", s.near_size / s.growth)
        fine = field.add("Threshold")  # inside: near_growth times the distance
        field.setNumber(fine, "InField", dist)
        field.setNumber(fine, "SizeMin", s.size_contact)
        field.setNumber(fine, "SizeMax", s.size_max)
        field.setNumber(fine, "DistMin", s.size_contact / s.near_growth)
        field.setNumber(fine, "DistMax", s.size_max / s.near_growth)
        edge = s.near_size / s.near_growth
        step = field.add("Threshold")  # none beyond the plateau's edge
        field.setNumber(step, "InField", dist)
        field.setNumber(step, "SizeMin", 1e-3 * s.size_contact)
        field.setNumber(step, "SizeMax", 1e3 * s.size_max)
        field.setNumber(step, "DistMin", edge)
        field.setNumber(step, "DistMax", edge * (1.0 + 1e-9))
        inside = field.add("Max")
        field.setNumbers(inside, "FieldsList", [fine, step])
        background = field.add("Min")
        field.setNumbers(background, "FieldsList", [thr, inside])
    if s.spot_size > 0 and s.spot_points:  # balls refined about points (module docstring)
        pts = [occ.addPoint(r, top - depth, 0.0) for r, depth in s.spot_points]
        occ.synchronize()
        d_s = field.add("Distance")
        field.setNumbers(d_s, "PointsList", pts)
        spot = field.add("Threshold")
        field.setNumber(spot, "InField", d_s)
        field.setNumber(spot, "SizeMin", s.spot_size)
        field.setNumber(spot, "SizeMax", s.size_max)
        field.setNumber(spot, "DistMin", s.spot_radius)
        field.setNumber(spot, "DistMax", s.spot_radius + (s.size_max - s.spot_size)
                        / s.spot_growth)
        finer = field.add("Min")
        field.setNumbers(finer, "FieldsList", [background, spot])
        background = finer
    return background


def _check_orientation(nodes: np.ndarray, tri: np.ndarray) -> None:
    """Raise MeshError on degenerate elements; flip clockwise ones in place."""
    p = nodes[tri[:, :3]]
    det = triangle_jacobian(p)[1]
    scale = np.max(np.abs(p[:, 1:] - p[:, :1]), axis=(1, 2)) ** 2
    if np.any(np.abs(det) < 1e-12 * scale):
        raise MeshError("the mesh has degenerate (zero-area) triangles")
    cw = det < 0
    if np.any(cw):
        tri[cw] = tri[cw][:, [0, 2, 1, 5, 4, 3]]


def mesh_settings(cfg: dict[str, Any]) -> MeshSettings:
    """Mesh settings of a (filled) contact config.

    Parameters
    ----------
    cfg : dict
        The filled ``contact`` section (``soil_radius``, ``mesh_size_contact``, ... in m).

    Returns
    -------
    MeshSettings
        The settings, a lift's subgrade included when ``subgrade_depth`` > 0.

    Raises
    ------
    ssw.errors.ConfigError
        A subgrade without a modulus ratio, or with one out of range.
    """
    return MeshSettings(
        soil_radius=float(cfg["soil_radius"]),
        soil_depth=float(cfg["soil_depth"]),
        size_contact=float(cfg["mesh_size_contact"]),
        growth=float(cfg["mesh_growth"]),
        size_max=float(cfg["mesh_size_max"]),
        plate_layers=int(cfg["plate_layers"]),
        base=str(cfg.get("soil_base", "bonded")),
        lateral=str(cfg.get("soil_lateral", "mould")),
        **_subgrade(cfg),
    )


def _subgrade(cfg: dict[str, Any]) -> dict[str, float]:
    """The subgrade of a lift (``subgrade_depth`` m, the lift's thickness; ``subgrade_ratio``
    its E over the lift's, set per scene by the solver from ``subgrade_E``; ``subgrade_nu``);
    none by default."""
    from ssw.errors import ConfigError

    h = float(cfg.get("subgrade_depth") or 0.0)
    if h <= 0:
        return {}
    if "subgrade_ratio" not in cfg:
        raise ConfigError("contact.subgrade_E", cfg.get("subgrade_E"),
                          "a lift's subgrade for a scene of known soil modulus (ssw contact; "
                          "the fem wall models samples on a rigid base only)")
    ratio, nu = float(cfg["subgrade_ratio"]), float(cfg.get("subgrade_nu", 0.3))
    if not (ratio > 0 and -1.0 < nu <= 0.5):
        raise ConfigError("contact.subgrade", {"ratio": ratio, "nu": nu},
                          "a subgrade modulus > 0 Pa and a Poisson's ratio in (-1, 0.5]")
    return {"subgrade_depth": h, "subgrade_ratio": ratio, "subgrade_nu": nu}
