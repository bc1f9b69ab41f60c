"""The device as the design variable: the space of devices a design searches, and one point
of it.

A device (:class:`ssw.device.Device`) has more knobs than its plate. The design varies

* on stated lists (discrete): the beads' material (the materials library's, each with its
  source and strength) and diameter (standard ball sizes), the number of beads, the sensor's
  position (a share of the chain from the striker), the plate's material;
* in bounded ranges (continuous, searched in their logarithm): the sensor bead's and the
  striker's mass as multiples of a bead's, the striker's drop height, the plate's thickness.

The plate's diameter is a fixed multiple of the bead diameter (the base device's, unless
stated), so that a device scaled in every length keeps its shape. A *chain* is one choice of
the discrete bead variables (material, diameter, count, sensor position): the scenes of a
chain advance together in one batched run (:mod:`ssw.design.device_eval`). A *family* is a
bead diameter and a plate material: the contact operators its candidates need (one mesh per
plate thickness and bead radius, :mod:`ssw.contact.operators`) and the unit of work of the
study's workflow (one job each, its chains scattered over parts).

Scan. Each continuous variable is first sampled at ``scan`` points, the centres of ``scan``
equal cells of its log range (one point: the geometric mean), so that a coarse scan never
sits on a bound; the bounded search (:mod:`ssw.design.device_search`) then moves the best
devices anywhere inside the ranges.
"""

from __future__ import annotations

import itertools
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

import numpy as np

from ssw.design.spec import THICKNESS_QUANTUM
from ssw.device import STANDARD_GRAVITY
from ssw.errors import ConfigError

#: Bead materials searched by default (keys of the materials library).
BEAD_MATERIALS = ("chrome_steel", "stainless316", "tungsten_carbide", "brass")
#: Bead diameters searched by default, m: 1/4, 3/8, 1/2 and 3/4 in bearing balls.
BEAD_DIAMETERS = (6.35e-3, 9.525e-3, 12.7e-3, 19.05e-3)
#: Bead counts (striker included) searched by default.
BEADS = (12, 20)
#: Sensor positions searched by default: the sensor's index over the bead count.
SENSOR_POSITIONS = (0.35, 0.5)
#: Plate materials searched by default.
PLATE_MATERIALS = ("pla", "al6061", "a36")
#: Continuous variables: (lo, hi, scan points) of each by default.
SENSOR_MASS_RATIO = (0.5, 2.0, 1)
STRIKER_MASS_RATIO = (0.5, 4.0, 2)
DROP_HEIGHT = (2.0e-3, 5.0e-2, 2)
PLATE_THICKNESS = (1.0e-4, 3.0e-3, 1)
#: Relative quantum of the continuous ratios and the drop height (a search revisits none
#: closer than this; reruns share their evaluations).
RATIO_QUANTUM = 1.0e-6
#: Names of the continuous variables, in the order of a search's vector.
CONTINUOUS = ("sensor_mass_ratio", "striker_mass_ratio", "drop_height", "plate_thickness")


@dataclass(frozen=True)
class Interval:
    """A continuous variable's range ``[lo, hi]`` (its SI unit or a ratio) and the number of
    points of its scan.

    Parameters
    ----------
    lo : float
        Lower bound, in the variable's SI unit (m for lengths) or a ratio.
    hi : float
        Upper bound, same unit as ``lo``.
    scan : int
        Points of the coarse scan (centres of equal cells of the log range).
    """

    lo: float
    hi: float
    scan: int = 1

    def check(self, name: str) -> None:
        """ConfigError naming ``design.device.<name>`` for a bad range.

        Parameters
        ----------
        name : str
            The variable's key under ``design.device`` (named in the error).

        Raises
        ------
        ssw.errors.ConfigError
            When the bounds are not finite with ``0 < lo <= hi``, or ``scan`` is no integer
            >= 1.
        """
        if not (np.isfinite(self.lo) and np.isfinite(self.hi) and 0 < self.lo <= self.hi):
            raise ConfigError(f"design.device.{name}.range", [self.lo, self.hi],
                              "[LO, HI] with 0 < LO <= HI")
        if not (isinstance(self.scan, int) and self.scan >= 1):
            raise ConfigError(f"design.device.{name}.scan", self.scan, "an integer >= 1")

    def scan_values(self) -> np.ndarray:
        """The scan: the centres of ``scan`` equal cells of ``[ln lo, ln hi]``.

        Returns
        -------
        numpy.ndarray
            (scan,) the scan points, in the variable's unit:
            ``exp(ln lo + (ln hi - ln lo) (k + 1/2) / scan)``, ``k = 0 .. scan - 1``.
        """
        a, b = np.log(self.lo), np.log(self.hi)
        return np.exp(a + (b - a) * (np.arange(self.scan) + 0.5) / self.scan)

    def contains(self, x: float) -> bool:
        """Whether ``x`` lies in the range (relative tolerance 1e-9).

        Parameters
        ----------
        x : float
            The value, in the variable's unit.

        Returns
        -------
        bool
            True when ``lo (1 - 1e-9) <= x <= hi (1 + 1e-9)``.
        """
        return self.lo * (1 - 1e-9) <= x <= self.hi * (1 + 1e-9)


@dataclass(frozen=True)
class DevicePoint:
    """One device of the space. SI units; masses as multiples of one bead's.

    Parameters
    ----------
    bead_material : str
        Key of the materials library.
    bead_diameter : float
        The beads' diameter, m.
    beads : int
        Beads including the striker (bead 0).
    sensor_index : int
        0-based index of the sensor bead from the striker.
    sensor_mass_ratio : float
        The sensor bead's mass over a bead's.
    striker_mass_ratio : float
        The striker's mass over a bead's.
    drop_height : float
        m, the striker's free fall (its speed ``sqrt(2 g h)``).
    plate_material : str
        Key of the materials library.
    plate_thickness : float
        The plate's thickness, m.
    plate_diameter : float
        The plate's diameter, m.
    """

    bead_material: str
    bead_diameter: float
    beads: int
    sensor_index: int
    sensor_mass_ratio: float
    striker_mass_ratio: float
    drop_height: float
    plate_material: str
    plate_thickness: float
    plate_diameter: float

    @property
    def bead_radius(self) -> float:
        """The beads' radius, m."""
        return 0.5 * self.bead_diameter

    @property
    def striker_velocity(self) -> float:
        """m/s, ``sqrt(2 g h)`` (free fall from the drop height)."""
        return float(np.sqrt(2.0 * STANDARD_GRAVITY * self.drop_height))

    @property
    def chain(self) -> tuple[str, float, int, int]:
        """The discrete bead variables: what one batched run shares."""
        return (self.bead_material, self.bead_diameter, self.beads, self.sensor_index)

    @property
    def key(self) -> tuple[Any, ...]:
        """Every variable (quantized): one evaluation per key."""
        return (*self.chain, self.sensor_mass_ratio, self.striker_mass_ratio,
                self.drop_height, self.plate_material, self.plate_thickness,
                self.plate_diameter)

    def continuous(self) -> np.ndarray:
        """The continuous variables in the order of :data:`CONTINUOUS`.

        Returns
        -------
        numpy.ndarray
            (4,) sensor and striker mass ratios (-), drop height (m), plate thickness (m).
        """
        return np.array([getattr(self, k) for k in CONTINUOUS])

    def with_continuous(self, x: np.ndarray) -> DevicePoint:
        """The point with the continuous variables ``x`` (order of :data:`CONTINUOUS`),
        quantized.

        Parameters
        ----------
        x : numpy.ndarray
            (4,) sensor and striker mass ratios (-), drop height (m), plate thickness (m).

        Returns
        -------
        DevicePoint
            This point with those values, rounded by :func:`quantize`.
        """
        return quantize(replace(self, **{k: float(v) for k, v in zip(CONTINUOUS, x,
                                                                    strict=True)}))

    def params(self, base: Any, materials: dict[str, Any]) -> Any:
        """The :class:`ssw.chain.params.ChainParams` of this device: ``base``'s numerics
        (time steps, gravity, damping, interface) with this device's beads, sensor, striker
        and plate, the materials' values.

        Parameters
        ----------
        base : ssw.chain.params.ChainParams
            The base chain whose numerics are kept.
        materials : dict of str to Material
            The materials library (key to density, kg/m^3, E, Pa, nu, -).

        Returns
        -------
        ssw.chain.params.ChainParams
            The chain of this device (masses, kg, from ``4/3 pi R^3 rho`` of a bead).

        Raises
        ------
        ssw.errors.ConfigError
            When the bead or plate material is not in ``materials``.
        """
        bead = _material(materials, self.bead_material, "design.device.bead_materials")
        plate = _material(materials, self.plate_material, "design.device.plate_materials")
        R = self.bead_radius
        m_bead = 4.0 / 3.0 * np.pi * R**3 * bead.density
        return base.with_(
            n_beads=int(self.beads), bead_radius=R, bead_density=bead.density,
            bead_E=bead.E, bead_nu=bead.nu, sensor_index=int(self.sensor_index),
            sensor_mass=float(self.sensor_mass_ratio * m_bead),
            striker_mass=float(self.striker_mass_ratio * m_bead), uniform=False,
            striker_velocity=self.striker_velocity, plate_material=plate.key,
            plate_thickness=float(self.plate_thickness), plate_E=plate.E, plate_nu=plate.nu,
            plate_diameter=float(self.plate_diameter))

    def device(self, base: Any, materials: dict[str, Any], name: str = "designed") -> Any:
        """The :class:`ssw.device.Device` of this point (``base``'s DAQ sensor, interface,
        preload and reading).

        Parameters
        ----------
        base : ssw.device.Device
            The base device whose sensor, interface, preload and reading are kept.
        materials : dict of str to Material
            The materials library (the bead material's density, kg/m^3, sets the masses).
        name : str
            The new device's name.

        Returns
        -------
        ssw.device.Device
            The device of this point.

        Raises
        ------
        ssw.errors.ConfigError
            When the bead material is not in ``materials``.
        """
        bead = _material(materials, self.bead_material, "design.device.bead_materials")
        m_bead = 4.0 / 3.0 * np.pi * self.bead_radius**3 * bead.density
        return base.with_(
            name=name, description=f"ssw design --space device: {self.label()}",
            beads=int(self.beads), bead_material=self.bead_material,
            bead_radius=self.bead_radius, sensor_index=int(self.sensor_index),
            sensor_mass=float(self.sensor_mass_ratio * m_bead),
            striker_mass=float(self.striker_mass_ratio * m_bead),
            striker_velocity=self.striker_velocity, plate_material=self.plate_material,
            plate_thickness=float(self.plate_thickness),
            plate_diameter=float(self.plate_diameter), source="")

    def label(self) -> str:
        """A short description (mm, g-free ratios).

        Returns
        -------
        str
            Beads, diameter (mm) and material, sensor index and mass ratio, striker mass
            ratio and drop height (mm), plate material and thickness (mm).
        """
        return (f"{self.beads} x {self.bead_diameter * 1e3:.4g} mm {self.bead_material}, "
                f"sensor {self.sensor_index} (x{self.sensor_mass_ratio:.3g}), striker "
                f"x{self.striker_mass_ratio:.3g} from {self.drop_height * 1e3:.3g} mm, "
                f"{self.plate_material} {self.plate_thickness * 1e3:.3g} mm")

    def to_dict(self) -> dict[str, Any]:
        """Every variable (JSON).

        Returns
        -------
        dict of str to Any
            Field name to value (SI units).
        """
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> DevicePoint:
        """A point from :meth:`to_dict`.

        Parameters
        ----------
        d : dict of str to Any
            Field name to value (SI units); unknown keys are ignored.

        Returns
        -------
        DevicePoint
            The point.
        """
        names = {f.name for f in fields(cls)}
        return cls(**{k: (int(v) if k in ("beads", "sensor_index") else
                          str(v) if k in ("bead_material", "plate_material") else float(v))
                      for k, v in d.items() if k in names})


def _material(materials: dict[str, Any], key: str, field: str) -> Any:
    if key not in materials:
        raise ConfigError(field, key, f"materials of the library: {', '.join(sorted(materials))}")
    return materials[key]


def _round(x: float, quantum: float) -> float:
    """``x`` rounded to a relative ``quantum`` (6 significant digits for 1e-6)."""
    if x == 0 or not np.isfinite(x):
        return float(x)
    digits = int(-np.floor(np.log10(quantum)))
    return float(f"{x:.{digits - 1}e}")


def quantize(p: DevicePoint) -> DevicePoint:
    """The point with its continuous variables rounded (:data:`RATIO_QUANTUM` relative; the
    plate's thickness to :data:`ssw.design.spec.THICKNESS_QUANTUM`).

    Parameters
    ----------
    p : DevicePoint
        The point.

    Returns
    -------
    DevicePoint
        The point with its mass ratios and drop height rounded to a relative 1e-6 and its
        plate thickness to a multiple of the thickness quantum (m).
    """
    t = float(np.round(p.plate_thickness / THICKNESS_QUANTUM) * THICKNESS_QUANTUM)
    return replace(p, sensor_mass_ratio=_round(p.sensor_mass_ratio, RATIO_QUANTUM),
                   striker_mass_ratio=_round(p.striker_mass_ratio, RATIO_QUANTUM),
                   drop_height=_round(p.drop_height, RATIO_QUANTUM), plate_thickness=t)


def sensor_index(position: float, beads: int) -> int:
    """The sensor's index for a position (share of the chain from the striker):
    ``floor(position beads + 1/2)``, kept within ``1 .. beads - 2``.

    Parameters
    ----------
    position : float
        The sensor's share of the chain from the striker, in (0, 1).
    beads : int
        Beads including the striker.

    Returns
    -------
    int
        The sensor bead's 0-based index.
    """
    return int(np.clip(np.floor(position * beads + 0.5), 1, beads - 2))


@dataclass(frozen=True)
class DeviceSpace:
    """The devices a design searches (module docstring). Lengths in m.

    Parameters
    ----------
    bead_materials : tuple of str
        Materials of the beads (library keys).
    bead_diameters : tuple of float
        Bead diameters, m.
    beads : tuple of int
        Bead counts, striker included.
    sensor_positions : tuple of float
        The sensor's index over the bead count, in (0, 1).
    plate_materials : tuple of str
        Materials of the plate (library keys).
    sensor_mass_ratio : Interval
        The sensor bead's mass over a bead's.
    striker_mass_ratio : Interval
        The striker's mass over a bead's.
    drop_height : Interval
        The striker's drop height, m.
    plate_thickness : Interval
        The plate's thickness, m.
    plate_diameter_ratio : float
        The plate's diameter over the bead diameter.
    """

    bead_materials: tuple[str, ...] = BEAD_MATERIALS
    bead_diameters: tuple[float, ...] = BEAD_DIAMETERS
    beads: tuple[int, ...] = BEADS
    sensor_positions: tuple[float, ...] = SENSOR_POSITIONS
    plate_materials: tuple[str, ...] = PLATE_MATERIALS
    sensor_mass_ratio: Interval = Interval(*SENSOR_MASS_RATIO)
    striker_mass_ratio: Interval = Interval(*STRIKER_MASS_RATIO)
    drop_height: Interval = Interval(*DROP_HEIGHT)
    plate_thickness: Interval = Interval(*PLATE_THICKNESS)
    plate_diameter_ratio: float = 49.5e-3 / 19.05e-3

    def __post_init__(self) -> None:
        for name in ("bead_materials", "bead_diameters", "beads", "sensor_positions",
                     "plate_materials"):
            if not getattr(self, name):
                raise ConfigError(f"design.device.{name}", [], "at least one value")
        if any(not (np.isfinite(d) and d > 0) for d in self.bead_diameters):
            raise ConfigError("design.device.bead_diameters", list(self.bead_diameters),
                              "diameters > 0 m")
        if any(int(n) != n or n < 5 for n in self.beads):
            raise ConfigError("design.device.beads", list(self.beads),
                              "integers >= 5 (striker, beads above and below the sensor)")
        if any(not 0 < s < 1 for s in self.sensor_positions):
            raise ConfigError("design.device.sensor_positions", list(self.sensor_positions),
                              "shares of the chain in (0, 1)")
        for name in CONTINUOUS:
            getattr(self, name).check(name)
        if self.plate_thickness.lo < 10 * THICKNESS_QUANTUM:
            raise ConfigError("design.device.plate_thickness.range", self.plate_thickness.lo,
                              f">= {10 * THICKNESS_QUANTUM:g} m")
        if not (np.isfinite(self.plate_diameter_ratio) and self.plate_diameter_ratio > 0):
            raise ConfigError("design.device.plate_diameter_ratio", self.plate_diameter_ratio,
                              "a ratio > 0")

    # ------------------------------------------------------------------ structure
    def families(self) -> list[tuple[float, str]]:
        """(bead diameter, plate material) pairs: the workflow's jobs.

        Returns
        -------
        list of tuple of (float, str)
            Bead diameter (m) and plate material key of each family.
        """
        return list(itertools.product(self.bead_diameters, self.plate_materials))

    def chains(self, diameter: float) -> list[tuple[str, float, int, int]]:
        """The chains of one bead diameter, in a fixed order (the same sensor index from
        two positions counts once).

        Parameters
        ----------
        diameter : float
            The bead diameter, m.

        Returns
        -------
        list of tuple of (str, float, int, int)
            Bead material, diameter (m), bead count and sensor index of each chain.
        """
        out = []
        for mat, n, pos in itertools.product(self.bead_materials, self.beads,
                                             self.sensor_positions):
            key = (mat, float(diameter), int(n), sensor_index(pos, int(n)))
            if key not in out:
                out.append(key)
        return out

    def scan(self, chain: tuple[str, float, int, int], plate_material: str
             ) -> list[DevicePoint]:
        """The scan points of one chain on one plate material.

        Parameters
        ----------
        chain : tuple of (str, float, int, int)
            Bead material, diameter (m), bead count and sensor index.
        plate_material : str
            The plate's material key.

        Returns
        -------
        list of DevicePoint
            The product of the continuous variables' scans, quantized.
        """
        mat, diameter, n, idx = chain
        grids = [getattr(self, k).scan_values() for k in CONTINUOUS]
        return [quantize(DevicePoint(mat, diameter, n, idx, float(sm), float(st), float(h),
                                     plate_material, float(t),
                                     self.plate_diameter_ratio * diameter))
                for sm, st, h, t in itertools.product(*grids)]

    def family_points(self, diameter: float, plate_material: str, part: int = 0,
                      parts: int = 1) -> list[DevicePoint]:
        """The scan points of a family's chains ``part``, ``part + parts``, ... (a part of
        the workflow's scatter; every chain whole in one part).

        Parameters
        ----------
        diameter : float
            The family's bead diameter, m.
        plate_material : str
            The family's plate material key.
        part : int
            This part's index, ``0 <= part < parts``.
        parts : int
            The number of parts the family's chains are split into.

        Returns
        -------
        list of DevicePoint
            The scan points of this part's chains.

        Raises
        ------
        ssw.errors.ConfigError
            On a bad ``part``/``parts`` or more parts than the family has chains.
        """
        if not (isinstance(parts, int) and parts >= 1 and 0 <= part < parts):
            raise ConfigError("--part", f"{part}/{parts}", "I/N with 0 <= I < N")
        every = self.chains(diameter)
        if parts > len(every):
            raise ConfigError("design.device.parts", parts, f"at most {len(every)} (the "
                              "family's chains: bead materials x counts x sensor positions)")
        chains = every[part::parts]
        return [p for c in chains for p in self.scan(c, plate_material)]

    @property
    def size(self) -> int:
        """Scan points of the whole space."""
        per = int(np.prod([getattr(self, k).scan for k in CONTINUOUS]))
        return sum(len(self.chains(d)) for d in self.bead_diameters) * per * len(
            self.plate_materials)

    def bounds(self) -> list[tuple[float, float]]:
        """The continuous variables' log bounds, in the order of :data:`CONTINUOUS`.

        Returns
        -------
        list of tuple of (float, float)
            ``(ln lo, ln hi)`` of each variable (ln of its SI value or ratio).
        """
        return [(float(np.log(getattr(self, k).lo)), float(np.log(getattr(self, k).hi)))
                for k in CONTINUOUS]

    def to_dict(self) -> dict[str, Any]:
        """Every field (JSON), the ranges as ``{range: [lo, hi], scan: n}``.

        Returns
        -------
        dict of str to Any
            Field name to value (SI units), plus ``size`` (scan points of the space).
        """
        d: dict[str, Any] = {k: list(getattr(self, k)) for k in (
            "bead_materials", "bead_diameters", "beads", "sensor_positions",
            "plate_materials")}
        for k in CONTINUOUS:
            iv = getattr(self, k)
            d[k] = {"range": [iv.lo, iv.hi], "scan": iv.scan}
        d["plate_diameter_ratio"] = self.plate_diameter_ratio
        d["size"] = self.size
        return d


def space_from_dict(d: dict[str, Any], base_ratio: float) -> DeviceSpace:
    """The :class:`DeviceSpace` of a config's ``design.device`` section (schema-filled or
    partial: missing keys take the defaults), ``base_ratio`` the base device's plate
    diameter over its bead diameter (when the section states none).

    Parameters
    ----------
    d : dict of str to Any
        The ``design.device`` section (lengths in m).
    base_ratio : float
        The base device's plate diameter over its bead diameter (-).

    Returns
    -------
    DeviceSpace
        The space.

    Raises
    ------
    ssw.errors.ConfigError
        When a value is out of its allowed range (:class:`DeviceSpace` checks).
    """
    kw: dict[str, Any] = {}
    for k, conv in (("bead_materials", str), ("bead_diameters", float), ("beads", int),
                    ("sensor_positions", float), ("plate_materials", str)):
        if d.get(k) is not None:
            kw[k] = tuple(conv(v) for v in d[k])
    for k in CONTINUOUS:
        v = d.get(k)
        if v is not None:
            lo, hi = v["range"]
            kw[k] = Interval(float(lo), float(hi), int(v.get("scan", 1)))
    ratio = d.get("plate_diameter_ratio")
    kw["plate_diameter_ratio"] = float(ratio) if ratio is not None else float(base_ratio)
    return DeviceSpace(**kw)


def point_of(params: Any, bead_material: str, plate_material: str) -> DevicePoint:
    """The :class:`DevicePoint` of a chain (``ChainParams``: a base device), its bead and
    plate material keys given (the params hold their values).

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The chain (SI units).
    bead_material : str
        The beads' material key.
    plate_material : str
        The plate's material key.

    Returns
    -------
    DevicePoint
        The point, masses as ratios to a bead's, drop height ``v^2 / (2 g)`` in m.
    """
    m = params.masses
    mb = params.bead_mass
    return DevicePoint(
        bead_material=bead_material, bead_diameter=2.0 * params.bead_radius,
        beads=int(params.n_beads), sensor_index=int(params.sensor_index),
        sensor_mass_ratio=float(m[params.sensor_index] / mb),
        striker_mass_ratio=float(m[0] / mb),
        drop_height=float(params.striker_velocity**2 / (2.0 * STANDARD_GRAVITY)),
        plate_material=plate_material, plate_thickness=float(params.plate_thickness),
        plate_diameter=float(params.plate_diameter))
