"""Parameters of the bead chain: a frozen dataclass built from the config's ``chain:`` section.

The chain (REFERENCE.md "The chain"; Nesterenko 2001; Daraio et al. 2006; Yang et al. 2011)
is ``N`` identical steel spheres stacked vertically, counted from the striker (bead 0) to the
bead that rests on the tested medium (bead ``N - 1``). Bead ``sensor_index`` is the sensor
particle: same contact geometry as the others (a sphere of the bead's radius and material),
its own mass (``sensor_mass``), and its signal the mean of its two contact forces. With
``uniform=True`` its mass is the bead's (the Daraio-lab instrumented-bead convention).

Device defaults. The device of Villacreses et al. (2021) is not documented in what we have
(REFERENCE.md [U]); the defaults below are documented choices:

* beads: 3/4 in (19.05 mm) AISI 52100 chrome-steel bearing balls, the size of the thesis's
  indenter (R = 9.53 mm), material ``chrome_steel`` of ``config/materials.yaml``;
* 20 beads, the sensor in the middle (index 10), as in REFERENCE.md's [M] reference chain;
* the striker velocity is the one parameter calibrated, on one foam of the thesis's
  Table 2 (see :mod:`ssw.chain.calibration` and ``config/config.yaml``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ssw.errors import ConfigError
from ssw.hertz import effective_modulus, hertz_coefficient, sphere_sphere_coefficient

#: Standard gravity, m/s^2 (CGPM 1901).
STANDARD_GRAVITY = 9.80665


@dataclass(frozen=True)
class ChainParams:
    """The chain and its numerics. SI units.

    Attributes
    ----------
    n_beads : beads including the striker (bead 0), >= 3.
    bead_radius : m.  bead_density : kg/m^3.  bead_E : Pa.  bead_nu : -.
    sensor_index : 0-based index of the sensor particle, 1 <= index <= n_beads - 2.
    sensor_mass : kg, mass of the sensor particle; ``None``: a bead's mass.
    striker_mass : kg; ``None``: a bead's mass.
    uniform : the sensor particle is a plain bead (its mass is ignored).
    striker_velocity : m/s, the striker's speed when it touches bead 1.
    gravity : precompress the chain by its weight and keep gravity on during the run.
    g : m/s^2.
    damping : N s/m, viscous dashpot in every closed contact (0: conservative, the default).
    plate_material, plate_thickness : the plate under the last bead (metadata of the
        ``fit``/``table`` walls; the thesis's 0.4 mm PLA plate).
    fit_law : ``k_hertz`` (F = K A_w d^1.5) or ``power`` (F = C d^n) for the ``fit`` wall.
    steps_per_contact : time steps per Hertz contact time of two beads at the striker speed.
    t_max : s, longest simulated time (a scene whose reflected wave has not passed the
        sensor by then is an error).
    """

    n_beads: int = 20
    bead_radius: float = 9.525e-3
    bead_density: float = 7810.0
    bead_E: float = 200.0e9
    bead_nu: float = 0.28
    sensor_index: int = 10
    sensor_mass: float | None = None
    striker_mass: float | None = None
    uniform: bool = False
    striker_velocity: float = 0.5247
    gravity: bool = True
    g: float = STANDARD_GRAVITY
    damping: float = 0.0
    plate_material: str = "pla"
    plate_thickness: float = 0.4e-3
    fit_law: str = "k_hertz"
    steps_per_contact: int = 80
    t_max: float = 0.02

    def __post_init__(self) -> None:
        if self.n_beads < 3:
            raise ConfigError("chain.beads", self.n_beads, "at least 3 (striker, sensor, last)")
        if not 1 <= self.sensor_index <= self.n_beads - 2:
            raise ConfigError(
                "chain.sensor_index", self.sensor_index,
                f"an index between 1 and beads - 2 = {self.n_beads - 2}",
            )
        for name in ("bead_radius", "bead_density", "bead_E", "striker_velocity", "t_max"):
            if not getattr(self, name) > 0:
                raise ConfigError(f"chain.{name}", getattr(self, name), "must be > 0")
        for name in ("sensor_mass", "striker_mass"):
            val = getattr(self, name)
            if val is not None and not val > 0:
                raise ConfigError(f"chain.{name}", val, "must be > 0 kg (or null: a bead's)")
        if not -1.0 < self.bead_nu <= 0.5:
            raise ConfigError("chain.bead_nu", self.bead_nu, "must lie in (-1, 0.5]")
        if self.damping < 0:
            raise ConfigError("chain.damping", self.damping, "must be >= 0 N s/m")
        if self.fit_law not in ("k_hertz", "power"):
            raise ConfigError("fit.law", self.fit_law, "k_hertz | power")
        if self.steps_per_contact < 4:
            raise ConfigError("chain.steps_per_contact", self.steps_per_contact, ">= 4")

    # ------------------------------------------------------------------ derived
    @property
    def bead_mass(self) -> float:
        """Mass of one bead, ``4/3 pi R^3 rho`` (kg)."""
        return 4.0 / 3.0 * np.pi * self.bead_radius**3 * self.bead_density

    @property
    def masses(self) -> np.ndarray:
        """Masses of beads 0..N-1 (kg), shape (N,)."""
        m = np.full(self.n_beads, self.bead_mass)
        if self.striker_mass is not None:
            m[0] = self.striker_mass
        if self.sensor_mass is not None and not self.uniform:
            m[self.sensor_index] = self.sensor_mass
        return m

    @property
    def bead_coefficient(self) -> float:
        """Bead-bead Hertz coefficient ``A = E sqrt(2R) / (3 (1 - nu^2))`` (N/m^1.5)."""
        return float(sphere_sphere_coefficient(self.bead_E, self.bead_nu, self.bead_radius))

    @property
    def bead_compliance(self) -> float:
        """``(1 - nu_b^2) / E_b`` (1/Pa), the bead's share of ``1/E*`` at the wall."""
        return (1.0 - self.bead_nu**2) / self.bead_E

    def wall_coefficient(self, soil_E: Any, soil_nu: Any) -> np.ndarray:
        """Hertz bead-on-half-space ``A_w = 4/3 sqrt(R) E*`` (N/m^1.5), broadcast.

        ``1/E* = (1 - nu_b^2)/E_b + (1 - nu_w^2)/E_w`` (REFERENCE.md; Johnson 1985 ch. 4).
        """
        e_star = effective_modulus(self.bead_E, self.bead_nu, soil_E, soil_nu)
        return hertz_coefficient(e_star, self.bead_radius)

    def contact_time(self) -> float:
        """Hertz contact time (s) of two beads meeting at the striker speed (Johnson 11.24)."""
        from ssw.hertz import contact_time

        m = self.masses
        m_eff = m[0] * m[1] / (m[0] + m[1])
        return float(contact_time(m_eff, self.bead_coefficient, self.striker_velocity))

    def with_(self, **changes: Any) -> ChainParams:
        """A copy with ``changes`` (``dataclasses.replace``)."""
        return replace(self, **changes)

    # ------------------------------------------------------------------ config
    @classmethod
    def from_config(cls, cfg: dict[str, Any], **overrides: Any) -> ChainParams:
        """Parameters from a validated config (:func:`ssw.config.load_config`).

        The bead's E, nu and density come from the materials library (``chain.bead_material``);
        ``overrides`` replace any field afterwards.
        """
        from ssw.config import library

        ch = cfg.get("chain", {})
        mats = library(cfg)
        key = ch.get("bead_material", "chrome_steel")
        if key not in mats:
            raise ConfigError("chain.bead_material", key, f"one of {', '.join(sorted(mats))}")
        bead = mats[key]
        fields: dict[str, Any] = {
            "n_beads": ch.get("beads", cls.n_beads),
            "bead_radius": ch.get("bead_radius", cls.bead_radius),
            "bead_density": bead.density,
            "bead_E": bead.E,
            "bead_nu": bead.nu,
            "sensor_index": ch.get("sensor_index", cls.sensor_index),
            "sensor_mass": ch.get("sensor_mass"),
            "striker_mass": ch.get("striker_mass"),
            "uniform": ch.get("uniform", cls.uniform),
            "striker_velocity": ch.get("striker_velocity", cls.striker_velocity),
            "gravity": ch.get("gravity", cls.gravity),
            "damping": ch.get("damping", cls.damping),
            "plate_material": ch.get("plate_material", cls.plate_material),
            "plate_thickness": ch.get("plate_thickness", cls.plate_thickness),
            "fit_law": cfg.get("fit", {}).get("law", cls.fit_law),
            "steps_per_contact": ch.get("steps_per_contact", cls.steps_per_contact),
            "t_max": ch.get("t_max", cls.t_max),
        }
        fields.update(overrides)
        return cls(**fields)
