"""The layered oracle: a rigid sphere on an infinite plate over an elastic soil, semi-analytic.

``ssw contact --engine layered``. An independent check of the FEM (:mod:`ssw.contact.scene`),
sharing none of its code (only :mod:`ssw.hertz` in the tests and the curve format
:mod:`ssw.curve`): the plate is an elastic layer (E1, nu1, thickness h) of infinite extent
bonded to, or resting frictionless on, an elastic half-space (E2, nu2) -- Burmister's
problem -- or, with ``soil_depth``, a soil layer on a rigid base (the FEM's fixed bottom).

1. Kernel (:mod:`.layered_kernel`): the Hankel transform of the surface deflection under
   axisymmetric pressure, from Love's strain function in each body and the exponentially
   scaled transfer system of the interfaces; ``A(xi) -> 1`` as ``xi h -> inf``.
2. Ring influence coefficients (:mod:`.layered_rings`): annuli of uniform pressure; the
   plate material's half-space part in closed form (complete elliptic integrals, Love
   1929), the rest, ``(A - 1)``, decaying like ``e^(-2 xi h)``, by Gauss-Legendre panels.
3. Contact (:mod:`.layered_lcp`): ring pressures ``p >= 0``, gaps to the exact sphere
   ``r^2 / (R + sqrt(R^2 - r^2)) - delta + u_z >= 0``, complementary: the discrete LCP
   solved exactly (active sets, each valid over a range of ``delta``).

Rings are ``ring_ratio r`` wide (uniform ``ring_ratio a_min`` near the axis), so every
contact radius above ``a_min`` is resolved alike; collocation at the ring midpoints.

Convergence (``ssw bench layered``; rigid sphere R = 9.53 mm, 1000 increments to 0.1 mm,
forces compared for delta >= 1 um):

* no plate vs Sneddon's exact sphere (:func:`ssw.hertz.sneddon_sphere`): max relative
  force error 1.8e-3 (ring_ratio 1/10), 4.7e-4 (1/20), 1.2e-4 (1/40, default), 2.9e-5
  (1/80): order 2.0, ``~0.19 ring_ratio^2``;
* 0.4 mm PLA / aluminium / steel plates on 10-1000 MPa, both interfaces: the change from
  1/40 to 1/80 is <= 1.0e-4 (Richardson: error at 1/40 <= 1.4e-4);
* Hankel quadrature: the default differs from one with ~30x the nodes (order 32, half-width
  panels, t_max 30) by <= 2e-12;
* the same error holds from the first increment (0.1 um) and on to 0.6 mm (a/R = 0.25).

So the oracle's stated relative force error at the defaults, ``LayeredSettings().
force_error``, is 2e-4 (``ERROR_COEFF ring_ratio^2``). The contact radius (from the gap,
``g^(2/3)`` extrapolated to zero) converges to first order: 0.4 % at the default.

Against the FEM (``ssw bench layered --parts compare``, tests/test_layered_fem.py): with a
0.4 m wide plate on the FEM's 1 m soil (modelled here by ``soil_depth = 1``) the FEM's
curves lie within 6.7e-4 of the oracle's for PLA / Al / steel 0.4 mm plates on 10-1000 MPa,
both interfaces; the study's 49.5 mm plate is softer by its finite diameter, up to 2.2 %
(steel on 10 MPa).

Speed (``--parts speed``, 1000 increments, one BLAS thread, 2 cores shared with other
jobs): 0.03-0.08 s a curve (0.015-0.03 s at ring_ratio 1/20, still 5e-4 accurate). The
FEM takes 0.5-1.0 s when it builds its condensed operators (a new plate geometry or
Poisson's ratio: 7-17x the oracle's time) and 2-40 ms once they are cached (one more soil
modulus under the same plate): the oracle's cost is all per scene (its kernel depends on
the modulus ratio), so it is the faster only for scenes the FEM has not seen.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from ssw.contact.layered_kernel import INTERFACES, Stack, plate_on_soil
from ssw.contact.layered_lcp import ZoneError, solve_sphere
from ssw.contact.layered_rings import Quadrature, graded_edges, influence_matrix
from ssw.curve import ForceCurve
from ssw.errors import ConfigError

ENGINE = "layered"
#: Relative force error per ring_ratio^2 (bench: 0.19 with no plate, less with plates),
#: rounded up: the stated error is ERROR_COEFF * ring_ratio^2.
ERROR_COEFF = 0.32
#: Growth of the candidate zone when the contact reaches its edge, and the tries.
ZONE_GROWTH = 1.4
ZONE_TRIES = 4
#: Contact settings the layered engine reads (the FEM's mesh settings do not apply).
CONTACT_KEYS = ("delta_max", "steps", "delta_reach", "delta_mode", "interface",
                "pressure_profiles")


@dataclass(frozen=True)
class LayeredSettings:
    """Numerics of the oracle.

    ``ring_ratio``: ring width / radius in the graded zone (error ``~0.19 ratio^2``);
    ``ring_min``: smallest contact radius resolved at that ratio, relative to
    ``sqrt(R delta_1)`` of the first increment (contacts on plates are 0.18-0.6 of it);
    ``candidate_factor``: ring zone radius / ``sqrt(R delta_last)``; ``soil_depth``: None
    for a half-space soil, or a depth (m) over a rigid base, ``soil_base`` ``bonded``
    (``u = 0``) or ``sliding`` (frictionless: ``u_z = 0``, no shear); ``quadrature``: the
    Hankel quadrature.

    Parameters
    ----------
    ring_ratio : float
        Ring width / radius in the graded zone.
    ring_min : float
        Smallest contact radius resolved at that ratio, relative to ``sqrt(R delta_1)``.
    candidate_factor : float
        Ring zone radius / ``sqrt(R delta_last)``.
    soil_depth : float or None
        Depth of the soil layer (m); None: a half-space.
    soil_base : str
        Below the layer: ``bonded``, ``sliding`` or ``elastic``.
    base_E : float or None
        Young's modulus of an elastic base (Pa).
    base_nu : float or None
        Poisson's ratio of an elastic base.
    quadrature : Quadrature
        The Hankel quadrature.
    """

    ring_ratio: float = 1.0 / 40.0
    ring_min: float = 0.1
    candidate_factor: float = 1.5
    soil_depth: float | None = None
    soil_base: str = "bonded"
    base_E: float | None = None  # Pa, soil_base elastic: the subgrade under the soil layer
    base_nu: float | None = None
    quadrature: Quadrature = field(default_factory=Quadrature)

    def __post_init__(self) -> None:
        if not 0 < self.ring_ratio <= 0.5:
            raise ConfigError("layered.ring_ratio", self.ring_ratio, "a ratio in (0, 0.5]")
        if not 0 < self.ring_min <= 1:
            raise ConfigError("layered.ring_min", self.ring_min, "a fraction in (0, 1]")
        if not self.candidate_factor > 1:
            raise ConfigError("layered.candidate_factor", self.candidate_factor, "> 1")
        if self.soil_depth is not None and not self.soil_depth > 0:
            raise ConfigError("layered.soil_depth", self.soil_depth, "None or a depth > 0 m")
        if self.soil_base not in ("bonded", "sliding", "elastic"):
            raise ConfigError("layered.soil_base", self.soil_base, "bonded | sliding | elastic")
        if self.soil_base == "elastic" and not (
                self.base_E is not None and self.base_E > 0 and self.base_nu is not None):
            raise ConfigError("layered.base_E", self.base_E,
                              "the subgrade's E > 0 Pa and Poisson's ratio (soil_base elastic)")

    @property
    def force_error(self) -> float:
        """Stated relative force error of the discretization (``ERROR_COEFF ratio^2``)."""
        return ERROR_COEFF * self.ring_ratio**2

    @classmethod
    def from_config(cls, values: dict[str, Any] | None) -> LayeredSettings:
        """Settings from a dict (e.g. ``contact.layered``); quadrature keys under ``quadrature``.

        Parameters
        ----------
        values : dict or None
            The settings (SI); None: the defaults.

        Returns
        -------
        LayeredSettings
            The settings.

        Raises
        ------
        ConfigError
            If a key is unknown.
        """
        values = dict(values or {})
        quad = values.pop("quadrature", None)
        unknown = set(values) - {f for f in cls.__dataclass_fields__ if f != "quadrature"}
        if unknown:
            raise ConfigError("contact.layered", sorted(unknown),
                              "ring_ratio, ring_min, candidate_factor, soil_depth, soil_base, "
                              "base_E, base_nu, quadrature")
        return cls(**values, quadrature=Quadrature(**(quad or {})))


def increments(delta_max: float, steps: int, delta_reach: float | None = None) -> np.ndarray:
    """Indentations (m): ``steps`` equal increments to ``delta_max`` and, when
    ``delta_reach`` is deeper, ``steps`` more to it (the contact contract of
    docs/CONTRACTS.md, ``contact.delta_mode``).

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

    Raises
    ------
    ConfigError
        If ``delta_max <= 0`` or ``steps < 1``.
    """
    if not (delta_max > 0 and int(steps) >= 1):
        raise ConfigError("contact.delta_max/steps", (delta_max, steps), "> 0 m and >= 1")
    d = delta_max * np.arange(1, int(steps) + 1) / int(steps)
    if delta_reach is not None and float(delta_reach) > delta_max * (1 + 1e-12):
        extra = np.arange(1, int(steps) + 1) / int(steps)
        d = np.concatenate([d, delta_max + (float(delta_reach) - delta_max) * extra])
    return d


def solve_stack(stack: Stack, radius: float, deltas: np.ndarray,
                settings: LayeredSettings | None = None,
                profiles: int = 0) -> tuple[ForceCurve, dict[str, Any]]:
    """Force-indentation curve of a rigid sphere (radius m) on a layered body.

    Returns the curve (stats filled, inputs empty) and the influence matrix, rings and
    LCP result (for tests and benchmarks).

    Parameters
    ----------
    stack : Stack
        The layered body (Pa, -, m).
    radius : float
        Sphere radius (m), > 0.
    deltas : numpy.ndarray
        Indentations (m), increasing.
    settings : LayeredSettings or None
        The settings; None: the defaults.
    profiles : int
        Number of pressure profiles to keep.

    Returns
    -------
    curve : ForceCurve
        The curve (N, m).
    details : dict
        Influence matrix (m/Pa), ring edges and points (m), areas (m^2), LCP result.

    Raises
    ------
    ConfigError
        If the radius is not > 0 or the candidate zone reaches the sphere's radius.
    """
    settings = settings or LayeredSettings()
    if not radius > 0:
        raise ConfigError("indenter_radius", radius, "a radius > 0 m")
    deltas = np.asarray(deltas, float)
    t0 = time.perf_counter()
    for attempt in range(ZONE_TRIES):  # a soft plate on a stiff soil widens the contact
        factor = settings.candidate_factor * ZONE_GROWTH**attempt
        r_max = factor * np.sqrt(radius * deltas[-1])
        if r_max >= radius:
            raise ConfigError("delta_max", float(deltas[-1]),
                              "an indentation whose candidate zone lies inside the sphere")
        try:
            t1, t2, rings = _solve_rings(stack, radius, deltas, settings, r_max, profiles)
            break
        except ZoneError:
            if attempt == ZONE_TRIES - 1:
                raise
    C, n_xi, edges, points, areas, keep, res = rings
    t3 = time.perf_counter()
    stats = {
        "engine": ENGINE, "rings": len(points), "dofs": len(points),
        "candidates": len(points), "xi_nodes": n_xi, "active_sets": res.active_sets,
        "lcp_iterations": res.iterations, "general_solves": res.general_solves,
        "max_active_ring": res.max_ring, "candidate_factor": factor,
        "force_error": settings.force_error,
        "wall_rings": t1 - t0, "wall_influence": t2 - t1, "wall_lcp": t3 - t2,
        "wall_total": t3 - t0,
    }
    pressure = None
    if keep.size:
        pressure = {"r": points, "delta": deltas[keep],
                    "p": np.array([res.profiles[int(k)] for k in keep])}
    curve = ForceCurve(deltas, res.force, res.contact_radius, {}, stats, pressure)
    return curve, {"C": C, "edges": edges, "points": points, "areas": areas, "lcp": res}


def _solve_rings(stack: Stack, radius: float, deltas: np.ndarray, settings: LayeredSettings,
                 r_max: float, profiles: int) -> tuple[float, float, tuple]:
    """Rings to ``r_max``, their influence matrix and the LCP; the times after the rings
    and after the matrix (s)."""
    rho = settings.ring_ratio
    a_min = min(settings.ring_min * np.sqrt(radius * deltas[0]), 0.5 * r_max)
    edges = graded_edges(r_max, rho, rho * a_min)
    points = 0.5 * (edges[1:] + edges[:-1])
    areas = np.pi * np.diff(edges**2)
    t1 = time.perf_counter()
    C, n_xi = influence_matrix(stack, points, edges, settings.quadrature)
    t2 = time.perf_counter()
    keep = np.unique(np.linspace(0, deltas.size - 1, profiles).round().astype(int)) \
        if profiles > 0 else np.zeros(0, int)
    res = solve_sphere(C, points, areas, radius, deltas, keep)
    return t1, t2, (C, n_xi, edges, points, areas, keep, res)


def solve_curve(soil: tuple[float, float], plate: tuple[float, float] | None,
                plate_thickness: float, radius: float, contact_cfg: dict[str, Any],
                settings: LayeredSettings | None = None) -> ForceCurve:
    """Force-indentation curve of a rigid sphere on an infinite plate (or none) on a soil.

    Parameters
    ----------
    soil : tuple of float
        ``(E, nu)`` of the soil, Pa and - (a half-space, or ``settings.soil_depth`` deep).
    plate : tuple of float or None
        ``(E, nu)`` of the plate, Pa and -, or None with ``plate_thickness == 0``.
    plate_thickness : float
        The plate's thickness, m.
    radius : float
        The sphere's radius, m.
    contact_cfg : dict
        The ``contact`` settings: ``delta_max``, ``steps``, ``delta_reach``,
        ``interface`` (bonded | frictionless), ``pressure_profiles``; an optional
        ``layered`` dict gives :class:`LayeredSettings` (unless ``settings`` is given).
    settings : LayeredSettings or None
        The oracle's discretization (rings, Hankel quadrature, soil depth).

    Returns
    -------
    ForceCurve
        The curve (N, m).
    """
    cfg = {"delta_max": 1.0e-4, "steps": 1000, "interface": "frictionless",
           "pressure_profiles": 5, **contact_cfg}
    if cfg["interface"] not in INTERFACES:
        raise ConfigError("contact.interface", cfg["interface"],
                          f"{' | '.join(INTERFACES)} (the layered engine)")
    if settings is None:
        settings = LayeredSettings.from_config(cfg.get("layered"))
    if plate_thickness < 0:
        raise ConfigError("plate_thickness", plate_thickness, "a thickness >= 0 m")
    if plate_thickness > 0 and plate is None:
        raise ConfigError("plate", plate, "(E, nu) of the plate when plate_thickness > 0")
    stack = plate_on_soil(plate, plate_thickness, soil, cfg["interface"], settings.soil_depth,
                          settings.soil_base, settings.base_E, settings.base_nu)
    deltas = increments(float(cfg["delta_max"]), int(cfg["steps"]), cfg.get("delta_reach"))
    curve, _ = solve_stack(stack, radius, deltas, settings, int(cfg["pressure_profiles"]))
    has_plate = plate is not None and plate_thickness > 0
    inputs = {
        **{k: cfg[k] for k in CONTACT_KEYS if k in cfg},
        "engine": ENGINE, "soil_E": float(soil[0]), "soil_nu": float(soil[1]),
        "plate_E": float(plate[0]) if has_plate else None,
        "plate_nu": float(plate[1]) if has_plate else None,
        "plate_thickness": float(plate_thickness) if has_plate else 0.0,
        "plate_diameter": None,  # infinite
        "indenter_radius": float(radius),
        "layered": {**{k: v for k, v in asdict(settings).items() if k != "quadrature"},
                    "quadrature": asdict(settings.quadrature)},
    }
    return ForceCurve(curve.delta, curve.force, curve.contact_radius, inputs, curve.stats,
                      curve.pressure)


def solve_scene(scene: Any, contact_cfg: dict[str, Any], indenter_radius: float,
                materials: dict[str, Any], cache: object = None,
                settings: LayeredSettings | None = None) -> ForceCurve:
    """The curve of one study scene (:class:`ssw.config.Scene`), as the FEM's
    ``solve_scene`` (``cache`` is accepted for the same call and unused).

    Parameters
    ----------
    scene : Scene
        The study scene.
    contact_cfg : dict
        The contact settings.
    indenter_radius : float
        Sphere radius (m).
    materials : dict
        The materials library (SI).
    cache : object
        Unused.
    settings : LayeredSettings or None
        The settings; None: from ``contact_cfg``.

    Returns
    -------
    ForceCurve
        The curve (N, m).

    Raises
    ------
    ConfigError
        If the plate's material is unknown or the sample has a mould.
    """
    plate = None
    key = scene.plate_material if scene.plate_thickness > 0 else "none"
    if scene.plate_thickness > 0:
        if scene.plate_material not in materials:
            raise ConfigError("plate_material", scene.plate_material,
                              f"a material of the library: {', '.join(sorted(materials))}")
        m = materials[scene.plate_material]
        plate = (m.E, m.nu)
    smp = getattr(scene, "sample", None)
    if smp is not None:  # an infinite layer of the sample's thickness on its base
        if smp.lateral == "mould":
            raise ConfigError("sample.lateral", smp.lateral,
                              "free with the layered engine (its layers are infinitely wide)")
        base = settings or LayeredSettings.from_config(contact_cfg.get("layered"))
        settings = replace(base, soil_depth=smp.thickness, soil_base=smp.base,
                           base_E=smp.base_E, base_nu=smp.base_nu)
    curve = solve_curve((scene.soil_E, scene.soil_nu), plate, scene.plate_thickness,
                        indenter_radius, contact_cfg, settings)
    inputs = {**curve.inputs, "plate_material": key, "scene_id": scene.scene_id}
    return ForceCurve(curve.delta, curve.force, curve.contact_radius, inputs, curve.stats,
                      curve.pressure)


def describe(result: dict[str, Any]) -> str:
    """Human summary of an ``ssw contact --engine layered`` result.

    Parameters
    ----------
    result : dict
        The command's result.

    Returns
    -------
    str
        The summary.
    """
    st = result["stats"]
    text = (f"scene {result.get('scene_id', '?')} (layered): F({result['delta'][-1]:.4g} m) = "
            f"{result['force'][-1]:.6g} N, contact radius {result['contact_radius'][-1]:.4g} m\n"
            f"{st['rings']} rings, {st['xi_nodes']} Hankel nodes, {st['active_sets']} active "
            f"sets, {len(result['delta'])} increments, stated force error "
            f"{st['force_error']:.1e}, wall {st['wall_total']:.3f} s (influence "
            f"{st['wall_influence']:.3f}, LCP {st['wall_lcp']:.3f})")
    return text + (f"\nwrote {result['output']}" if result.get("output") else "")
