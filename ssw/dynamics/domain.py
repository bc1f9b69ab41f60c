"""Domain and element sizes of the dynamic FEM from the soil's wave speeds.

Two lengths set the dynamic mesh of :func:`ssw.contact.mesh.build_mesh` (its family: sizes
graded from the contact point, ``h(d) = clip(growth d, size_contact, size_max)``):

* the **domain** radius = depth ``L``: nothing the boundary reflects may come back to the
  contact inside the window ``T_w`` that decides the TOF (from the first wall motion to
  the end of the run), so ``L >= c_p T_w / 2`` (a P wave's round trip, ``c_p`` capped for
  nearly incompressible soils as the boundary's, :attr:`ssw.dynamics.system.Material.c_p_boundary`;
  the boundary's
  dashpots absorb most of it anyway), clipped to ``[L_min, L_max]``: at least
  :data:`MIN_PLATE_RADII` plate radii (the static springs of the absorbing boundary then
  see a far field) and at most ``L_max`` (1 m, the quasi-static FEM's sample: a soil that
  fast is quasi-static at the contact's time scale);
* the **largest element** ``size_max = c_s / (f_max n_w)``: ``n_w`` (:data:`WAVE_ELEMENTS`)
  quadratic elements per shear wavelength at the highest frequency ``f_max`` of the last
  contact's force (:data:`F_MAX`, measured by ``ssw bench dynamic``), the slowest wave
  (Rayleigh waves are slower still by ~8 %: the margin of ``n_w``).

The number of elements is then about ``(L / size_max)^2 ~ (c_p T_w f_max n_w / (2 c_s))^2``:
independent of the soil's modulus and density, so every scene costs about the same.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.contact.mesh import MeshSettings
from ssw.dynamics.system import Material
from ssw.errors import ConfigError

#: Highest frequency (Hz) of the last contact's force that the mesh resolves.
F_MAX = 10.0e3
#: Quadratic elements per shear wavelength at F_MAX.
WAVE_ELEMENTS = 4.0
#: Smallest domain, in plate radii (and at least MIN_DOMAIN m).
MIN_PLATE_RADII = 4.0
MIN_DOMAIN = 0.05
#: Largest domain (m): the quasi-static FEM's soil sample.
MAX_DOMAIN = 1.0
#: Element size at the contact point (m) and growth rate of the graded mesh.
SIZE_CONTACT = 10.0e-6
GROWTH = 0.1
#: Elements through the plate, at least.
PLATE_LAYERS = 4


@dataclass(frozen=True)
class DomainSpec:
    """How to size the dynamic domain (module docstring). SI units.

    Parameters
    ----------
    window : float
        Time the contact's response must be free of reflections (s).
    f_max : float
        Highest frequency the mesh resolves (Hz).
    wave_elements : float
        Elements per shear wavelength at ``f_max``.
    size_contact : float
        Element size under the contact (m).
    growth : float
        Element size growth rate away from the contact.
    plate_layers : int
        Element layers through the plate.
    min_domain : float
        Smallest domain radius = depth (m).
    max_domain : float
        Largest domain radius = depth (m).
    domain : float or None
        A fixed domain radius = depth (m) instead of the wave-speed rule; None: the rule.
    size_max : float or None
        A fixed largest element (m) instead of the wave rule; None: the rule.
    """

    window: float  # s, the time the contact's response must be free of reflections
    f_max: float = F_MAX  # Hz
    wave_elements: float = WAVE_ELEMENTS
    size_contact: float = SIZE_CONTACT  # m
    growth: float = GROWTH
    plate_layers: int = PLATE_LAYERS
    min_domain: float = MIN_DOMAIN  # m
    max_domain: float = MAX_DOMAIN  # m
    domain: float | None = None  # m: a fixed domain instead of the wave-speed rule
    size_max: float | None = None  # m: a fixed largest element instead of the wave rule

    def __post_init__(self) -> None:
        for name in ("window", "f_max", "wave_elements", "size_contact", "growth",
                     "min_domain", "max_domain"):
            if not getattr(self, name) > 0:
                raise ConfigError(f"dynamics.{name}", getattr(self, name), "a value > 0")
        for name in ("domain", "size_max"):
            if getattr(self, name) is not None and not getattr(self, name) > 0:
                raise ConfigError(f"dynamics.{name}", getattr(self, name), "a length > 0 m or null")


def domain_size(soil: Material, plate_radius: float, spec: DomainSpec) -> float:
    """Radius = depth (m) of the dynamic domain (module docstring).

    Parameters
    ----------
    soil : Material
        The soil (Pa, -, kg/m^3).
    plate_radius : float
        Plate radius (m).
    spec : DomainSpec
        The domain sizing.

    Returns
    -------
    float
        Radius = depth of the domain (m).
    """
    if spec.domain is not None:
        return float(spec.domain)
    lo = max(spec.min_domain, MIN_PLATE_RADII * plate_radius)
    reach = 0.5 * soil.c_p_boundary * spec.window
    return float(np.clip(reach, lo, max(lo, spec.max_domain)))


def mesh_settings(soil: Material, plate_radius: float, spec: DomainSpec) -> MeshSettings:
    """Mesh settings of :func:`ssw.contact.mesh.build_mesh` for the dynamic scene.

    Parameters
    ----------
    soil : Material
        The soil (Pa, -, kg/m^3).
    plate_radius : float
        Plate radius (m).
    spec : DomainSpec
        The domain sizing.

    Returns
    -------
    MeshSettings
        The mesh settings (m).
    """
    L = domain_size(soil, plate_radius, spec)
    h_wave = soil.c_s / (spec.f_max * spec.wave_elements)
    size_max = float(min(h_wave, L / 4.0)) if spec.size_max is None else spec.size_max
    return MeshSettings(soil_radius=L, soil_depth=L, size_contact=spec.size_contact,
                        growth=spec.growth, size_max=max(size_max, spec.size_contact),
                        plate_layers=spec.plate_layers)
