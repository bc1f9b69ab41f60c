"""What a plate design asks: the soils, the plates to consider, the objective and the limits.

A design looks for the plate under the chain's last bead (material, thickness, optionally
diameter and striker speed) that makes the device most sensitive to the soil's modulus over
a range of soils, while the plate stays elastic, the sample yields no more than allowed and
the plate stays light against a bead (:class:`DesignSpec`; the ``design:`` section of a
study config, :func:`spec_from_config`).

Objective. The worst case over the soil range of the sensitivity::

    S(E) = |d ln TOF / d ln E|,

the relative TOF change per relative change of the soil's modulus: the larger, the finer the
modulus the device resolves for a given TOF scatter (the resolution
``dE/E = u_TOF / (TOF S)``, :mod:`ssw.design.evaluate`).

Constraints, each an index that must stay at or below its limit:

* plate: ``plate_yield_index = max_E sigma_vM,plate / Y_plate <= 1`` (the plate stays
  elastic; ``Y`` the plate material's yield stress, ``ssw/data/materials.yaml``);
* sample: ``soil_yield_index = max_E sigma_vM,soil / Y_soil(E) <= soil_yield_limit``
  (first yield from the elastic field; ``Y_soil = soil_strength`` (Pa) when given, else
  ``soil_strength_ratio * E``);
* mass: ``mass_ratio = m_plate / m_bead <= max_mass_ratio`` (the chain's wall is
  quasi-static: it neglects the plate's inertia, which a plate heavier than a bead would
  not allow).

Soil strength. The soils of a design are given by their modulus only; their strength is a
stated assumption, ``Y_soil = soil_strength_ratio E`` (default :data:`SOIL_STRENGTH_RATIO`,
inside the range of compacted clays, ``E_u / s_u`` 100-1500 with ``Y = 2 s_u`` (Duncan &
Buchignani 1976), and of rigid polyurethane foams, compressive strength ~0.04 E [U]). The
ranking of plates by how much the sample yields does not depend on it (every plate's index
scales alike); only the constraint ``soil_yield_limit`` does. ``soil_peak_strain`` (the
peak von Mises stress over E) is reported beside the index, free of this assumption.

References
----------
Duncan, J. M. & Buchignani, A. L. (1976). An engineering manual for settlement studies.
Geotechnical Engineering Report, University of California, Berkeley.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ssw.errors import ConfigError
from ssw.validity import SOIL_STRENGTH_RATIO as _VALIDITY_RATIO

#: Default soil strength as a share of its modulus (module docstring): the one stated
#: assumption every result's yield check names (:data:`ssw.validity.SOIL_STRENGTH_RATIO`).
SOIL_STRENGTH_RATIO = _VALIDITY_RATIO
#: Default thickness range searched, m.
THICKNESS = (1.0e-4, 3.0e-3)
#: Default plate materials.
MATERIALS = ("pla", "al6061", "a36")
#: Soil moduli of the sensitivity curve (log-spaced over the range).
MODULI = 20
#: Half-step in ln E of the central difference of ln TOF.
LOG_STEP = 0.05
#: Thicknesses (log-spaced) scanned per material before the bounded search.
SCAN_POINTS = 5
#: Tolerance of the bounded search, in ln(thickness).
THICKNESS_TOL = 0.01
#: Thicknesses are rounded to this (m): reruns and neighbouring searches share operators.
THICKNESS_QUANTUM = 1.0e-6
#: TOF hits averaged per measurement for the resolution (the thesis's three hits).
HITS = 3


@dataclass(frozen=True)
class DesignSpec:
    """A plate design problem (module docstring). SI units.

    Parameters
    ----------
    soil_E : tuple of (float, float)
        ``(lo, hi)`` Pa, the soils the device must measure.
    soil_nu : float
        Their Poisson's ratio (-).
    materials : tuple of str
        Plate material keys (the materials library).
    thickness : tuple of (float, float)
        ``(lo, hi)`` m, the thickness range searched per material.
    plate_diameters : tuple of float
        m, plate diameters tried (discrete); empty: the device's.
    striker_velocities : tuple of float
        m/s, striker speeds tried (discrete); empty: the device's.
    moduli : int
        Soil moduli of the sensitivity curve (log-spaced, ends included).
    log_step : float
        Half-step in ln E of the central difference of ln TOF (-).
    soil_strength : float or None
        Pa, the soil's yield stress, or None: ``soil_strength_ratio * E``.
    soil_strength_ratio : float
        Yield stress over modulus of the soil (-, when no ``soil_strength``).
    soil_yield_limit : float
        The largest soil yield index allowed (-, 1: first yield).
    max_mass_ratio : float
        The largest plate mass over a bead's mass (-).
    hits : int
        TOF hits averaged per measurement (resolution).
    tof_scatter : float
        s, one hit's TOF standard deviation.
    tof_scatter_source : str
        Where ``tof_scatter`` comes from.
    tof_sampling : float
        s, the TOF's sampling uncertainty at the DAQ's rate.
    sample_rate : float or None
        S/s, the DAQ's sample rate (None: not stated).
    scan_points : int
        Thicknesses scanned per material before the bounded search.
    thickness_tol : float
        The bounded search's tolerance in ln(thickness) (-).
    extra : dict of str to Any
        Further values carried along (not compared, not written by :meth:`to_dict`).
    """

    soil_E: tuple[float, float]
    soil_nu: float
    materials: tuple[str, ...] = MATERIALS
    thickness: tuple[float, float] = THICKNESS
    plate_diameters: tuple[float, ...] = ()
    striker_velocities: tuple[float, ...] = ()
    moduli: int = MODULI
    log_step: float = LOG_STEP
    soil_strength: float | None = None
    soil_strength_ratio: float = SOIL_STRENGTH_RATIO
    soil_yield_limit: float = 1.0
    max_mass_ratio: float = 1.0
    hits: int = HITS
    tof_scatter: float = 1.53e-5
    tof_scatter_source: str = ""
    tof_sampling: float = 0.0
    sample_rate: float | None = None
    scan_points: int = SCAN_POINTS
    thickness_tol: float = THICKNESS_TOL
    extra: dict[str, Any] = field(default_factory=dict, compare=False, hash=False)

    def __post_init__(self) -> None:
        check_soil(self.soil_E, self.soil_nu)
        tlo, thi = self.thickness
        if not (np.isfinite(tlo) and np.isfinite(thi) and 0 < tlo < thi):
            raise ConfigError("--thickness", f"{tlo}:{thi}", "LO:HI with 0 < LO < HI (m)")
        if tlo < 10 * THICKNESS_QUANTUM:
            raise ConfigError("--thickness", tlo, f">= {10 * THICKNESS_QUANTUM:g} m")
        if not self.materials:
            raise ConfigError("--materials", "", "at least one plate material")
        for name, vals in (("--plate-diameters", self.plate_diameters),
                           ("--striker-velocities", self.striker_velocities)):
            if any(not (np.isfinite(v) and v > 0) for v in vals):
                raise ConfigError(name, list(vals), "values > 0")
        if self.moduli < 2:
            raise ConfigError("design.moduli", self.moduli, "an integer >= 2")
        if not 0 < self.log_step <= 0.2:
            raise ConfigError("design.log_step", self.log_step, "a step in (0, 0.2]")
        for name in ("soil_strength_ratio", "soil_yield_limit", "max_mass_ratio",
                     "tof_scatter", "thickness_tol"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ConfigError(f"design.{name}", v, "a value > 0")
        if self.soil_strength is not None and not (np.isfinite(self.soil_strength)
                                                   and self.soil_strength > 0):
            raise ConfigError("--soil-strength", self.soil_strength, "a stress > 0 Pa")
        if self.hits < 1 or self.scan_points < 2:
            raise ConfigError("design.hits, design.scan_points",
                              (self.hits, self.scan_points), "hits >= 1, scan_points >= 2")
        if not (np.isfinite(self.tof_sampling) and self.tof_sampling >= 0):
            raise ConfigError("tof_sampling", self.tof_sampling, "an uncertainty >= 0 s")

    @property
    def grid(self) -> np.ndarray:
        """(moduli,) Pa: the soil moduli of the sensitivity curve, log-spaced."""
        return np.geomspace(self.soil_E[0], self.soil_E[1], self.moduli)

    def soil_yield_stress(self, E: np.ndarray) -> np.ndarray:
        """The soil's yield stress (Pa) at moduli ``E`` (module docstring).

        Parameters
        ----------
        E : numpy.ndarray
            Soil moduli, Pa.

        Returns
        -------
        numpy.ndarray
            Yield stress, Pa, shaped as ``E``: ``soil_strength`` when stated, else
            ``soil_strength_ratio E``.
        """
        return soil_yield_stress(E, self.soil_strength, self.soil_strength_ratio)

    @property
    def tof_uncertainty(self) -> float:
        """s, the mean TOF's standard uncertainty of one measurement: the scatter over
        ``sqrt(hits)`` and the sampling term, in quadrature."""
        return float(np.hypot(self.tof_scatter / np.sqrt(self.hits), self.tof_sampling))

    def statement(self) -> dict[str, Any]:
        """The objective and the constraints, stated (the JSON's ``objective`` and
        ``constraints``).

        Returns
        -------
        dict of str to Any
            ``objective``, ``constraints``, ``ranking`` and ``resolution``, each in words
            with this spec's values.
        """
        strength = (f"{self.soil_strength:.4g} Pa" if self.soil_strength is not None else
                    f"{self.soil_strength_ratio:g} E (assumed; the ranking does not depend "
                    "on it)")
        return {
            "objective": "maximize the worst case over the soil range of the sensitivity "
                         "|d ln TOF / d ln E| (the exact derivative of the chain's TOF with "
                         "the fem wall: its forward sensitivity in E)",
            "constraints": {
                "plate_yield_index": "max over E of the plate's peak von Mises stress over "
                                     "its yield stress <= 1 (the plate stays elastic)",
                "soil_yield_index": f"max over E of the soil's peak von Mises stress (elastic "
                                    f"field) over its yield stress {strength} <= "
                                    f"{self.soil_yield_limit:g}",
                "mass_ratio": f"plate mass over a bead's <= {self.max_mass_ratio:g} (the "
                              "quasi-static wall neglects the plate's inertia)",
            },
            "ranking": "the feasible candidate of largest sensitivity; when none is "
                       "feasible, the smallest total relative violation",
            "resolution": f"dE/E = u_TOF / (TOF S), u_TOF = {self.tof_uncertainty:.3g} s: "
                          f"one hit's scatter {self.tof_scatter:.3g} s "
                          f"({self.tof_scatter_source or 'source not stated'}) over "
                          f"sqrt({self.hits}) hits and the sampling term "
                          f"{self.tof_sampling:.3g} s at {self.sample_rate or 0:g} S/s, "
                          "in quadrature",
        }

    def to_dict(self) -> dict[str, Any]:
        """Every field (JSON).

        Returns
        -------
        dict of str to Any
            Every field but ``extra`` (SI units) and ``soil_E_grid`` (Pa, :attr:`grid`).
        """
        d = asdict(self)
        d.pop("extra")
        return {**d, "soil_E_grid": self.grid.tolist()}


def check_soil(soil_E: tuple[float, float], soil_nu: float) -> None:
    """ConfigError naming ``--soil-E`` or ``--soil-nu`` for a bad soil range (Pa) or
    Poisson's ratio.

    Parameters
    ----------
    soil_E : tuple of (float, float)
        ``(lo, hi)`` soil moduli, Pa.
    soil_nu : float
        The soil's Poisson's ratio (-).

    Raises
    ------
    ssw.errors.ConfigError
        When not ``0 < lo < hi`` (finite), or ``soil_nu`` is outside (-1, 0.5].
    """
    lo, hi = soil_E
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
        raise ConfigError("--soil-E", f"{lo}:{hi}", "LO:HI moduli with 0 < LO < HI (Pa)")
    if not -1.0 < soil_nu <= 0.5:
        raise ConfigError("--soil-nu", soil_nu, "a Poisson's ratio in (-1, 0.5]")


def soil_yield_stress(E: np.ndarray, strength: float | None, ratio: float) -> np.ndarray:
    """The soil's yield stress (Pa) at moduli ``E`` (Pa): ``strength`` when stated, else
    ``ratio E`` (module docstring).

    Parameters
    ----------
    E : numpy.ndarray
        Soil moduli, Pa.
    strength : float or None
        The soil's stated yield stress, Pa, or None.
    ratio : float
        Yield stress over modulus (-), used when ``strength`` is None.

    Returns
    -------
    numpy.ndarray
        Yield stress, Pa, shaped as ``E``.
    """
    E = np.asarray(E, float)
    if strength is not None:
        return np.full(E.shape, float(strength))
    return ratio * E


def parse_range(text: str, field_name: str) -> tuple[float, float]:
    """``LO:HI`` -> (lo, hi) floats; ConfigError naming ``field_name`` otherwise.

    Parameters
    ----------
    text : str
        The range as ``LO:HI`` (SI units).
    field_name : str
        The flag or key named in the error.

    Returns
    -------
    tuple of (float, float)
        ``(lo, hi)``, in the unit of ``text``.

    Raises
    ------
    ssw.errors.ConfigError
        When ``text`` is not two numbers separated by a colon.
    """
    try:
        lo, hi = (float(x) for x in str(text).split(":"))
    except ValueError as exc:
        raise ConfigError(field_name, text, "LO:HI (two numbers, SI units)") from exc
    return lo, hi


def parse_list(text: str | None, field_name: str) -> tuple[float, ...]:
    """``A,B,...`` -> floats (empty for None or '').

    Parameters
    ----------
    text : str or None
        Comma-separated numbers (SI units), or None.
    field_name : str
        The flag or key named in the error.

    Returns
    -------
    tuple of float
        The numbers, in the unit of ``text``.

    Raises
    ------
    ssw.errors.ConfigError
        When an item is no number.
    """
    if not text:
        return ()
    try:
        return tuple(float(x) for x in str(text).split(","))
    except ValueError as exc:
        raise ConfigError(field_name, text, "comma-separated numbers (SI units)") from exc


def spec_from_config(design: dict[str, Any], soil: str, **fields: Any) -> DesignSpec:
    """The :class:`DesignSpec` of soil range ``soil`` of a config's ``design:`` section
    (schema-filled), with ``fields`` (the device's and the DAQ's values) added.

    Parameters
    ----------
    design : dict of str to Any
        The config's ``design:`` section (SI units).
    soil : str
        The key of a soil range under ``design.soils``.
    **fields : Any
        Further :class:`DesignSpec` fields; they override the section's.

    Returns
    -------
    DesignSpec
        The design problem.

    Raises
    ------
    ssw.errors.ConfigError
        When ``soil`` is no soil range of the section, or a value is out of range.
    """
    soils = design.get("soils", {})
    if soil not in soils:
        raise ConfigError("design soil range", soil, f"one of {', '.join(soils) or '(none)'}")
    s = soils[soil]
    kw: dict[str, Any] = {
        "soil_E": tuple(float(x) for x in s["soil_E"]), "soil_nu": float(s["soil_nu"]),
        "materials": tuple(design.get("materials", MATERIALS)),
        "thickness": tuple(float(x) for x in design.get("thickness", THICKNESS)),
        "plate_diameters": tuple(float(x) for x in design.get("plate_diameters", [])),
        "striker_velocities": tuple(float(x) for x in design.get("striker_velocities", [])),
    }
    for key in ("moduli", "log_step", "soil_strength", "soil_strength_ratio",
                "soil_yield_limit", "max_mass_ratio", "hits", "scan_points",
                "thickness_tol"):
        if design.get(key) is not None:
            kw[key] = design[key]
    kw.update(fields)
    return DesignSpec(**kw)
