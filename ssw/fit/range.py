"""The indentation range a fit covers: by default, what the chain reaches at its last contact.

Fitting a law on the whole FEM curve (0..0.1 mm in the thesis) weights indentations the
device never reaches (stiff soils) or misses those it does (soft soils). The default
range, mode ``chain``, is ``[0, factor * delta_peak(E, nu)]`` with ``delta_peak`` the peak
wall indentation of the chain on that soil, with the Hertz wall, from
``ssw.chain.run.peak_wall_indentation(soil_E, soil_nu, params)`` (the dynamics,
Stage II). Energy conservation bounds it from above (``energy_bound_indentation``, the
independent check of the tests): the wall cannot store more than the striker's kinetic
energy plus the work of the chain's weight over the wall's indentation,

      ``(2/5) A_w delta^(5/2) = 1/2 m_s v^2 + (M g + P) delta``,

with ``A_w = 4/3 E* sqrt(R_b)``, ``1/E* = (1-nu_b^2)/E_b + (1-nu_s^2)/E_s``, ``m_s`` the
striker (one bead) mass, ``M`` the chain's mass (gravity on), ``P`` the preload on bead 1
and ``v`` the striker speed
(bead-bead springs and kinetic energy left in the chain only lower the peak). A plate
stiffer than the soil makes the peak smaller still; one softer than the soil makes it
larger, which ``softer_half_space`` accounts for.

Other modes: ``fixed`` (``[delta_min, delta_max]`` from the config) and ``curve`` (the whole
curve). The upper end is clipped to the curve's last indentation; the result says so.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ssw import hertz
from ssw.errors import ConfigError

G = 9.80665  # m/s^2, standard gravity
RANGE_MODES = ("chain", "fixed", "curve")


@dataclass(frozen=True)
class ChainEstimate:
    """The chain quantities the energy bound needs. SI units.

    Parameters
    ----------
    beads : int
        Number of beads, the striker included.
    bead_radius : float
        Bead radius (m).
    bead_density : float
        Bead density (kg/m^3).
    bead_E : float
        Bead's Young's modulus (Pa).
    bead_nu : float
        Bead's Poisson's ratio.
    striker_velocity : float
        Striker speed (m/s).
    gravity : bool
        Whether the chain's weight loads the wall.
    preload : float
        Constant force on bead 1 (N).
    """

    beads: int  # including the striker
    bead_radius: float  # m
    bead_density: float  # kg/m^3
    bead_E: float  # Pa
    bead_nu: float  # -
    striker_velocity: float  # m/s
    gravity: bool
    preload: float = 0.0  # N, constant force on bead 1

    @property
    def bead_mass(self) -> float:
        """kg: ``4/3 pi R^3 rho``."""
        return 4.0 / 3.0 * np.pi * self.bead_radius**3 * self.bead_density

    @classmethod
    def from_config(cls, cfg: dict[str, Any]) -> ChainEstimate:
        """From a validated study config (its device and the materials library).

        Parameters
        ----------
        cfg : dict
            The validated study config.

        Returns
        -------
        ChainEstimate
            The chain's estimate (SI).
        """
        from ssw.config import device_of, library

        dev = device_of(cfg)
        mat = library(cfg)[dev.bead_material]
        return cls(
            beads=dev.beads,
            bead_radius=dev.bead_radius,
            bead_density=mat.density,
            bead_E=mat.E,
            bead_nu=mat.nu,
            striker_velocity=dev.striker_velocity,
            gravity=bool(cfg["chain"]["gravity"]),
            preload=dev.preload,
        )


def energy_bound_indentation(
    soil_E: ArrayLike, soil_nu: ArrayLike, chain: ChainEstimate
) -> NDArray[np.float64]:
    """Upper bound (m) of the Hertz-wall peak indentation from energy conservation.

    The positive root of ``(2/5) A_w d^(5/2) - (M g + P) d = 1/2 m_s v^2``
    (:func:`ssw.hertz.energy_indentation`, the upper end of its final bracket: the wall
    holds the energy there); vectorized over ``soil_E`` and ``soil_nu``.

    Parameters
    ----------
    soil_E : array_like
        Soil Young's modulus (Pa).
    soil_nu : array_like
        Soil Poisson's ratio.
    chain : ChainEstimate
        The chain (SI).

    Returns
    -------
    numpy.ndarray
        Indentation bound (m), the broadcast shape.

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 11.
    """
    E_star = hertz.effective_modulus(chain.bead_E, chain.bead_nu, soil_E, soil_nu)
    A = hertz.hertz_coefficient(E_star, chain.bead_radius)
    m = chain.bead_mass
    W0 = 0.5 * m * chain.striker_velocity**2
    Mg = (chain.beads * m * G if chain.gravity else 0.0) + chain.preload
    return hertz.energy_indentation(A, W0, Mg)


def peak_wall_indentation(
    soil_E: ArrayLike, soil_nu: ArrayLike, cfg: dict[str, Any]
) -> tuple[NDArray[np.float64], str]:
    """Peak wall indentation (m) of the config's chain on a Hertz wall (one batched run of
    :mod:`ssw.chain.run`), and its source, ``"chain"``.

    Parameters
    ----------
    soil_E : array_like
        Soil Young's modulus (Pa).
    soil_nu : array_like
        Soil Poisson's ratio.
    cfg : dict
        The validated study config.

    Returns
    -------
    peak : numpy.ndarray
        Peak indentations (m).
    source : str
        ``"chain"``.
    """
    from ssw.chain.params import ChainParams
    from ssw.chain.run import peak_wall_indentation as chain_peak

    params = ChainParams.from_config(cfg)
    return np.asarray(chain_peak(soil_E, soil_nu, params), float), "chain"


@dataclass(frozen=True)
class FitRange:
    """A fit range (m) and how it was chosen.

    Parameters
    ----------
    lo : float
        Lower end (m).
    hi : float
        Upper end (m).
    mode : str
        The range mode of the config.
    source : str
        Where the upper end comes from: ``chain``, ``config`` or ``curve``.
    needed : float
        The upper end before clipping to the curve (m).
    clipped : bool
        Whether the curve stops short of ``needed``.
    """

    lo: float
    hi: float
    mode: str
    source: str  # chain | config | curve
    needed: float  # m, the upper end before clipping to the curve
    clipped: bool  # the curve stops short of ``needed``


def softer_half_space(
    soil_E: ArrayLike, soil_nu: ArrayLike, plate_E: Any = None, plate_nu: Any = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(E, nu) of the softer of soil and plate, per scene (1-D); a plate E of None or NaN
    (no plate) keeps the soil. The chain's peak indentation into a Hertz wall of that
    material bounds the real one from above when the plate is softer than the soil.

    Parameters
    ----------
    soil_E : array_like
        Soil Young's modulus (Pa).
    soil_nu : array_like
        Soil Poisson's ratio.
    plate_E : Any
        Plate Young's modulus (Pa), scalar or per scene; None or NaN: no plate.
    plate_nu : Any
        Plate Poisson's ratio per scene.

    Returns
    -------
    E : numpy.ndarray
        Young's modulus (Pa) per scene.
    nu : numpy.ndarray
        Poisson's ratio per scene.
    """
    E = np.atleast_1d(np.asarray(soil_E, float)).copy()
    nu = np.atleast_1d(np.asarray(soil_nu, float)).copy()
    if plate_E is None:
        return E, nu
    pE = np.broadcast_to(np.array(plate_E, dtype=float), E.shape)  # None -> NaN
    pnu = np.broadcast_to(np.array(plate_nu, dtype=float), E.shape)
    softer = np.isfinite(pE) & (pE < E)
    E[softer], nu[softer] = pE[softer], pnu[softer]
    return E, nu


def energy_reach(
    soil_E: ArrayLike, soil_nu: ArrayLike, plate_E: Any, plate_nu: Any, radius: float,
    energy: float,
) -> NDArray[np.float64]:
    """Indentation (m) at which a rigid sphere (``radius`` m) stores ``energy`` (J) in a Hertz
    half-space of the softer of each scene's soil and plate (``softer_half_space``):
    ``(2/5) A d^(5/2) = W``, ``A = 4/3 E/(1 - nu^2) sqrt(R)`` (Johnson 1985, eq. 4.23), so
    ``d = (5 W / (2 A))^(2/5)``.

    The chain presses its wall no deeper than the energy it brings allows, and a plate
    stiffer than the soil only makes the contact stiffer than that wall (the bound of
    :func:`scenes_delta_max`), so with ``energy`` above the chain's (the striker's kinetic
    energy and the column's weight on the indentation) the curve covers the chain's range
    for any device of that energy: ``contact.delta_mode: energy``.

    Parameters
    ----------
    soil_E : array_like
        Soil Young's modulus (Pa).
    soil_nu : array_like
        Soil Poisson's ratio.
    plate_E : Any
        Plate Young's modulus (Pa) per scene; None or NaN: no plate.
    plate_nu : Any
        Plate Poisson's ratio per scene.
    radius : float
        Radius of the rigid sphere (m).
    energy : float
        Energy to store (J).

    Returns
    -------
    numpy.ndarray
        Indentation (m) per scene.
    """
    if not (np.isfinite(energy) and energy > 0):
        raise ConfigError("contact.reach_energy", energy, "an energy > 0 J")
    E, nu = softer_half_space(soil_E, soil_nu, plate_E, plate_nu)
    A = hertz.hertz_coefficient(hertz.effective_modulus(E, nu), float(radius))
    return hertz.energy_indentation(A, float(energy))


def fit_ranges(
    soil_E: ArrayLike, soil_nu: ArrayLike, curve_delta_max: ArrayLike, cfg: dict[str, Any],
    plate_E: Any = None, plate_nu: Any = None,
) -> list[FitRange]:
    """Fit ranges of many scenes (1-D arrays of one length) under the config's ``fit.range``.

    Parameters
    ----------
    soil_E : array_like
        The scenes' soil moduli, Pa.
    soil_nu : array_like
        The scenes' soil Poisson's ratios.
    curve_delta_max : array_like
        Each curve's last indentation, m.
    cfg : dict
        Validated study config (``fit.range.{mode, factor, delta_min, delta_max}``); in
        mode ``chain`` the chain runs once for all scenes (batched).
    plate_E : array_like or None
        The plates' moduli, Pa (None entries: no plate). In mode ``chain`` a plate softer
        than its soil replaces the soil in the Hertz wall (``softer_half_space``).
    plate_nu : array_like or None
        The plates' Poisson's ratios.

    Returns
    -------
    list of FitRange
        One range (m) per scene.
    """
    E, nu = softer_half_space(soil_E, soil_nu, plate_E, plate_nu)
    dmax = np.atleast_1d(np.asarray(curve_delta_max, float))
    rc = cfg.get("fit", {}).get("range", {})
    mode = rc.get("mode", "chain")
    lo = float(rc.get("delta_min", 0.0))
    if mode == "chain":
        d, source = peak_wall_indentation(E, nu, cfg)
        needed = float(rc.get("factor", 1.0)) * np.asarray(d, float).ravel()
    elif mode == "fixed":
        needed, source = np.full(E.size, float(rc.get("delta_max", 1.0e-4))), "config"
    elif mode == "curve":
        needed, source = dmax.copy(), "curve"
    else:
        raise ConfigError("fit.range.mode", mode, f"one of {', '.join(RANGE_MODES)}")
    hi = np.minimum(needed, dmax)
    if np.any(~(hi > lo)):
        raise ConfigError(
            "fit.range.delta_min", lo, f"below every range's upper end ({hi.min():.6g} m)"
        )
    clipped = needed > dmax * (1 + 1e-12)
    return [
        FitRange(lo, float(h), mode, source, float(n), bool(c))
        for h, n, c in zip(hi, needed, clipped, strict=True)
    ]


def fit_range(
    soil_E: float, soil_nu: float, curve_delta_max: float, cfg: dict[str, Any],
    plate_E: float | None = None, plate_nu: float | None = None,
) -> FitRange:
    """The fit range of one scene: :func:`fit_ranges` for one scene.

    Parameters
    ----------
    soil_E : float
        Soil Young's modulus (Pa).
    soil_nu : float
        Soil Poisson's ratio.
    curve_delta_max : float
        The curve's last indentation (m).
    cfg : dict
        The validated study config.
    plate_E : float or None
        Plate Young's modulus (Pa); None: no plate.
    plate_nu : float or None
        Plate Poisson's ratio.

    Returns
    -------
    FitRange
        The fit range (m).
    """
    return fit_ranges(soil_E, soil_nu, curve_delta_max, cfg, plate_E, plate_nu)[0]


def scene_delta_max(
    soil_E: float, soil_nu: float, cfg: dict[str, Any],
    plate: tuple[float, float] | None = None,
) -> float:
    """Indentation (m) a scene's curve must reach for the chain and the default fit.

    ``fit.range.factor`` times the chain's peak indentation into a Hertz wall of the softer
    of the soil and the plate (``plate = (E, nu)``, Pa and -; None without a plate): a
    plate stiffer than the soil makes the contact stiffer than that wall and the real peak
    smaller; a plate softer than the soil (the thesis's printed 100 MPa PLA on a 445 MPa
    foam) makes it larger than the soil's Hertz wall, but not larger than a half-space of
    the plate's material. In fit range mode ``curve`` it is ``contact.delta_max``.

    Parameters
    ----------
    soil_E : float
        Soil Young's modulus (Pa).
    soil_nu : float
        Soil Poisson's ratio.
    cfg : dict
        The validated study config.
    plate : tuple of float or None
        The plate's ``(E, nu)`` (Pa, -); None: no plate.

    Returns
    -------
    float
        Indentation (m).
    """
    pE, pnu = plate if plate is not None else (None, None)
    return float(scenes_delta_max([soil_E], [soil_nu], [pE], [pnu], cfg)[0])


def scenes_delta_max(
    soil_E: ArrayLike, soil_nu: ArrayLike, plate_E: Any, plate_nu: Any, cfg: dict[str, Any]
) -> NDArray[np.float64]:
    """:func:`scene_delta_max` of many scenes (1-D), with one batched chain run.

    Parameters
    ----------
    soil_E : array_like
        Soil Young's modulus (Pa).
    soil_nu : array_like
        Soil Poisson's ratio.
    plate_E : Any
        Plate Young's modulus (Pa) per scene; None or NaN: no plate.
    plate_nu : Any
        Plate Poisson's ratio per scene.
    cfg : dict
        The validated study config.

    Returns
    -------
    numpy.ndarray
        Indentation (m) per scene.
    """
    E = np.atleast_1d(np.asarray(soil_E, float))
    if cfg.get("fit", {}).get("range", {}).get("mode", "chain") == "curve":
        return np.full(E.size, float(cfg["contact"]["delta_max"]))
    ranges = fit_ranges(E, soil_nu, np.full(E.size, np.inf), cfg, plate_E, plate_nu)
    return np.array([r.needed for r in ranges])
