"""Condensed contact operators of a geometry, built once and cached (memory and disk).

A scene is a rigid sphere on a plate (or none) on a soil. Its finite element model
(:mod:`ssw.contact.mesh`, :mod:`ssw.contact.assembly`) splits into two substructures that
meet at the plate-soil interface (:mod:`ssw.contact.substructure`):

* the plate, condensed onto its contact candidates (the ``u_z`` of the top nodes with
  ``r <= zone``) and its interface dofs, at unit E: one operator per (geometry, plate nu);
* the soil, condensed onto its interface dofs at unit E: one operator per (geometry, soil
  nu); without a plate, onto the contact candidates.

Interface dofs: the normal displacement ``u_z`` of every interface node (``frictionless``,
``unilateral``), and ``u_r`` too off the axis (``bonded``). A scene's problem is then a dense
symmetric positive definite system of a few hundred unknowns, ``E_plate P + E_soil S(nu)``
(:func:`ssw.contact.coupling.scene_lcp`): per interface law, the two bodies share the
interface dofs (``frictionless``, ``bonded``), or only the one on the axis, the others
becoming a second set of contact constraints (``unilateral``: the plate may lift off).
This module builds and keeps the operators; what they keep of a geometry (its retained
dofs, a body's operator) is :mod:`ssw.contact.retained`, a scene's problem assembled from
them :mod:`ssw.contact.coupling` (both importable from here).

Candidate zone. The candidates are the top nodes with ``r <= zone``, ``zone`` =
:data:`ZONE_SHARE` of the sphere radius, rounded down to :data:`ZONE_QUANTUM` (so that the
FEM's 9.53 mm indenter and the chain's 9.525 mm bead share operators), or more when the
indentation asks for it (``candidate_factor sqrt(R delta)``). The zone does not depend on
the scene's indentation, so one operator serves every curve and the chain's wall law.

Cache. Operators are kept in memory per process and on disk under
``$SSW_CACHE_DIR/contact`` (default ``~/.cache/ssw``; ``SSW_CACHE_DIR=none`` turns the disk
cache off), one file per operator, and one per geometry for its retained dofs
(``layout.npz``) and its mesh (``model.npz``: the bodies' stress fields need it where the
operators come from the disk, :mod:`ssw.contact.stress`), named by a hash of every input
that changes it: the
geometry and mesh settings, the zone, the interface kind, nu, the source of every module
the computation runs (the import closure of this module, :func:`ssw.provenance.source_hash`:
derived from the package, not a hand list) and the versions of gmsh, numpy and scipy. A
file is written under a temporary name, flushed to disk (``fsync``, then the folder's) and
renamed into place, so concurrent jobs on a shared file system never see a partial file
(two jobs building the same operator both write a complete copy; the last rename wins). A
file that cannot be read back whole (truncated, corrupt: a crash, a full disk, another
system's copy), of another format version, or missing an array or holding one of another
shape than its record promises or its geometry needs, is removed and rebuilt with a
:class:`~ssw.cachefile.CacheWarning`, never used (:mod:`ssw.cachefile`; the formats:
:data:`LAYOUT_FORMAT`, :data:`MODEL_FORMAT`, :data:`BODY_FORMAT`).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import time
from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ssw.cachefile import CacheFormat, read_arrays, write_arrays
from ssw.cachefile import CacheWarning as CacheWarning  # where the cache's users look

# a scene's problem from the operators, importable where the operators' users look
from ssw.contact.coupling import SCENES_KEPT as SCENES_KEPT
from ssw.contact.coupling import SceneLCP as SceneLCP
from ssw.contact.coupling import coupled_stiffness as coupled_stiffness
from ssw.contact.coupling import scene_lcp as scene_lcp
from ssw.contact.mesh import Mesh, MeshSettings, build_mesh
from ssw.contact.retained import BodyOperator as BodyOperator
from ssw.contact.retained import Layout as Layout
from ssw.contact.retained import sphere_gap0 as sphere_gap0
from ssw.errors import ConfigError

#: Candidate zone radius as a share of the sphere's radius (a contact radius of R/2 is an
#: indentation of R/4, far beyond the chain's: 2.4 mm for the thesis's ball).
ZONE_SHARE = 0.5
#: m, the zone is a multiple of this (indenters within it share operators).
ZONE_QUANTUM = 1.0e-4
#: Largest zone as a share of the sphere radius (the gap formula needs r < R).
ZONE_LIMIT = 0.95
#: Version of the operators' file format (in each file's record, :mod:`ssw.cachefile`, and
#: in the cache key). 2: every file carries its record (kind, version, shapes).
FORMAT = 2


@dataclass(frozen=True)
class Geometry:
    """What a model's mesh and retained dofs depend on. Lengths in m.

    Parameters
    ----------
    plate_thickness : float
        Plate thickness (m); 0: no plate.
    plate_radius : float
        Plate radius (m).
    mesh : MeshSettings
        The mesh settings (m).
    zone : float
        Radius of the candidate zone on the top surface (m).
    bonded : bool
        Whether the interface shares u_r as well (bonded) or u_z only.
    """

    plate_thickness: float  # 0: no plate
    plate_radius: float
    mesh: MeshSettings
    zone: float  # radius of the candidate zone on the top surface
    bonded: bool  # the interface shares u_r as well (bonded) or u_z only

    def key(self) -> str:
        """Hash of the geometry, the code and the library versions (hex).

        Returns
        -------
        str
            The hex digest.
        """
        return _geometry_key(self)


@functools.lru_cache(maxsize=64)
def _geometry_key(geom: Geometry) -> str:
    return _hash({"geometry": asdict(geom), "code": _code_hash(), "format": FORMAT})


def zone_of(radius: float, candidate_factor: float, delta_end: float,
            plate_radius: float | None = None) -> float:
    """Candidate zone radius (m) for a sphere of ``radius`` pushed to ``delta_end`` (m).

    Parameters
    ----------
    radius : float
        Sphere radius (m).
    candidate_factor : float
        Zone radius in units of ``sqrt(R delta_end)``.
    delta_end : float
        Deepest indentation (m).
    plate_radius : float or None
        Plate radius (m), a bound; None or 0: none.

    Returns
    -------
    float
        Zone radius (m).

    Raises
    ------
    ConfigError
        If the zone would reach too far into the sphere's radius.
    """
    zone = np.floor(ZONE_SHARE * radius / ZONE_QUANTUM) * ZONE_QUANTUM
    need = candidate_factor * np.sqrt(radius * delta_end)
    if need > zone:
        zone = np.ceil(need / ZONE_QUANTUM) * ZONE_QUANTUM
    if zone >= ZONE_LIMIT * radius:
        raise ConfigError("contact.delta_max", delta_end,
                          f"an indentation whose contact zone ({need:.4g} m) stays within "
                          f"{ZONE_LIMIT:g} of the sphere radius ({radius:g} m)")
    if plate_radius:
        zone = min(zone, plate_radius)
    return float(zone)


def geometry_of(contact: dict[str, Any], plate_thickness: float, radius: float,
                delta_end: float, interface: str) -> Geometry:
    """The :class:`Geometry` of a scene from its (filled) ``contact`` settings.

    Parameters
    ----------
    contact : dict
        The filled contact settings (SI).
    plate_thickness : float
        Plate thickness (m).
    radius : float
        Sphere radius (m).
    delta_end : float
        Deepest indentation (m).
    interface : str
        The plate-soil interface.

    Returns
    -------
    Geometry
        The geometry.

    Raises
    ------
    ConfigError
        If the soil radius is not larger than the plate's.
    """
    from ssw.contact.mesh import mesh_settings

    plate_radius = 0.5 * float(contact["plate_diameter"]) if plate_thickness > 0 else 0.0
    if plate_radius >= float(contact["soil_radius"]):
        field = "sample.radius" if "soil_lateral" in contact else "contact.soil_radius"
        raise ConfigError(field, float(contact["soil_radius"]),
                          f"a radius larger than the plate's ({plate_radius:g} m)")
    return Geometry(
        plate_thickness=float(plate_thickness), plate_radius=plate_radius,
        mesh=mesh_settings(contact),
        zone=zone_of(radius, float(contact["candidate_factor"]), delta_end, plate_radius),
        bonded=interface == "bonded" and plate_thickness > 0,
    )


@dataclass
class _Model:
    """A built mesh with its split interface and retained-dof lists (in memory only)."""

    mesh: Mesh
    nodes: np.ndarray
    tri: np.ndarray
    body: np.ndarray
    free: np.ndarray
    cand: np.ndarray
    iface_nodes: np.ndarray  # (n_i, 2) (soil node, plate node) per retained interface dof
    iface_comp: np.ndarray
    layout: Layout
    wall_mesh: float


def _hash(obj: Any) -> str:
    text = json.dumps(obj, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


@functools.lru_cache(maxsize=1)
def _code_hash() -> str:
    """Hash of the source that computes the operators (this module's import closure) and
    of the numeric libraries' versions."""
    from importlib.metadata import version

    from ssw.provenance import source_hash

    libs = " ".join(f"{p} {version(p)}" for p in ("gmsh", "numpy", "scipy"))
    return _hash({"source": source_hash([__name__], packages=False), "libraries": libs})


def cache_dir() -> Path | None:
    """The disk cache folder: ``$SSW_CACHE_DIR/contact`` (default ``~/.cache/ssw``); None
    (memory only) when ``SSW_CACHE_DIR`` is ``none``, ``off`` or empty.

    Returns
    -------
    pathlib.Path or None
        The folder, or None.
    """
    from ssw.h5io import cache_root

    root = cache_root()
    return None if root is None else root / "contact"


#: Meshes an :class:`OperatorStore` keeps in memory (the plate design condenses a batch of
#: plates, then computes their stresses on the same meshes).
MODELS_KEPT = 16


class OperatorStore:
    """Operators by geometry and material, in memory and (optionally) on disk.

    Parameters
    ----------
    directory : the disk cache folder; ``"env"`` (default) reads :func:`cache_dir`; None:
        memory only.
    """

    def __init__(self, directory: str | Path | None = "env") -> None:
        self.directory = cache_dir() if directory == "env" else (
            Path(directory) if directory is not None else None)
        self._models: OrderedDict[str, _Model] = OrderedDict()
        self._layouts: dict[str, Layout] = {}
        self._bodies: dict[str, BodyOperator] = {}
        self.hits = {"memory": 0, "disk": 0, "built": 0}
        self._cost = {"count": 0, "wall_mesh": 0.0, "wall_assemble": 0.0, "wall_factor": 0.0}

    def pop_cost(self) -> dict[str, float]:
        """Operators built and seconds spent meshing, assembling and factoring them since
        the last call (the cost a curve's stats charge to it).

        Returns
        -------
        dict
            Operators built and seconds spent (s) by stage.
        """
        out, self._cost = self._cost, {"count": 0, "wall_mesh": 0.0, "wall_assemble": 0.0,
                                       "wall_factor": 0.0}
        return out

    # -- geometry ---------------------------------------------------------------------------
    def _model(self, geom: Geometry) -> _Model:
        """The mesh of ``geom`` with its retained dofs: from memory, the disk cache (the same
        arrays, bit for bit: meshing is deterministic), or meshed here (and kept on disk:
        a process that reads the operators of a geometry still needs its mesh for their
        stresses, ssw.contact.stress)."""
        key = geom.key()
        if key in self._models:
            self._models.move_to_end(key)
            return self._models[key]
        path = self._path(key, "model")
        model = _model_from_arrays(read_arrays(path, MODEL_FORMAT))
        if model is None:
            model = _build_model(geom)
            write_arrays(path, MODEL_FORMAT, _model_arrays(model))
        self._models[key] = model
        while len(self._models) > MODELS_KEPT:  # the last few meshes (about 1 MB each)
            self._models.popitem(last=False)
        return model

    def layout(self, geom: Geometry) -> Layout:
        """The retained dofs of ``geom`` (from memory, disk, or by meshing it).

        Parameters
        ----------
        geom : Geometry
            The scene's geometry (m).

        Returns
        -------
        Layout
            The retained dofs.
        """
        key = geom.key()
        if key in self._layouts:
            return self._layouts[key]
        path = self._path(key, "layout")
        data = read_arrays(path, LAYOUT_FORMAT)
        if data is not None:
            lay = Layout(data["r"], data["weight"], data["iface_r"], data["iface_comp"],
                         int(data["nodes"]), int(data["elements"]))
        else:
            lay = self._model(geom).layout
            write_arrays(path, LAYOUT_FORMAT, asdict(lay))
        self._layouts[key] = lay
        return lay

    def body(self, geom: Geometry, which: str, nu: float) -> BodyOperator:
        """The condensed operator of the ``plate`` or the ``soil`` of ``geom`` at Poisson's
        ratio ``nu`` (unit E).

        Parameters
        ----------
        geom : Geometry
            The scene's geometry (m).
        which : str
            ``plate`` or ``soil``.
        nu : float
            Poisson's ratio.

        Returns
        -------
        BodyOperator
            The condensed operator (unit E).

        Raises
        ------
        ConfigError
            If ``which`` is neither, or the plate has no thickness.
        """
        if which not in ("plate", "soil"):
            raise ConfigError("body", which, "plate | soil")
        if which == "plate" and geom.plate_thickness <= 0:
            raise ConfigError("plate_thickness", geom.plate_thickness, "> 0 m for a plate")
        key = _hash({"geometry": geom.key(), "body": which, "nu": float(nu)})
        if key in self._bodies:
            self.hits["memory"] += 1
            return self._bodies[key]
        path = self._path(geom.key(), f"{which}-{key}")
        data = read_arrays(path, BODY_FORMAT, {"dofs": _body_dofs(self.layout(geom), which)})
        if data is not None:
            op = BodyOperator(data["S"], json.loads(str(data["stats"])))
            self.hits["disk"] += 1
        else:
            op, factor = _condense(self._model(geom), which, float(nu))
            if factor is not None and _KEPT[0] > 0:
                from ssw.contact.substructure import LeadingBlock

                # the unit upper factor the interior solves use, not the SuperLU object
                # (its L and U twice over, SuperLU's and scipy's copies): the thesis
                # designs' peak resident memory 0.84-0.97 GB -> 0.55 GB, a quarter fewer
                # page faults
                _FACTORS[(geom.key(), which, float(nu))] = (
                    factor[0], LeadingBlock(factor[1], factor[0].n_int))
                while len(_FACTORS) > _KEPT[0]:
                    _FACTORS.popitem(last=False)
            write_arrays(path, BODY_FORMAT, {"S": op.S, "stats": json.dumps(op.stats)})
            self.hits["built"] += 1
            self._cost["count"] += 1
            for k in ("wall_mesh", "wall_assemble", "wall_factor"):
                self._cost[k] += float(op.stats[k])
        self._bodies[key] = op
        return op

    def _path(self, geom_key: str, name: str) -> Path | None:
        return None if self.directory is None else self.directory / geom_key / f"{name}.npz"


#: The scalar fields of a :class:`~ssw.contact.mesh.Mesh` and their types (the disk cache
#: keeps them as 0-d arrays).
_MESH_SCALARS = {"top": float, "plate_radius": float, "soil_radius": float,
                 "soil_depth": float, "base": str, "lateral": str, "subgrade_ratio": float,
                 "subgrade_nu": float}
#: The array fields of a :class:`_Model` besides its mesh and layout.
_MODEL_ARRAYS = ("nodes", "tri", "free", "cand", "iface_nodes", "iface_comp")

#: The shapes of a :class:`~ssw.contact.retained.Layout`'s arrays: ``nc`` contact
#: candidates, ``ni`` retained interface dofs.
_LAYOUT_SHAPES: dict[str, tuple[str | int, ...]] = {
    "r": ("nc",), "weight": ("nc",), "iface_r": ("ni",), "iface_comp": ("ni",),
    "nodes": (), "elements": ()}
_LAYOUT_KINDS = {"r": "f", "weight": "f", "iface_r": "f", "iface_comp": "iu",
                 "nodes": "iu", "elements": "iu"}
#: ``layout.npz``: a geometry's retained dofs (:meth:`OperatorStore.layout`).
LAYOUT_FORMAT = CacheFormat("contact.layout", FORMAT, _LAYOUT_SHAPES, _LAYOUT_KINDS,
                            what="layout")
#: ``model.npz``: a geometry's mesh (``mesh_*``: as many nodes and elements as its layout
#: counts, ``per_el`` nodes per element), its nodes after the interface split (``n``),
#: contact candidates (``nc``) and retained interface dofs (``ni``), and its layout
#: (``layout_*``).
MODEL_FORMAT = CacheFormat(
    "contact.model", FORMAT,
    {"mesh_nodes": ("layout_nodes", 2), "mesh_tri": ("layout_elements", "per_el"),
     "mesh_body": ("layout_elements",), "mesh_subgrade": ("layout_elements",),
     **{f"mesh_{k}": () for k in _MESH_SCALARS},
     "nodes": ("n", 2), "tri": ("layout_elements", "per_el"), "free": ("n", 2),
     "cand": ("nc",),
     "iface_nodes": ("ni", 2), "iface_comp": ("ni",),
     **{f"layout_{k}": v for k, v in _LAYOUT_SHAPES.items()}},
    {"mesh_nodes": "f", "mesh_tri": "iu", "mesh_body": "iu", "mesh_subgrade": "b",
     **{f"mesh_{k}": "U" if t is str else "f" for k, t in _MESH_SCALARS.items()},
     "nodes": "f", "tri": "iu", "free": "b", "cand": "iu", "iface_nodes": "iu",
     "iface_comp": "iu", **{f"layout_{k}": v for k, v in _LAYOUT_KINDS.items()}},
    optional=frozenset({"mesh_subgrade"}), what="mesh")
#: ``plate-*.npz``, ``soil-*.npz``: a body's condensed operator ``S`` on its ``dofs``
#: retained dofs (the plate's candidates and interface dofs; the soil's interface dofs, or
#: its candidates without a plate) and the stats of its condensation (JSON text).
BODY_FORMAT = CacheFormat("contact.body", FORMAT, {"S": ("dofs", "dofs"), "stats": ()},
                          {"S": "f", "stats": "U"}, what="operator")


def _body_dofs(layout: Layout, which: str) -> int:
    """The retained dofs of a body's operator: the plate's candidates and interface dofs;
    the soil's interface dofs under a plate, else the candidates."""
    nc, ni = layout.r.size, layout.iface_r.size
    if which == "plate":
        return nc + ni
    return ni if ni else nc


def _model_arrays(model: _Model) -> dict[str, np.ndarray]:
    """A model as the arrays of its disk-cache file (:func:`_model_from_arrays`)."""
    m = model.mesh
    out = {f"mesh_{k}": np.asarray(getattr(m, k)) for k in ("nodes", "tri", "body", *_MESH_SCALARS)}
    if m.subgrade is not None:
        out["mesh_subgrade"] = np.asarray(m.subgrade)
    out.update({k: np.asarray(getattr(model, k)) for k in _MODEL_ARRAYS})
    out.update({f"layout_{k}": np.asarray(v) for k, v in asdict(model.layout).items()})
    return out


def _model_from_arrays(data: dict[str, np.ndarray] | None) -> _Model | None:
    """The model a disk-cache file holds (:func:`_model_arrays`; checked against
    :data:`MODEL_FORMAT` when read), or None (no usable file: rebuilt)."""
    if data is None:
        return None
    mesh = Mesh(data["mesh_nodes"], data["mesh_tri"], data["mesh_body"],
                subgrade=data.get("mesh_subgrade"),
                **{k: t(data[f"mesh_{k}"]) for k, t in _MESH_SCALARS.items()})
    lay = Layout(data["layout_r"], data["layout_weight"], data["layout_iface_r"],
                 data["layout_iface_comp"], int(data["layout_nodes"]),
                 int(data["layout_elements"]))
    parts = {k: data[k] for k in _MODEL_ARRAYS}
    return _Model(mesh, parts["nodes"], parts["tri"], mesh.body, parts["free"], parts["cand"],
                  parts["iface_nodes"], parts["iface_comp"], lay, 0.0)


def _build_model(geom: Geometry) -> _Model:
    """Mesh the geometry and find its contact candidates and interface dofs."""
    from ssw.contact.assembly import (
        fixed_free,
        geometric_tolerance,
        split_interface,
        top_surface_weights,
    )

    t0 = time.perf_counter()
    mesh = build_mesh(geom.plate_thickness, geom.plate_radius, geom.mesh)
    nodes, tri, pairs = split_interface(mesh)
    tol = geometric_tolerance(nodes, tri)
    free = fixed_free(nodes, tol, mesh.soil_radius, mesh.soil_depth, mesh.base,
                          mesh.lateral)
    top_body = 1 if geom.plate_thickness > 0 else 0
    weight = top_surface_weights(nodes, tri, np.flatnonzero(mesh.body == top_body), mesh.top,
                                 tol)
    top = np.flatnonzero(weight > 0)
    top = top[np.argsort(nodes[top, 0])]
    cand = top[nodes[top, 0] <= geom.zone * (1 + 1e-12)]
    if np.any(~free[cand, 1]):
        raise ConfigError("contact.soil_radius", geom.mesh.soil_radius,
                          "a domain wider than the candidate zone")
    pairs = pairs[np.argsort(nodes[pairs[:, 0], 0])]
    if geom.bonded:
        comp = np.stack([np.zeros(len(pairs), int), np.ones(len(pairs), int)], axis=1)
        keep = np.stack([free[pairs[:, 0], 0], np.ones(len(pairs), bool)], axis=1)
        iface = np.repeat(pairs, 2, axis=0)[keep.ravel()]
        icomp = comp.ravel()[keep.ravel()]
    else:
        iface, icomp = pairs, np.ones(len(pairs), int)
    lay = Layout(nodes[cand, 0].copy(), weight[cand].copy(), nodes[iface[:, 0], 0].copy()
                 if len(iface) else np.zeros(0), icomp.astype(np.int64),
                 len(mesh.nodes), len(mesh.tri))
    return _Model(mesh, nodes, tri, mesh.body, free, cand, iface, icomp.astype(np.int64),
                  lay, time.perf_counter() - t0)


#: Factorizations of condensed bodies kept in memory for their interior solves (the
#: stresses of the states just traced: :func:`take_factor`), at most this many, inside
#: :func:`keeping_factors` only (each holds the unit upper factor of a body's LU,
#: :class:`ssw.contact.substructure.LeadingBlock`: 10-60 MB).
_FACTORS: OrderedDict[tuple[str, str, float], tuple[Any, Any]] = OrderedDict()
_KEPT = [0]


@contextlib.contextmanager
def keeping_factors(n: int) -> Iterator[None]:
    """Within the block, the factorizations of the last ``n`` bodies condensed are kept
    for :func:`take_factor`; on leaving it every one left is dropped.

    Parameters
    ----------
    n : int
        How many to keep (the bodies whose stresses follow: two per plate scene).

    Yields
    ------
    None
        Nothing; the block runs with the factorizations kept.
    """
    old = _KEPT[0]
    _KEPT[0] = int(n)
    try:
        yield
    finally:
        _KEPT[0] = old
        _FACTORS.clear()


def take_factor(geom: Geometry, which: str, nu: float) -> tuple[Any, Any] | None:
    """The body matrix and the interior solve of the pivot-free LU that the condensation of
    a body computed in this process (:func:`ssw.contact.substructure.schur_factor`,
    :class:`ssw.contact.substructure.LeadingBlock`), removed from memory.

    Parameters
    ----------
    geom : Geometry
        The scene's geometry.
    which : str
        ``plate`` or ``soil``.
    nu : float
        The body's Poisson's ratio.

    Returns
    -------
    tuple or None
        ``(BodyMatrix, LeadingBlock)``; None when the operator came from disk or memory, was
        condensed with pivoting, or was not kept (:func:`keeping_factors`).
    """
    return _FACTORS.pop((geom.key(), which, float(nu)), None)


def _condense(model: _Model, which: str, nu: float) -> tuple[BodyOperator, tuple[Any, Any] | None]:
    """Condense one body of ``model`` (unit E) onto its retained dofs; with the operator,
    its body matrix and factorization (None after the pivoted fallback)."""
    from ssw.contact.substructure import condense_body, min_degree_order

    plate = which == "plate"
    has_plate = bool(np.any(model.body == 1))
    tri = model.tri[model.body == (1 if plate else 0)]
    if plate:
        b_nodes = np.concatenate([model.cand, model.iface_nodes[:, 1]])
        b_comps = np.concatenate([np.ones(len(model.cand), int), model.iface_comp])
    elif has_plate:
        b_nodes, b_comps = model.iface_nodes[:, 0], model.iface_comp
    else:
        b_nodes, b_comps = model.cand, np.ones(len(model.cand), int)
    E_el: Any = 1.0
    nu_el: Any = nu
    sub = model.mesh.subgrade
    if not plate and sub is not None:  # a lift on its subgrade: one soil body, two materials
        s = sub[model.body == 0]
        E_el = np.where(s, model.mesh.subgrade_ratio, 1.0)
        nu_el = np.where(s, model.mesh.subgrade_nu, nu)
    c = condense_body(model.nodes, tri, nu_el, model.free, b_nodes, b_comps, min_degree_order,
                      E_el)
    stats = {"dofs": c.dofs, "nnz_factor": c.nnz_factor, "backward_error": c.backward_error,
             "pivoted": c.pivoted, "wall_mesh": model.wall_mesh,
             "wall_assemble": c.wall_assemble, "wall_factor": c.wall_factor}
    model.wall_mesh = 0.0  # the mesh is paid once
    return BodyOperator(c.S, stats), (None if c.factor is None else (c.body, c.factor))


#: The store of this process (``ssw contact`` batches, the chain's fem wall).
_DEFAULT: OperatorStore | None = None


def default_store() -> OperatorStore:
    """The process-wide :class:`OperatorStore` (disk cache from ``$SSW_CACHE_DIR``).

    Returns
    -------
    OperatorStore
        The store.
    """
    global _DEFAULT
    if _DEFAULT is None or _DEFAULT.directory != cache_dir():
        _DEFAULT = OperatorStore()
    return _DEFAULT
