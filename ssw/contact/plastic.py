"""Elasto-plastic contact: a rigid frictionless sphere pressed into (and lifted off) a plastic
sample (any model of :mod:`ssw.constitutive`), directly or through a plate (elastic or
yielding), with an active set on the contact inside Newton's iteration.

The solver is split by concept; this module is its entry point (a study scene's path, the
curve files) and keeps every public name importable:

* :mod:`ssw.contact.plastic_model`: the discrete u-p problem of one mesh (the element, the
  condensed far field, the Newton matrix and its solves);
* :mod:`ssw.contact.plastic_path`: the path, increment by increment (the active set inside
  Newton's iteration, cutbacks);
* :mod:`ssw.contact.plastic_elastic`: its elastic parts (elastic spans, first yield located
  between the increments);
* :mod:`ssw.contact.plastic_mesh`: the meshes a path is solved on.

Discretization. The scene's mesh (:func:`ssw.contact.mesh.build_mesh`) and the
Taylor-Hood u-p element of the elastic engine (:mod:`ssw.contact.elements`: P2
displacements, continuous P1 mean stress ``p``), written for a nonlinear deviatoric law
(Simo & Hughes 1998, sec. 4.4; de Souza Neto et al. 2008, sec. 15.4). Von Mises flow is
isochoric, so ``dev sigma`` depends on ``dev eps`` alone and ``p = K tr eps`` stays
elastic: the mixed form is exact and free of volumetric locking for any ``nu < 0.5`` and
any plastic flow (a pure displacement P2 element locks as the plastic zone becomes
incompressible). Below yield the equations are the elastic engine's, so on the elastic
engine's mesh the curve is that engine's (tests/test_contact_plastic.py). Models with
plastic volume change (Drucker-Prager, crushable foam) take their mean stress from the
return mapping: for them the solver uses the displacement form of the same P2 element,
free of locking as long as neither the elastic nor the plastic response is near
incompressible (foams crush with a plastic Poisson's ratio near 0; a dilatant soil changes
volume); below yield it differs from the elastic engine by the P2 discretization error.

Plate. A plate on the sample (the thesis's device) is meshed as by the elastic engine and
tied to the sample by the contact config's ``interface``: ``frictionless`` (the thesis's;
the two surfaces share ``u_z`` and slide freely) or ``bonded``. The tie is bilateral, as
the elastic engine's: on unloading the plate follows the dent it pressed (a plate that
springs back off a permanent dent, the ``unilateral`` interface, is refused). The plate is
elastic, or yields by its own model (``plate_model``: von Mises with the plate material's
strength; the sample may then be elastic, ``model=None``). Below yield the curve is the
elastic engine's with the same plate (tests); a plate of the sample's own material bonded
to it yields as the half-space does (Johnson's first yield, tests). The residual
indentation splits into the interface's depth on the axis and the plate's thinning there.

A study config's plastic curve (``ssw contact --soil-model``) is solved on the config's
domain and growth with its element at the contact point scaled to the path
(:func:`path_mesh_settings`; ``--plastic-mesh study``: the elastic engine's mesh, whose
element at the contact point resolves indentations down to 3e-7 m); times and errors
against a converged mesh: ``ssw bench plastic --plastic-study``.

References
----------
Johnson, K. L. (1985). *Contact Mechanics*. Cambridge, sec. 4.2, 6.1.
Simo, J. C. & Hughes, T. J. R. (1998). *Computational Inelasticity*. Springer.
de Souza Neto, E. A., Peric, D. & Owen, D. R. J. (2008). *Computational Methods for
Plasticity*. Wiley.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.contact.plastic_mesh import (
    ELASTIC_GROWTH,
    NEAR,
    PATH_RESOLVED,
    contact_mesh,
    elastic_mesh_settings,
    hertz_yield_point,
    near_radius,
    path_mesh_settings,
    plate_contact_radius,
)
from ssw.contact.plastic_path import (
    MAX_CUTS,
    MAX_ITER,
    RTOL,
    STALL_RTOL,
    ContactZoneError,
    PlasticCurve,
    solve_path,
)
from ssw.errors import ConfigError

__all__ = [
    "DATASETS", "ELASTIC_GROWTH", "KIND", "MAX_CUTS", "MAX_ITER", "NEAR", "PATH_RESOLVED",
    "PLASTIC_MESHES", "RTOL", "STALL_RTOL", "ContactZoneError", "PlasticCurve",
    "contact_mesh", "elastic_mesh_settings", "hertz_yield_point", "johnson_first_yield",
    "loading_curve", "near_radius", "path_mesh_settings", "plate_contact_radius",
    "read_plastic_curve", "scene_curve", "scene_meshes", "scene_path", "solve_path",
    "solve_plastic_scene", "summary", "write_plastic_curve",
]


def johnson_first_yield(E: float, nu: float, Y: float, radius: float) -> tuple[float, float]:
    """Hertz force (N) and indentation (m) at first yield of a von Mises half-space under a
    rigid sphere (Johnson 1985, sec. 6.1): ``p0 = k Y`` with ``k`` the peak of
    ``(sigma_r - sigma_z) / p0`` on the axis (1.61 at nu 0.3), ``a = pi p0 R / (2 E*)``,
    ``F = 2/3 pi a^2 p0``, ``delta = a^2 / R``; ``k`` computed from the axis stresses.

    Parameters
    ----------
    E : float
        Pa, the half-space's Young's modulus.
    nu : float
        -, its Poisson's ratio (``E* = E / (1 - nu^2)``, the sphere rigid).
    Y : float
        Pa, its yield stress in tension/compression (von Mises).
    radius : float
        m, the sphere's radius.

    Returns
    -------
    tuple of float
        The force (N) and the indentation (m) at first yield.

    References
    ----------
    K. L. Johnson, *Contact Mechanics*, Cambridge University Press (1985), sec. 6.1.
    """
    from ssw.constitutive.yield_index import first_yield_ratio

    k = first_yield_ratio(nu)
    Es = E / (1.0 - nu * nu)
    p0 = k * Y
    a = np.pi * p0 * radius / (2.0 * Es)
    return float(2.0 / 3.0 * np.pi * a * a * p0), float(a * a / radius)


#: Plastic mesh choices of :func:`solve_plastic_scene`.
PLASTIC_MESHES = ("path", "study")


def solve_plastic_scene(
    soil: tuple[float, float], model: Any, radius: float, contact_cfg: dict[str, Any],
    unload: bool = False, plate: tuple[float, float] | None = None,
    plate_thickness: float = 0.0, plate_model: Any = None, mesh: str = "path",
) -> PlasticCurve:
    """The plastic curve of a sphere on a sample, through a plate, with the contact
    config's domain (a finite block's boundaries included), mesh growth and increments
    (:func:`ssw.contact.scene.settings_of`, :func:`ssw.contact.scene.indentation_steps`),
    on the meshes of :func:`scene_meshes`.

    Parameters
    ----------
    soil : tuple of float
        The sample's ``(E Pa, nu)``.
    model : model of :mod:`ssw.constitutive` or None
        The sample's law (None: elastic).
    radius : float
        The sphere's radius, m.
    contact_cfg : dict
        The config's ``contact`` section (``plate_diameter`` and ``interface`` too).
    unload : bool
        Lift the sphere back after loading.
    plate : tuple of float or None
        The plate's ``(E Pa, nu)`` when ``plate_thickness > 0``.
    plate_thickness : float
        The plate's thickness, m (0: none).
    plate_model : model of :mod:`ssw.constitutive` or None
        The plate's law (None: elastic).
    mesh : str
        ``path``: the path's two meshes (:func:`scene_meshes`); ``study``: the elastic
        engine's mesh as configured, throughout.

    Returns
    -------
    PlasticCurve
        The path (:func:`solve_path`).

    Raises
    ------
    ConfigError
        On a plate without its elastic constants, or an unknown ``mesh``.
    """
    deltas, plastic, elastic, sizes = scene_meshes(soil, model, radius, contact_cfg, plate,
                                                   plate_thickness, plate_model, mesh)
    from ssw.contact.scene import settings_of

    cfg_interface = str(settings_of(contact_cfg)["interface"])
    t = float(plate_thickness)
    curve = solve_path(plastic, float(soil[0]), float(soil[1]), model, radius, deltas,
                       unload, plate=plate if t > 0 else None, interface=cfg_interface,
                       plate_model=plate_model if t > 0 else None, elastic_mesh=elastic)
    curve.stats.update(sizes)
    return curve


def scene_meshes(
    soil: tuple[float, float], model: Any, radius: float, contact_cfg: dict[str, Any],
    plate: tuple[float, float] | None = None, plate_thickness: float = 0.0,
    plate_model: Any = None, mesh: str = "path", elastic_growth: float = ELASTIC_GROWTH,
) -> tuple[np.ndarray, Any, Any, dict[str, float]]:
    """The increments and meshes of :func:`solve_plastic_scene`.

    ``path`` (two meshes, :func:`ssw.contact.plastic_path.solve_path`'s ``elastic_mesh``):
    the plastic part on the study's domain and growth with its element at the contact
    point scaled to the path's end (:func:`path_mesh_settings`); the elastic part (the
    increments before first yield) on that mesh graded finer towards the contact point,
    down to the study's element there (the elastic engine's), and, on a bare sample,
    refined where Hertz's field first yields and at the contact's edge then
    (:func:`elastic_mesh_settings`, :func:`hertz_yield_point`). ``study``: the elastic
    engine's mesh as configured, one mesh.

    Parameters
    ----------
    soil : tuple of float
        The sample's ``(E Pa, nu)``.
    model : model of :mod:`ssw.constitutive` or None
        The sample's law (None: elastic).
    radius : float
        The sphere's radius, m.
    contact_cfg : dict
        The config's ``contact`` section.
    plate : tuple of float or None
        The plate's ``(E Pa, nu)`` when ``plate_thickness > 0``.
    plate_thickness : float
        The plate's thickness, m (0: none).
    plate_model : model of :mod:`ssw.constitutive` or None
        The plate's law (None: elastic).
    mesh : str
        ``path`` (two meshes) | ``study`` (one), as :func:`solve_plastic_scene`'s.
    elastic_growth : float
        The elastic part's grading (:func:`elastic_mesh_settings`'s ``growth``).

    Returns
    -------
    tuple
        The loading increments (m), the mesh, the elastic part's mesh (None: the one
        mesh) and the element sizes at the contact point (``mesh_size_contact``,
        ``elastic_mesh_size_contact``; m).

    Raises
    ------
    ConfigError
        On a plate without its elastic constants, or an unknown ``mesh``.
    """
    from ssw.contact.mesh import build_mesh, mesh_settings
    from ssw.contact.scene import indentation_steps, settings_of

    if mesh not in PLASTIC_MESHES:
        raise ConfigError("--plastic-mesh", mesh, " | ".join(PLASTIC_MESHES))
    cfg = settings_of(contact_cfg)
    t = float(plate_thickness)
    if t > 0 and plate is None:
        raise ConfigError("plate", None, "the plate's (E Pa, nu) when plate_thickness > 0")
    deltas = indentation_steps(float(cfg["delta_max"]), int(cfg["steps"]))
    study = mesh_settings(cfg)
    rp = 0.5 * float(cfg["plate_diameter"]) if t > 0 else 0.0
    if mesh == "study":
        return deltas, build_mesh(t, rp, study), None, {
            "mesh_size_contact": study.size_contact}
    d_end = float(deltas[-1])
    a_c = None
    if plate_model is not None and t > 0:
        a_c = plate_contact_radius(radius, d_end, soil, plate)
    settings = path_mesh_settings(study, radius, d_end, t, a_c)
    # where a bare sample first yields under Hertz's field (a plate moves it): the elastic
    # part's mesh is refined there
    spot = hertz_yield_point(model, float(soil[0]), float(soil[1]), radius) if (
        model is not None and t == 0) else None
    elastic = elastic_mesh_settings(study, settings.size_contact,
                                    spot if spot is not None and spot[0] <= d_end else None,
                                    elastic_growth, radius)
    return deltas, build_mesh(t, rp, settings), build_mesh(t, rp, elastic), {
        "mesh_size_contact": settings.size_contact,
        "elastic_mesh_size_contact": elastic.size_contact}


#: ``ssw_kind`` of a plastic curve file.
KIND = "plastic_contact_curve"
#: Per-increment datasets of a plastic curve file: name -> (attribute, units, description).
DATASETS = {
    "delta": ("delta", "m", "indentation of the rigid sphere (loading, then unloading)"),
    "force": ("force", "N", "reaction force on the sphere"),
    "branch": ("branch", "1", "0 loading, 1 unloading"),
    "contact_radius": ("contact_radius", "m", "contact radius"),
    "dissipated": ("dissipated", "J", "cumulative plastic work"),
    "plastic_volume": ("plastic_volume", "m^3", "volume of the points that have yielded"),
    "plastic_depth": ("plastic_depth", "m", "depth of the plastic zone"),
    "plastic_radius": ("plastic_radius", "m", "radius of the plastic zone"),
    "iterations": ("iterations", "1", "Newton iterations of the increment"),
    "yield_ratio": ("yield_ratio", "1", "largest q / Y"),
}


def summary(curve: PlasticCurve) -> dict[str, Any]:
    """The scalars of a path (SI): first yield, permanent set, works.

    Parameters
    ----------
    curve : PlasticCurve
        The path.

    Returns
    -------
    dict
        ``first_yield_force`` (N), ``first_yield_delta``, ``residual_indentation``,
        ``interface_residual_indentation``, ``plate_thinning`` (m; None where unknown),
        ``dissipated_work``, ``external_work``, ``stored_energy`` (J), ``force_max`` (N).
    """
    under, total = curve.interface_residual, curve.residual_indentation
    return {"first_yield_force": curve.first_yield_force,
            "first_yield_delta": curve.first_yield_delta,
            "residual_indentation": total,
            "interface_residual_indentation": under,
            "plate_thinning": None if under is None or total is None else total - under,
            "dissipated_work": curve.dissipated_work, "external_work": curve.external_work,
            "stored_energy": curve.stored_energy,
            "force_max": float(np.max(curve.force)) if curve.force.size else 0.0}


def write_plastic_curve(path: Any, curve: PlasticCurve, inputs: dict[str, Any]) -> None:
    """Write ``curve`` (both branches) and its inputs to HDF5 ``path`` atomically.

    Parameters
    ----------
    path : str or Path
        The HDF5 file.
    curve : PlasticCurve
        The path (its :data:`DATASETS`, :func:`summary` and ``stats``).
    inputs : dict
        The inputs recorded in the file's provenance.
    """
    from ssw.h5io import atomic_h5, write_dataset

    with atomic_h5(path, kind=KIND, inputs=inputs) as f:
        for name, (attr, units, text) in DATASETS.items():
            write_dataset(f, name, getattr(curve, attr), units, text)
        for k, v in summary(curve).items():
            f.attrs[k] = np.nan if v is None else v
        st = f.create_group("stats")
        for k, v in curve.stats.items():
            st.attrs[k] = v


def read_plastic_curve(path: Any) -> dict[str, Any]:
    """The datasets and scalars of a plastic curve file (None for an unknown scalar).

    Parameters
    ----------
    path : str or Path
        A file of :func:`write_plastic_curve`.

    Returns
    -------
    dict
        The :data:`DATASETS` arrays, the :func:`summary` scalars (SI) and ``inputs``.
    """
    import h5py

    from ssw.h5io import check_kind, read_inputs

    with h5py.File(path, "r") as f:
        check_kind(f, KIND)
        out = {name: f[name][()] for name in DATASETS}
        for k in ("first_yield_force", "first_yield_delta", "residual_indentation",
                  "interface_residual_indentation", "plate_thinning", "dissipated_work",
                  "external_work", "stored_energy", "force_max"):
            v = float(f.attrs.get(k, np.nan))
            out[k] = None if np.isnan(v) else v
        out["inputs"] = read_inputs(f)
    return out


def loading_curve(curve: PlasticCurve, inputs: dict[str, Any]) -> Any:
    """The loading branch of a plastic path as a :class:`ssw.curve.ForceCurve` (what a
    study's contact job writes for a scene with a ``soil_model``; the unloading branch is
    in the plastic curve file, :func:`write_plastic_curve`).

    Parameters
    ----------
    curve : PlasticCurve
        The path.
    inputs : dict
        The scene's inputs (the curve's metadata, with its :func:`summary`).

    Returns
    -------
    ssw.curve.ForceCurve
        Indentation (m), force (N) and contact radius (m) of the loading branch.
    """
    from ssw.curve import ForceCurve

    m = curve.branch == 0
    return ForceCurve(curve.delta[m], curve.force[m], curve.contact_radius[m],
                      {**inputs, **summary(curve)}, dict(curve.stats))


def scene_path(scene: Any, contact_cfg: dict[str, Any], indenter_radius: float,
               plate: tuple[float, float] | None, unload: bool = False, mesh: str = "path"
               ) -> tuple[PlasticCurve, dict[str, Any]]:
    """The plastic path of a scene with a ``soil_model`` or a ``plate_model``, and its
    inputs: :func:`solve_plastic_scene` on the contact config's domain and increments (a
    finite block's settings already applied, :meth:`ssw.sample.Sample.contact_settings`).

    Parameters
    ----------
    scene : ssw.config.Scene
        The scene (its sample's model, None: elastic; its plate's model, None: elastic).
    contact_cfg : dict
        The config's ``contact`` section.
    indenter_radius : float
        The sphere's radius, m.
    plate : tuple of float or None
        The scene's plate ``(E Pa, nu)`` (:func:`ssw.contact.scene.scene_plate`).
    unload : bool
        Lift the sphere back until it leaves the surface.
    mesh : str
        ``path`` | ``study`` (:func:`solve_plastic_scene`).

    Returns
    -------
    tuple
        The :class:`PlasticCurve` and its inputs (dict).
    """
    from ssw.contact.scene import settings_of

    plate_key = scene.plate_material if scene.plate_thickness > 0 else "none"
    plate_model = getattr(scene, "plate_model", None)
    curve = solve_plastic_scene((scene.soil_E, scene.soil_nu), scene.soil_model,
                                indenter_radius, contact_cfg, unload=unload, plate=plate,
                                plate_thickness=scene.plate_thickness,
                                plate_model=plate_model, mesh=mesh)
    inputs = {"soil_E": scene.soil_E, "soil_nu": scene.soil_nu, "plate_material": plate_key,
              "plate_E": plate[0] if plate else None, "plate_nu": plate[1] if plate else None,
              "plate_thickness": float(scene.plate_thickness),
              "indenter_radius": indenter_radius,
              "soil_model": (scene.soil_model.params() if scene.soil_model is not None
                             else {"model": "linear-elastic"}),
              "plate_model": plate_model.params() if plate_model is not None else None,
              "plastic_mesh": mesh, "scene_id": scene.scene_id, **settings_of(contact_cfg)}
    if mesh == "path":
        inputs["plastic_mesh_size_contact"] = float(curve.stats["mesh_size_contact"])
    return curve, inputs


def scene_curve(scene: Any, contact_cfg: dict[str, Any], indenter_radius: float,
                plate: tuple[float, float] | None) -> Any:
    """A study scene with a ``soil_model``: its loading curve (:func:`loading_curve`) of
    :func:`scene_path`.

    Parameters
    ----------
    scene : ssw.config.Scene
        The scene.
    contact_cfg : dict
        The config's ``contact`` section.
    indenter_radius : float
        The sphere's radius, m.
    plate : tuple of float or None
        The scene's plate ``(E Pa, nu)``.

    Returns
    -------
    ssw.curve.ForceCurve
        The loading branch (:func:`loading_curve`).
    """
    return loading_curve(*scene_path(scene, contact_cfg, indenter_radius, plate))

