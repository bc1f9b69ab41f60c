"""Meshes of the elasto-plastic contact (:mod:`ssw.contact.plastic`), all built by the one
mesh builder :func:`ssw.contact.mesh.build_mesh`: a mesh scaled to the contact radius (the
plastic wall's tables), the contact radius a stiff plate gives the sphere, the near zone
a path's Newton iterations see (the far field beyond it condensed), and the mesh settings
of a study's plastic path: its plastic part's and its elastic part's (refined where
Hertz's field first yields, :func:`hertz_yield_point`).

References
----------
Johnson, K. L. (1985). *Contact Mechanics*. Cambridge, sec. 4.2.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.contact.assembly import element_sizes
from ssw.contact.mesh import Mesh


def contact_mesh(radius: float, d_max: float, *, fine: float = 8.0, growth: float = 0.3,
                 domain: float = 40.0, plate_thickness: float = 0.0,
                 plate_radius: float = 0.0, contact_radius: float | None = None) -> Mesh:
    """A mesh scaled to the contact: the plastic wall's tables and ``ssw bench contact
    --plastic`` (the elastic engine's meshes are graded for indentations down to 1e-9 m,
    far finer at the contact point than a plastic path needs).

    Parameters
    ----------
    radius : float
        The sphere's radius ``R``, m.
    d_max : float
        The largest indentation, m: the Hertz contact radius ``a = sqrt(R d_max)`` sets the
        domain (``domain x a``).
    fine : float
        The element at the contact point is ``a_c / fine``.
    growth : float
        Element size over the distance from the contact point beyond it.
    domain : float
        Domain size over ``a`` (a plate's: 4 plate radii at least).
    plate_thickness : float
        The plate's thickness, m (0: none; a plate has 2 element layers at least).
    plate_radius : float
        The plate's radius, m.
    contact_radius : float or None
        The contact radius ``a_c`` to resolve, m (default ``a``; on a stiff plate the
        sphere's own contact is smaller: :func:`plate_contact_radius`).

    Returns
    -------
    Mesh
        The mesh (:func:`ssw.contact.mesh.build_mesh`).
    """
    from ssw.contact.mesh import MeshSettings, build_mesh

    a = float(np.sqrt(radius * d_max))
    a_c = a if contact_radius is None else min(a, float(contact_radius))
    t, rp = float(plate_thickness), float(plate_radius)
    if t <= 0:
        return build_mesh(0.0, 0.0, MeshSettings(domain * a, domain * a, a_c / fine, growth,
                                                 8.0 * a, 1))
    dom = max(domain * a, 4.0 * rp)
    return build_mesh(t, rp, MeshSettings(dom, dom, min(a_c / fine, t / 2), growth,
                                          max(8.0 * a, 0.05 * dom), 2))


def plate_contact_radius(radius: float, d_max: float, soil: tuple[float, float],
                         plate: tuple[float, float]) -> float:
    """The sphere's contact radius on a plate stiffer than its sample, m: Hertz's on the
    plate's material at the force Hertz gives on the sample at ``d_max``,
    ``a_p = sqrt(R d_max) (E*_s / E*_p)^(1/3)`` (``F = 4/3 E*_s sqrt(R) d^1.5`` and
    ``a^3 = 3 F R / (4 E*_p)``; Johnson 1985, sec. 4.2), ``sqrt(R d_max)`` when the plate
    is the softer. A plate spreads the load, so the force is larger and the estimate a lower
    bound: a mesh that resolves it resolves the contact.

    Parameters
    ----------
    radius : float
        The sphere's radius ``R``, m.
    d_max : float
        The largest indentation, m.
    soil : tuple of float
        The sample's ``(E Pa, nu)``.
    plate : tuple of float
        The plate's ``(E Pa, nu)``.

    Returns
    -------
    float
        The contact radius, m.
    """
    es = soil[0] / (1.0 - soil[1] ** 2)
    ep = plate[0] / (1.0 - plate[1] ** 2)
    return float(np.sqrt(radius * d_max) * min(1.0, es / ep) ** (1.0 / 3.0))


#: Near zone of a condensed path: this many times the larger of ``sqrt(2 R delta)`` at the
#: last indentation (the sphere's section at the depth delta below the flat surface: the
#: contact radius of a plastic indentation without pile-up; Hertz's is ``sqrt(R delta)``)
#: and the plate's spreading length, plus the size of the mesh's elements there (the ring
#: of elements that meets the far field then lies beyond). The plastic zone is checked
#: against its edge (the path is solved again with a zone twice as large when it reaches
#: it, ``stats['near_restarts']``). A von Mises half-space yields to 0.81 (E/Y 20) and
#: 0.87 (E/Y 100) times ``sqrt(2 R delta)`` below the surface; a larger zone only costs
#: time (1.5 took 1.6 times as long on the study's curve; the condensation is exact).
NEAR = 1.0

def near_radius(mesh: Mesh, E: float, nu: float, radius: float, d_end: float,
                punch: str | None = None, plate: tuple[float, float] | None = None) -> float:
    """The near zone's radius (m) of a path to ``d_end`` (m): ``NEAR`` times the larger
    of ``sqrt(2 R d_end)`` (``R`` the sphere's ``radius``; a punch: its radius) and, with a
    plate, the length over which it spreads a load on the sample, ``(2 D (1 - nu^2) /
    E)^(1/3)``, ``D = E_p t^3 / (12 (1 - nu_p^2))`` (a plate on an elastic half-space),
    plus the largest element size of the mesh about that distance from the contact point.

    Parameters
    ----------
    mesh : Mesh
        The mesh (its plate's thickness).
    E : float
        The sample's Young's modulus, Pa.
    nu : float
        The sample's Poisson's ratio.
    radius : float
        The sphere's (or punch's) radius, m.
    d_end : float
        The path's largest indentation, m.
    punch : str or None
        A flat punch (``smooth`` | ``rough``), or None: the sphere.
    plate : tuple of float or None
        The plate's ``(E Pa, nu)``.

    Returns
    -------
    float
        The radius, m.
    """
    a = float(radius) if punch is not None else float(np.sqrt(2.0 * radius * d_end))
    t = float(mesh.top)
    if plate is not None and t > 0:
        D = plate[0] * t**3 / (12.0 * (1.0 - plate[1] ** 2))
        a = max(a, (2.0 * D * (1.0 - nu * nu) / E) ** (1.0 / 3.0))
    r = NEAR * a
    # the ring of elements that meets the far field lies beyond r: one element size more
    xy = mesh.nodes[mesh.tri[:, :3]].mean(axis=1)
    dist = np.hypot(xy[:, 0], xy[:, 1] - t)
    h = element_sizes(mesh.nodes, mesh.tri)[(dist > 0.8 * r) & (dist < 1.25 * r)]
    return r + (float(np.max(h)) if h.size else 0.0)


#: The mesh of a plastic path (``mesh="path"``) resolves the contact radii from that of
#: this share of the path's last indentation on: its element at the contact point is
#: ``mesh_growth sqrt(R share delta_end)`` (at least the config's ``mesh_size_contact``);
#: the error this costs against a converged mesh is stated in ssw/bench/plastic.py.
PATH_RESOLVED = 1.0
#: The elastic part's mesh of a plastic path (:func:`elastic_mesh_settings`): element size
#: over the distance from the contact point, from the study's element there to the plastic
#: mesh's (every contact radius of the elastic part resolved by about 1 / 0.15 elements;
#: the errors this leaves on the study's plastic scene: docs/physics/plastic.md).
ELASTIC_GROWTH = 0.15
#: The spots about the estimated first-yield point and the contact's edge then
#: (:func:`hertz_yield_point`): element ``a_y / SPOT_FINE`` within ``SPOT_RADIUS a_y`` of
#: each, growing by ``SPOT_GROWTH`` of the distance beyond (``a_y`` Hertz's contact radius
#: there).
SPOT_FINE = 20.0
SPOT_RADIUS = 0.1
SPOT_GROWTH = 0.3


def path_mesh_settings(settings: Any, radius: float, d_end: float,
                       plate_thickness: float = 0.0, contact_radius: float | None = None
                       ) -> Any:
    """The mesh settings of a plastic path: the study's (domain, boundaries, growth,
    largest element, plate layers) with the element at the contact point scaled to the
    path (``PATH_RESOLVED``; at most a plate layer).

    Parameters
    ----------
    settings : ssw.contact.mesh.MeshSettings
        The study's mesh settings (:func:`ssw.contact.mesh.mesh_settings`).
    radius : float
        The sphere's radius, m.
    d_end : float
        The path's largest indentation, m.
    plate_thickness : float
        The plate's thickness, m (0: none).
    contact_radius : float or None
        A smaller contact radius at ``d_end`` to resolve, m (a yielding plate's own,
        :func:`plate_contact_radius`).

    Returns
    -------
    ssw.contact.mesh.MeshSettings
        The settings with ``size_contact`` replaced.
    """
    from dataclasses import replace

    a = float(np.sqrt(radius * d_end))
    if contact_radius is not None:
        a = min(a, float(contact_radius))
    h = settings.growth * a * float(np.sqrt(PATH_RESOLVED))
    if plate_thickness > 0:
        h = min(h, plate_thickness / settings.plate_layers)
    return replace(settings, size_contact=max(settings.size_contact, h))


def hertz_yield_point(model: Any, E: float, nu: float, radius: float
                      ) -> tuple[float, float] | None:
    """Where and when a model first yields in Hertz's field on the axis under a rigid
    sphere: the indentation (m) and the depth below the surface (m) of the largest yield
    ratio of the axis stresses (Johnson 1985, sec. 6.1)

        ``sigma_z = -p0 / (1 + zeta^2)``,
        ``sigma_r = sigma_t = -p0 [(1 + nu) (1 - zeta atan(1 / zeta)) - 1 / (2 (1 + zeta^2))]``,

    ``zeta = z / a``, at the peak pressure ``p0`` where it reaches 1 (the ratio is
    proportional to ``p0`` for every model of :mod:`ssw.constitutive` at its virgin state),
    ``a = pi p0 R / (2 E*)``, ``delta = a^2 / R``. For von Mises it is Johnson's first
    yield (``p0 = 1.61 Y`` at ``0.48 a`` for nu 0.3). None when the model does not yield
    (elastic) or yields at any pressure (a cohesionless cone).

    Parameters
    ----------
    model : model of :mod:`ssw.constitutive`
        The sample's law.
    E : float
        The sample's Young's modulus, Pa.
    nu : float
        The sample's Poisson's ratio.
    radius : float
        The sphere's radius ``R``, m.

    Returns
    -------
    tuple of float or None
        ``(delta_y, depth_y)``, m.

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*. Cambridge, eq. 3.45 and sec. 6.1.
    """
    from ssw.constitutive.base import initial_state

    zeta = np.linspace(1e-4, 3.0, 3001)
    sz = -1.0 / (1.0 + zeta * zeta)
    sr = -((1.0 + nu) * (1.0 - zeta * np.arctan(1.0 / zeta)) - 0.5 / (1.0 + zeta * zeta))
    p_ref = float(getattr(model, "strength", np.inf))
    p_ref = p_ref if np.isfinite(p_ref) and p_ref > 0 else 1e6
    stress = p_ref * np.stack([sr, sz, sr, np.zeros_like(sr)], axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.asarray(model.yield_ratio(stress, initial_state(zeta.size)), float)
    if not np.all(np.isfinite(ratio)) or not np.max(ratio) > 0:
        return None
    i = int(np.argmax(ratio))
    p0 = p_ref / float(ratio[i])
    a = np.pi * p0 * radius / (2.0 * E / (1.0 - nu * nu))
    return float(a * a / radius), float(zeta[i] * a)


def elastic_mesh_settings(settings: Any, plateau: float,
                          yield_point: tuple[float, float] | None = None,
                          growth: float = ELASTIC_GROWTH, radius: float = 0.0) -> Any:
    """The mesh settings of a plastic path's elastic part (the loading increments before
    first yield, :func:`ssw.contact.plastic_path.solve_path`'s ``elastic_mesh``): the
    plastic path's mesh (the study's settings with the element ``plateau`` at the contact
    point, :func:`path_mesh_settings`) graded finer towards the contact point, ``h =
    growth d`` from the study's element at the contact point (the elastic engine's: it
    resolves the contact radii from ``size_contact / growth`` on; so the elastic part's
    mesh, like the engine's, does not depend on the increments) up to ``plateau``, and
    refined in spots about the first-yield point and the contact's edge then
    (``SPOT_FINE``: the plastic zone starts there, and the stresses there set the
    first yield).

    Parameters
    ----------
    settings : ssw.contact.mesh.MeshSettings
        The study's mesh settings (:func:`ssw.contact.mesh.mesh_settings`).
    plateau : float
        The plastic path's element at the contact point, m (:func:`path_mesh_settings`).
    yield_point : tuple of float or None
        ``(delta_y, depth_y)`` (m) of the estimated first yield
        (:func:`hertz_yield_point`); None: no spots.
    growth : float
        Element size over the distance from the contact point (default
        ``ELASTIC_GROWTH``).
    radius : float
        The sphere's radius ``R``, m (the contact radius at first yield ``sqrt(R
        delta_y)`` sizes the spots; needed with ``yield_point``).

    Returns
    -------
    ssw.contact.mesh.MeshSettings
        The settings with the finer grading (and the spots).

    Raises
    ------
    ConfigError
        A ``yield_point`` without the sphere's ``radius``.
    """
    from dataclasses import replace

    from ssw.errors import ConfigError

    g = float(growth)
    out = replace(settings, size_contact=min(float(settings.size_contact), plateau),
                  near_size=float(plateau), near_growth=g)
    if yield_point is not None:
        if not radius > 0:
            raise ConfigError("radius", radius, "the sphere's radius > 0 m with a yield point")
        a_y = float(np.sqrt(radius * yield_point[0]))
        out = replace(out, spot_size=a_y / SPOT_FINE,
                      spot_points=((0.0, float(yield_point[1])), (a_y, 0.0)),
                      spot_radius=SPOT_RADIUS * a_y, spot_growth=SPOT_GROWTH)
    return out
