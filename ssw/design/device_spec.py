"""What a device design asks: the soils, the objective, the limits, the DAQ and the search.

Objective. The worst case over the soil range of the relative resolution of the modulus::

    dE/E (E) = u_TOF(E) / (TOF(E) S(E)),    S = |d ln TOF / d ln E|,

the relative change of E that moves the mean TOF of one measurement by its standard
uncertainty (smaller is better). ``S`` is exact for the discrete TOF (forward sensitivities,
:func:`ssw.tof.api.tof_derivatives`), and ``u_TOF`` the quadratic sum of

* one hit's scatter (the device's stated ``repeatability.tof_std``, or the thesis's),
  averaged over ``hits`` hits;
* the DAQ's noise through the peak picker, averaged over the hits, and the sampled peaks'
  error at the DAQ's rate: its mean over the sample clock's phase (systematic, not
  averaged) and its spread over the phase (random per hit) (:mod:`ssw.design.sampling`).

Constraints, each an index that must stay at or below its limit (hard: a device that
breaks one is not built; soft: the sample's yield, which ranks devices when none keeps it):

* ``overlap_index`` <= 1 (hard): the incident and reflected pulses separate at the sensor
  (:mod:`ssw.design.device_eval`: the valley between them on the dense output below the
  peak rule's gap share of the smaller one);
* ``round_trip_index`` <= 1 (hard): the reflected peak comes back no sooner than the
  shortest physical round trip (:func:`ssw.signal.tof.shortest_round_trip`), so it is a
  reflection and not a later pulse of a heavy striker's train;
* ``detection_index`` <= 1 (hard): the reflected peak stands out of the DAQ's noise by the
  peak rule's ``noise_k`` sigmas; ``range_index`` <= 1 (hard): the sensor's largest reading
  within the full scale of the sensor and the DAQ (:attr:`ssw.device.Device.full_scale_force`);
* ``bead_yield_index`` <= 1 (hard): the beads stay elastic (Hertz first yield of two beads
  at the chain's largest contact force, :func:`ssw.constitutive.yield_index.yield_index`);
* ``plate_yield_index`` <= ``plate_yield_limit`` (hard; 1 by default: first yield),
  ``plate_mass_ratio`` <= ``max_plate_mass_ratio`` (hard: the quasi-static wall neglects
  the plate's inertia), as in the plate design;
* ``mass`` <= ``max_mass`` and ``length`` <= ``max_length`` (hard: a hand-held device);
* ``soil_yield_index`` <= ``soil_yield_limit`` (soft), the sample's first yield in the
  elastic field with its strength ``soil_strength`` or ``soil_strength_ratio E``
  (:mod:`ssw.design.spec`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ssw.design.spec import check_soil, soil_yield_stress
from ssw.errors import ConfigError

#: Soil moduli of a device's curves (log-spaced over the range, ends included).
MODULI = 6
#: kg, the heaviest device (beads, striker, sensor and plate) held by hand.
MAX_MASS = 1.5
#: m, the longest device: the column of beads, the drop and the plate.
MAX_LENGTH = 0.6
#: Sample-clock phases over which a sampled peak's error is averaged (a divisor of the
#: simulated DAQ's oversampling, ``ssw.daq.simulated.OVERSAMPLE``).
PHASES = 4
#: Devices refined by the bounded search after the scan.
FINALISTS = 2
#: Evaluations of each finalist's bounded search.
REFINE_EVALUATIONS = 12
#: Tolerance of the bounded search, in the logarithm of each continuous variable.
REFINE_TOL = 0.02
#: Hits of the finalists' plastic check (0: off; ``ssw.design.hits_check``).
PLASTIC_HITS = 0


@dataclass(frozen=True)
class DeviceSpec:
    """A device design problem (module docstring). SI units.

    Parameters
    ----------
    soil_E : tuple of float
        (lo, hi) Pa, the soils the device must measure.
    soil_nu : float
        Their Poisson's ratio (-).
    moduli : int
        Soil moduli of each device's curves.
    soil_strength : float or None
        Pa, the soil's yield stress, or None: ``soil_strength_ratio E``.
    soil_strength_ratio : float
        The soil's yield stress over its modulus.
    soil_yield_limit : float
        The largest soil yield index allowed.
    plate_yield_limit : float
        The largest plate yield index allowed (1: the plate's first yield; above, a local
        dent accepted, for ``--plastic-hits`` to judge).
    max_plate_mass_ratio : float
        The largest plate mass over a bead's.
    max_mass : float
        kg, the heaviest device.
    max_length : float
        m, the longest device.
    hits : int
        TOF hits averaged per measurement.
    tof_scatter : float
        s, one hit's TOF standard deviation (stated, not modelled).
    tof_scatter_source : str
        Where it comes from.
    sample_rate : float
        S/s, the DAQ's rate.
    noise_rms : float
        N, the DAQ's white noise.
    phases : int
        Sample-clock phases of the sampled peaks' error.
    finalists : int
        Devices refined by the bounded search.
    refine_evaluations : int
        Evaluations of each bounded search.
    refine_tol : float
        The bounded search's tolerance in the variables' logarithm.
    plastic_hits : int
        Hits of the plastic check of the finalists and the base device (0: none; else at
        least 2: :func:`ssw.design.hits_check.device_hits_check`).
    """

    soil_E: tuple[float, float]
    soil_nu: float
    moduli: int = MODULI
    soil_strength: float | None = None
    soil_strength_ratio: float = 0.01
    soil_yield_limit: float = 1.0
    plate_yield_limit: float = 1.0
    max_plate_mass_ratio: float = 1.0
    max_mass: float = MAX_MASS
    max_length: float = MAX_LENGTH
    hits: int = 3
    tof_scatter: float = 1.53e-5
    tof_scatter_source: str = ""
    sample_rate: float = 51200.0
    noise_rms: float = 0.05
    phases: int = PHASES
    finalists: int = FINALISTS
    refine_evaluations: int = REFINE_EVALUATIONS
    refine_tol: float = REFINE_TOL
    plastic_hits: int = PLASTIC_HITS

    def __post_init__(self) -> None:
        check_soil(self.soil_E, self.soil_nu)
        if self.moduli < 2:
            raise ConfigError("design.device.moduli", self.moduli, "an integer >= 2")
        for name in ("soil_strength_ratio", "soil_yield_limit", "plate_yield_limit",
                     "max_plate_mass_ratio",
                     "max_mass", "max_length", "tof_scatter", "sample_rate", "refine_tol"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ConfigError(f"design.device.{name}", v, "a value > 0")
        if self.soil_strength is not None and not (np.isfinite(self.soil_strength)
                                                   and self.soil_strength > 0):
            raise ConfigError("--soil-strength", self.soil_strength, "a stress > 0 Pa")
        if not (np.isfinite(self.noise_rms) and self.noise_rms >= 0):
            raise ConfigError("--noise-rms", self.noise_rms, "a noise >= 0 N")
        if self.phases not in (1, 2, 4, 8, 16):
            raise ConfigError("design.device.phases", self.phases, "1, 2, 4, 8 or 16")
        for name in ("hits", "finalists"):
            if getattr(self, name) < 1:
                raise ConfigError(f"design.device.{name}", getattr(self, name),
                                  "an integer >= 1")
        if not (isinstance(self.plastic_hits, int) and (self.plastic_hits == 0
                                                        or self.plastic_hits >= 2)):
            raise ConfigError("design.device.plastic_hits", self.plastic_hits,
                              "0 (no plastic check) or an integer >= 2 (--plastic-hits)")
        if self.refine_evaluations < 0:
            raise ConfigError("design.device.refine_evaluations", self.refine_evaluations,
                              "an integer >= 0 (0: no bounded search)")

    @property
    def grid(self) -> np.ndarray:
        """(moduli,) Pa: the soil moduli, log-spaced."""
        return np.geomspace(self.soil_E[0], self.soil_E[1], self.moduli)

    def soil_yield_stress(self, E: np.ndarray) -> np.ndarray:
        """The soil's yield stress (Pa) at moduli ``E``
        (:func:`ssw.design.spec.soil_yield_stress`).

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
    def limits(self) -> dict[str, float]:
        """Each index's limit (module docstring)."""
        return {"overlap_index": 1.0, "round_trip_index": 1.0, "detection_index": 1.0,
                "range_index": 1.0,
                "bead_yield_index": 1.0, "plate_yield_index": self.plate_yield_limit,
                "plate_mass_ratio": self.max_plate_mass_ratio, "mass": self.max_mass,
                "length": self.max_length, "soil_yield_index": self.soil_yield_limit}

    def statement(self) -> dict[str, Any]:
        """The objective and the constraints, stated (the JSON's ``objective`` and
        ``constraints``).

        Returns
        -------
        dict of str to Any
            ``objective``, ``constraints``, ``plastic_check``, ``ranking`` and
            ``resolution``, each in words with this spec's values.
        """
        strength = (f"{self.soil_strength:.4g} Pa" if self.soil_strength is not None else
                    f"{self.soil_strength_ratio:g} E (assumed)")
        return {
            "objective": "minimize the worst case over the soil range of the resolution "
                         "dE/E = u_TOF / (TOF |d ln TOF / d ln E|) (exact forward "
                         "sensitivities of the chain's TOF on the fem wall of each device)",
            "constraints": {
                "overlap_index": "valley between the incident and reflected pulses at the "
                                 "sensor (dense output) over the peak rule's gap share of "
                                 "the smaller pulse <= 1 (hard: the pulses separate)",
                "round_trip_index": "the shortest physical round trip sensor -> wall -> "
                                    "sensor (ssw.signal.tof.shortest_round_trip) over the "
                                    "TOF <= 1 (hard: a reflection, not the striker's train)",
                "detection_index": "the peak rule's noise floor over the reflected peak "
                                   "<= 1 (hard)",
                "range_index": "the sensor's largest reading over the full scale of the "
                               "sensor and the DAQ <= 1 (hard)",
                "bead_yield_index": "Hertz peak pressure of two beads at the largest contact "
                                    "force over their first-yield pressure <= 1 (hard)",
                "plate_yield_index": "max over E of the plate's peak von Mises stress over "
                                     f"its yield stress <= {self.plate_yield_limit:g} (hard)",
                "plate_mass_ratio": f"plate mass over a bead's <= {self.max_plate_mass_ratio:g}"
                                    " (hard)",
                "mass": f"beads, striker, sensor and plate <= {self.max_mass:g} kg (hard)",
                "length": f"bead column, drop and plate <= {self.max_length:g} m (hard)",
                "soil_yield_index": f"max over E of the soil's peak von Mises stress (elastic "
                                    f"field) over its yield stress {strength} <= "
                                    f"{self.soil_yield_limit:g} (soft)",
            },
            "plastic_check": (
                f"the {self.finalists} best devices of distinct chains and plates and the "
                f"base device struck {self.plastic_hits} times on a virgin von Mises sample "
                f"of the soil strength at the soil of their largest soil yield index, "
                f"through the plate yielding as von Mises with the library's strength: the "
                f"plate's dent, the sample's set, the TOF drift (not a constraint)"
                if self.plastic_hits else "off (design.device.plastic_hits 0)"),
            "ranking": "the feasible device of finest resolution; when none is feasible, the "
                       "smallest weighted violation (hard limits first)",
            "resolution": f"u_TOF^2 = scatter^2 / hits + (noise^2 + spread^2) / hits + bias^2: "
                          f"one hit's scatter {self.tof_scatter:.3g} s "
                          f"({self.tof_scatter_source or 'source not stated'}), "
                          f"{self.hits} hits, the DAQ's noise {self.noise_rms:g} N rms at "
                          f"{self.sample_rate:g} S/s through the peak picker, the sampled "
                          f"peaks' bias and spread over {self.phases} clock phases",
        }

    def to_dict(self) -> dict[str, Any]:
        """Every field (JSON) and the soil grid.

        Returns
        -------
        dict of str to Any
            Every field (SI units) and ``soil_E_grid`` (Pa, :attr:`grid`).
        """
        return {**asdict(self), "soil_E_grid": self.grid.tolist()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> DeviceSpec:
        """A spec from :meth:`to_dict`.

        Parameters
        ----------
        d : dict of str to Any
            The fields (SI units); ``soil_E_grid`` is ignored.

        Returns
        -------
        DeviceSpec
            The spec.
        """
        kw = {k: v for k, v in d.items() if k != "soil_E_grid"}
        kw["soil_E"] = tuple(kw["soil_E"])
        return cls(**kw)
