"""Parameters of the bead chain: a frozen dataclass built from the config's ``chain:`` section.

The chain (REFERENCE.md "The chain"; Nesterenko 2001; Daraio et al. 2006; Yang et al. 2011)
is ``N`` identical steel spheres stacked vertically, counted from the striker (bead 0) to the
bead that rests on the tested medium (bead ``N - 1``). Bead ``sensor_index`` is the sensor
particle: same contact geometry as the others (a sphere of the bead's radius and material),
its own mass (``sensor_mass``), and its signal the mean of its two contact forces. With
``uniform=True`` its mass is the bead's (the Daraio-lab instrumented-bead convention).

The physical values come from a device (:class:`ssw.device.Device`, YAML files in
``config/devices/``; the thesis's device is the default), the numerics (time steps, gravity,
the fit law) from the study config's ``chain:`` section: :meth:`ChainParams.from_config`.
The contacts' dissipation (its law, :mod:`ssw.chain.dissipation`, and coefficient) is the
device's (``dissipation:``); the config's ``chain.damping``, when given (not null), replaces
the coefficient, as a flag replaces a device field (``--damping``, ``--damping-law``). The
dataclass defaults below are those of the thesis device.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ssw.chain.dissipation import DEFAULT_LAW, law_of
from ssw.errors import ConfigError
from ssw.hertz import effective_modulus, hertz_coefficient, sphere_sphere_coefficient

#: Standard gravity, m/s^2 (CGPM 1901).
STANDARD_GRAVITY = 9.80665
#: What the sensor particle can report: the mean of its two contact forces, or one of them.
SENSOR_READS = ("mean", "upper", "lower")


@dataclass(frozen=True)
class ChainParams:
    """The chain and its numerics. SI units.

    Parameters
    ----------
    n_beads : int
        Beads including the striker (bead 0), >= 3.
    bead_radius : float
        m.
    bead_density : float
        kg/m^3.
    bead_E : float
        Pa.
    bead_nu : float
        -.
    sensor_index : int
        0-based index of the sensor particle, 1 <= index <= n_beads - 2.
    sensor_mass : float or None
        kg, mass of the sensor particle; ``None``: a bead's mass.
    striker_mass : float or None
        kg; ``None``: a bead's mass.
    uniform : bool
        The sensor particle is a plain bead (its mass is ignored).
    striker_velocity : float
        m/s, the striker's speed when it touches bead 1.
    gravity : bool
        Precompress the chain by its weight and keep gravity on during the run.
    g : float
        m/s^2.
    damping : float
        The dissipation coefficient ``c`` of every closed contact, in the unit of
        ``damping_law`` (the dashpot's N s/m; 0: conservative, the default).
    damping_law : str
        The contacts' dissipation law, a name of :data:`ssw.chain.dissipation.LAWS`: the
        damping force ``c d'`` (``dashpot``), ``c sqrt(d) d'`` (``kuwabara_kono``) or ``c
        F_el(d) d'`` (``hunt_crossley``) in each closed contact.
    plate_material : str
        The plate under the last bead (the thesis's PLA): the ``fit`` wall's K-table group.
    plate_thickness : float
        m (the thesis's 0.4 mm; 0 = no plate).
    plate_E : float
        Pa, the ``fem`` wall's plate.
    plate_nu : float
        -.
    plate_diameter : float
        m.
    plate_interface : str
        ``frictionless`` | ``bonded`` | ``unilateral``.
    preload : float
        N, a constant downward force on bead 1 (the top of the resting column: a guide
        sleeve, a spring, a weight), in the statics and during the hit.
    sensor_reads : str
        Which force the sensor particle reports: ``mean`` of its two contact forces (an
        instrumented bead), ``upper`` or ``lower`` contact (a load cell above or below its
        mass).
    fit_law : str
        ``k_hertz`` (F = K A_w d^1.5) or ``power`` (F = C d^n) for the ``fit`` wall.
    steps_per_contact : int
        Time steps per Hertz contact time of two beads at the striker speed.
    t_max : float
        s, longest simulated time (a scene whose reflected wave has not passed the sensor
        by then is run again for longer, up to ``ssw.chain.run.T_END_CAP``).
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
    damping_law: str = DEFAULT_LAW
    plate_material: str = "pla"
    plate_thickness: float = 0.4e-3
    plate_E: float = 3.5e9
    plate_nu: float = 0.36
    plate_diameter: float = 49.5e-3
    plate_interface: str = "frictionless"
    preload: float = 0.0
    sensor_reads: str = "mean"
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
        law = law_of(self.damping_law, "chain.damping_law")
        if not (np.isfinite(self.damping) and self.damping >= 0):
            raise ConfigError("chain.damping", self.damping,
                              f"a coefficient >= 0 {law.unit} ({law.name}: {law.formula})")
        if self.fit_law not in ("k_hertz", "power"):
            raise ConfigError("fit.law", self.fit_law, "k_hertz | power")
        if self.preload < 0 or not np.isfinite(self.preload):
            raise ConfigError("chain.preload", self.preload, "a force >= 0 N")
        if self.sensor_reads not in SENSOR_READS:
            raise ConfigError("sensor.reads", self.sensor_reads, " | ".join(SENSOR_READS))
        if self.plate_thickness < 0:
            raise ConfigError("plate.thickness", self.plate_thickness, ">= 0 m (0: no plate)")
        if self.plate_interface not in ("frictionless", "bonded", "unilateral"):
            raise ConfigError("plate.interface", self.plate_interface,
                              "frictionless | bonded | unilateral")
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
        """Hertz bead-on-half-space ``A_w = 4/3 sqrt(R) E*``.

        ``1/E* = (1 - nu_b^2)/E_b + (1 - nu_w^2)/E_w`` (REFERENCE.md; Johnson 1985 ch. 4).

        Parameters
        ----------
        soil_E : array_like
            Pa.
        soil_nu : array_like
            -.

        Returns
        -------
        numpy.ndarray
            N/m^1.5, broadcast.
        """
        e_star = effective_modulus(self.bead_E, self.bead_nu, soil_E, soil_nu)
        return hertz_coefficient(e_star, self.bead_radius)

    def wall_coefficient_dE(self, soil_E: Any, soil_nu: Any) -> np.ndarray:
        """``dA_w/dE`` of :meth:`wall_coefficient` at fixed ``soil_nu``: ``A_w E* c_w / E``
        with ``c_w = (1 - nu_w^2) / E``, from ``dE*/dE = E*^2 c_w / E``.

        Parameters
        ----------
        soil_E : array_like
            Pa.
        soil_nu : array_like
            -.

        Returns
        -------
        numpy.ndarray
            N/m^1.5/Pa, broadcast.
        """
        E = np.asarray(soil_E, float)
        c_w = (1.0 - np.asarray(soil_nu, float) ** 2) / E
        e_star = effective_modulus(self.bead_E, self.bead_nu, soil_E, soil_nu)
        return self.wall_coefficient(soil_E, soil_nu) * e_star * c_w / E

    def contact_time(self) -> float:
        """Hertz contact time (s) of two beads meeting at the striker speed (Johnson 11.24).

        Returns
        -------
        float
            Contact time (s).
        """
        from ssw.hertz import contact_time

        m = self.masses
        m_eff = m[0] * m[1] / (m[0] + m[1])
        return float(contact_time(m_eff, self.bead_coefficient, self.striker_velocity))

    def with_(self, **changes: Any) -> ChainParams:
        """A copy with ``changes`` (``dataclasses.replace``).

        Parameters
        ----------
        **changes : Any
            Field names and their new values (SI units, as the fields).

        Returns
        -------
        ChainParams
            The changed copy.
        """
        return replace(self, **changes)

    # ------------------------------------------------------------------ config
    @classmethod
    def from_config(cls, cfg: dict[str, Any], device: Any = None, **overrides: Any
                    ) -> ChainParams:
        """Parameters of a validated config: its device with the config's materials library
        and the numerics of its ``chain:`` section (and ``fit.law``).

        Parameters
        ----------
        cfg : dict
            A validated config (:func:`ssw.config.load_config`).
        device : Device or None
            A :class:`ssw.device.Device` instead of the config's ``device:``.
        **overrides
            Fields replaced afterwards.

        Returns
        -------
        ChainParams
            The chain.
        """
        from ssw.config import device_of, library

        dev = device if device is not None else device_of(cfg)
        return chain_params(dev, library(cfg), **numerics_of(cfg), **overrides)


def chain_params(device: Any, materials: dict[str, Any] | None = None, **numerics: Any
                 ) -> ChainParams:
    """The :class:`ChainParams` of a device: its beads, sensor, striker, preload and plate
    with the materials' values, and the study's numerics.

    Parameters
    ----------
    device : Device
        A :class:`ssw.device.Device`.
    materials : dict or None
        The materials library (key -> Material; default: the shipped one, ``realistic``).
    **numerics
        The non-device fields of ChainParams (``steps_per_contact``, ``t_max``,
        ``gravity``, ``fit_law``, ...), and ``damping``, ``damping_law`` replacing the
        device's dissipation.

    Returns
    -------
    ChainParams
        The chain.

    Raises
    ------
    ConfigError
        A material not in the library, or an unknown numerics field.
    """
    from dataclasses import fields as dc_fields

    from ssw.materials import material_set

    mats = materials if materials is not None else material_set()

    def material(key: str, field: str) -> Any:
        if key not in mats:
            raise ConfigError(field, key,
                              f"a material of the library: {', '.join(sorted(mats))}")
        return mats[key]

    bead = material(device.bead_material, "chain.bead_material")
    values: dict[str, Any] = {
        "n_beads": device.beads, "bead_radius": device.bead_radius,
        "bead_density": bead.density, "bead_E": bead.E, "bead_nu": bead.nu,
        "sensor_index": device.sensor_index, "sensor_mass": device.sensor_mass,
        "striker_mass": device.striker_mass, "striker_velocity": device.striker_velocity,
        "preload": device.preload, "sensor_reads": device.sensor_reads,
        "plate_material": device.plate_material if device.has_plate else "none",
        "plate_thickness": device.plate_thickness, "plate_diameter": device.plate_diameter,
        "plate_interface": device.plate_interface,
        "damping_law": device.dissipation_law, "damping": device.dissipation,
    }
    if device.has_plate:
        plate = material(device.plate_material, "plate.material")
        values["plate_E"], values["plate_nu"] = plate.E, plate.nu
    unknown = set(numerics) - {f.name for f in dc_fields(ChainParams)}
    if unknown:
        raise ConfigError("chain numerics", sorted(unknown), "fields of ChainParams")
    values.update(numerics)
    return ChainParams(**values)


def numerics_of(cfg: dict[str, Any]) -> dict[str, Any]:
    """The non-device ChainParams fields of a validated config.

    Parameters
    ----------
    cfg : dict
        A validated config.

    Returns
    -------
    dict
        ``gravity``, ``fit_law``, ``steps_per_contact``, ``t_max``, and ``damping`` when the
        config gives it (not null: it replaces the device's dissipation coefficient, in
        the unit of the device's law).
    """
    ch = cfg.get("chain", {})
    out = {
        "gravity": ch.get("gravity", ChainParams.gravity),
        "fit_law": cfg.get("fit", {}).get("law", ChainParams.fit_law),
        "steps_per_contact": ch.get("steps_per_contact", ChainParams.steps_per_contact),
        "t_max": ch.get("t_max", ChainParams.t_max),
    }
    if ch.get("damping") is not None:
        out["damping"] = ch["damping"]
    return out


#: ChainParams fields that may take one value per scene inside one batched run.
VARYING = ("striker_velocity", "preload", "striker_mass", "sensor_mass")


@dataclass(frozen=True)
class Batch:
    """The per-scene values of one batched run: a chain whose striker speed, preload and
    masses may differ from scene to scene (a calibration scan). SI units.

    Parameters
    ----------
    params : ChainParams
        Every other field.
    n : int
        Scenes.
    striker_velocity : numpy.ndarray
        (n,) m/s.
    preload : numpy.ndarray
        (n,) N.
    masses : numpy.ndarray
        (n, N) kg.
    """

    params: ChainParams
    n: int
    striker_velocity: np.ndarray
    preload: np.ndarray
    masses: np.ndarray

    @classmethod
    def of(cls, params: ChainParams, n: int, vary: dict[str, Any] | None = None) -> Batch:
        """``params`` for ``n`` scenes, with the fields of ``vary`` replaced per scene.

        Parameters
        ----------
        params : ChainParams
            The chain.
        n : int
            Scenes.
        vary : dict or None
            Names of :data:`VARYING` -> values broadcast to (n,).

        Returns
        -------
        Batch
            The scenes' values.

        Raises
        ------
        ConfigError
            An unknown field, or a value out of its range.
        """
        vary = {k: v for k, v in (vary or {}).items() if v is not None}
        unknown = set(vary) - set(VARYING)
        if unknown:
            raise ConfigError("vary", sorted(unknown), f"fields of {VARYING}")
        vals = {k: np.broadcast_to(np.asarray(v, float), (n,)).copy() for k, v in vary.items()}
        for k, v in vals.items():
            bad = ~np.isfinite(v) | ((v < 0) if k == "preload" else (v <= 0))
            if np.any(bad):
                raise ConfigError(f"chain.{k}", v[bad][:5].tolist(),
                                  ">= 0 N" if k == "preload" else "values > 0")
        masses = np.tile(params.masses, (n, 1))
        if "striker_mass" in vals:
            masses[:, 0] = vals["striker_mass"]
        if "sensor_mass" in vals and not params.uniform:
            masses[:, params.sensor_index] = vals["sensor_mass"]
        return cls(
            params=params, n=n,
            striker_velocity=vals.get("striker_velocity",
                                      np.full(n, float(params.striker_velocity))),
            preload=vals.get("preload", np.full(n, float(params.preload))),
            masses=masses,
        )

    def take(self, idx: np.ndarray) -> Batch:
        """The scenes ``idx``.

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        Batch
            The batch of the selected scenes (the same chain parameters).
        """
        idx = np.asarray(idx)
        return Batch(self.params, int(idx.size), self.striker_velocity[idx], self.preload[idx],
                     self.masses[idx])

    def contact_time(self) -> np.ndarray:
        """(n,) Hertz contact time (s) of the striker meeting bead 1 (Johnson 11.24).

        Returns
        -------
        numpy.ndarray
            Contact time (s), (n,).
        """
        from ssw.hertz import contact_time

        m0, m1 = self.masses[:, 0], self.masses[:, 1]
        return contact_time(m0 * m1 / (m0 + m1), self.params.bead_coefficient,
                            self.striker_velocity)
