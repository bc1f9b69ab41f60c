"""Drucker-Prager plasticity with a tension cutoff: a soil's cohesion, friction and dilatancy.

Surfaces (perfectly plastic; ``p`` the mean stress, tension positive; ``sqrt(J2) = q /
sqrt(3)``):

    cone      f1 = sqrt(J2) + eta p - xi c <= 0,     flow potential sqrt(J2) + eta_bar p,
    cutoff    f2 = p - t <= 0,                       associated (volumetric flow),

with ``t`` the tension cutoff, at most the cone's apex ``p_apex = xi c / eta`` (without a
stated tensile strength the cutoff is the apex itself, so the apex return is the corner
return below with zero deviator). Non-associated flow takes ``eta_bar`` from the
dilatancy angle ``psi`` as ``eta`` from ``phi``.

Match to Mohr-Coulomb (``c``, ``phi``; de Souza Neto, Peric & Owen 2008, sec. 6.4.3):

* ``outer`` (default): the cone through the Mohr-Coulomb pyramid's compressive edges,
  ``eta = 6 sin(phi) / (sqrt(3) (3 - sin(phi)))``, ``xi = 6 cos(phi) / (sqrt(3) (3 -
  sin(phi)))``. Under the axis of an indenter the stress is triaxial compression (``sigma_r
  = sigma_t``, ``sigma_z`` the most compressive), where this cone and Mohr-Coulomb agree
  exactly;
* ``inner``: through the tensile edges, ``3 + sin(phi)`` in the denominators (a lower
  bound of Mohr-Coulomb's strength everywhere);
* ``plane-strain``: ``eta = 3 tan(phi) / sqrt(9 + 12 tan^2(phi))``, ``xi = 3 / sqrt(9 +
  12 tan^2(phi))``: the same plane-strain limit loads as Mohr-Coulomb (associated flow).

Return mapping (backward Euler, closed form per region of the trial ``(p_tr, q_tr)``;
de Souza Neto et al. 2008, Boxes 8.8-8.9, with the cutoff as a second surface):

* cone: ``d gamma = f1_tr / (G + K eta eta_bar)``, ``sqrt(J2) = sqrt(J2_tr) - G d gamma``,
  ``p = p_tr - K eta_bar d gamma``, valid while ``p <= t``;
* cutoff: ``p = t``, deviator kept, valid while ``f1(t, q_tr) <= 0``;
* corner (the apex when ``t = p_apex``): ``p = t``, ``sqrt(J2) = xi c - eta t``.

Each region's consistent tangent follows from ``d(p, q) / d(p_tr, q_tr)``
(:func:`ssw.constitutive.tensors.pq_tangent`): at the corner ``p`` and ``q`` are fixed, only
the deviatoric direction turns (zero tangent at the apex). With ``eta_bar != eta`` the
tangent is not symmetric.

References
----------
de Souza Neto, E. A., Peric, D. & Owen, D. R. J. (2008). *Computational Methods for
Plasticity*. Wiley, ch. 6 and 8.
Drucker, D. C. & Prager, W. (1952). Soil mechanics and plastic analysis or limit design.
*Q. Appl. Math.* 10, 157-165.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ssw.constitutive.base import YIELD_RTOL, Update, check_stress, number_text
from ssw.constitutive.tensors import ONE, SQRT_2_3, invariants, pq_tangent, stress_of, trial
from ssw.errors import ConfigError

#: Matches of the cone to Mohr-Coulomb (module docstring).
MATCHES = ("outer", "inner", "plane-strain")
SQRT3 = float(np.sqrt(3.0))


def cone(angle_deg: float, match: str) -> tuple[float, float]:
    """``(eta, xi)`` of the cone matched to a Mohr-Coulomb angle (degrees).

    Parameters
    ----------
    angle_deg : float
        Mohr-Coulomb friction (or dilatancy) angle (degrees).
    match : str
        The matching: ``outer``, ``inner`` or ``plane-strain``.

    Returns
    -------
    tuple of float
        ``(eta, xi)``, dimensionless.

    Raises
    ------
    ConfigError
        If ``match`` is none of the three.

    References
    ----------
    de Souza Neto, E. A., Peric, D. and Owen, D. R. J. (2008). *Computational Methods for
    Plasticity*, Wiley, ch. 6.
    """
    a = np.radians(float(angle_deg))
    if match == "outer":
        d = SQRT3 * (3.0 - np.sin(a))
        return float(6.0 * np.sin(a) / d), float(6.0 * np.cos(a) / d)
    if match == "inner":
        d = SQRT3 * (3.0 + np.sin(a))
        return float(6.0 * np.sin(a) / d), float(6.0 * np.cos(a) / d)
    if match == "plane-strain":
        d = np.sqrt(9.0 + 12.0 * np.tan(a) ** 2)
        return float(3.0 * np.tan(a) / d), float(3.0 / d)
    raise ConfigError("soil_model.match", match, " | ".join(MATCHES))


@dataclass(frozen=True)
class DruckerPrager:
    """Drucker-Prager with a tension cutoff (module docstring).

    Parameters
    ----------
    cohesion : float
        ``c`` (Pa), >= 0.
    friction_angle : float
        Degrees, [0, 90).
    dilatancy_angle : float or None
        Degrees, [0, friction_angle]; None: the friction angle (associated).
    tension_cutoff : float or None
        The largest mean stress ``t`` (Pa), >= 0; None: the apex.
    match : str
        The Mohr-Coulomb match: ``outer``, ``inner`` or ``plane-strain``.
    """

    cohesion: float
    friction_angle: float
    dilatancy_angle: float | None = None
    tension_cutoff: float | None = None
    match: str = "outer"
    name: ClassVar[str] = "drucker-prager"

    def __post_init__(self) -> None:
        check_stress(self, "cohesion", "a cohesion >= 0 Pa", zero=True)
        if not 0.0 <= self.friction_angle < 90.0:
            raise ConfigError("soil_model.friction_angle", self.friction_angle,
                              "an angle in [0, 90) degrees")
        psi = self.dilatancy
        if not 0.0 <= psi <= self.friction_angle:
            raise ConfigError("soil_model.dilatancy_angle", self.dilatancy_angle,
                              "an angle in [0, friction_angle] degrees")
        if self.match not in MATCHES:
            raise ConfigError("soil_model.match", self.match, " | ".join(MATCHES))
        if self.tension_cutoff is not None and not self.tension_cutoff >= 0:
            raise ConfigError("soil_model.tension_cutoff", self.tension_cutoff,
                              "a mean stress >= 0 Pa (or none: the apex)")
        if self.cohesion == 0 and self.friction_angle == 0:
            raise ConfigError("soil_model", "c = 0, phi = 0", "a cohesion or a friction angle")

    @property
    def dilatancy(self) -> float:
        """The dilatancy angle in use, degrees."""
        return float(self.friction_angle if self.dilatancy_angle is None
                     else self.dilatancy_angle)

    @property
    def key(self) -> str:
        """Short file-name-safe text that tells two models apart (enters the scene id)."""
        text = (f"dp-c{number_text(self.cohesion, 1e3)}kPa-phi"
                f"{number_text(self.friction_angle)}")
        if self.dilatancy != self.friction_angle:
            text += f"-psi{number_text(self.dilatancy)}"
        if self.tension_cutoff is not None:
            text += f"-t{number_text(self.tension_cutoff, 1e3)}kPa"
        if self.match != "outer":
            text += f"-{self.match}"
        return text

    @property
    def constants(self) -> tuple[float, float, float, float]:
        """``(eta, xi, eta_bar, t)``: the cone, the flow potential's slope and the cutoff."""
        eta, xi = cone(self.friction_angle, self.match)
        eta_bar, _ = cone(self.dilatancy, self.match)
        apex = xi * self.cohesion / eta if eta > 0 else np.inf
        t = apex if self.tension_cutoff is None else min(float(self.tension_cutoff), apex)
        return eta, xi, eta_bar, float(t)

    @property
    def strength(self) -> float:
        """Unconfined compressive strength of the Mohr-Coulomb material,
        ``2 c cos(phi) / (1 - sin(phi))``, Pa (the outer cone's too)."""
        a = np.radians(self.friction_angle)
        return float(2.0 * self.cohesion * np.cos(a) / (1.0 - np.sin(a)))

    def params(self) -> dict[str, Any]:
        """The model's parameters as a plain dict (SI units, angles in degrees).

        Returns
        -------
        dict
            ``model`` (the registry name) and each parameter.
        """
        return {"model": self.name, "cohesion": self.cohesion,
                "friction_angle": self.friction_angle, "dilatancy_angle": self.dilatancy,
                "tension_cutoff": self.tension_cutoff, "match": self.match}

    def update(self, E: float, nu: float, strain: np.ndarray, state: np.ndarray) -> Update:
        """Return mapping of ``strain`` (n, 4) from ``state`` (n, 5) (module docstring).

        Parameters
        ----------
        E : float
            Young's modulus of the sample (Pa).
        nu : float
            Poisson's ratio of the sample, in (-1, 0.5).
        strain : numpy.ndarray
            Total strains (Mandel), (n, 4).
        state : numpy.ndarray
            State at the increment's start, (n, 5): plastic strain and hardening variable.

        Returns
        -------
        Update
            Stress (Pa), consistent tangent (Pa), new state, yield flags and return regions.

        Raises
        ------
        ConfigError
            If ``E`` is not > 0 or ``nu`` lies outside (-1, 0.5).
        """
        K, G, p_tr, q_tr, n = trial(E, nu, strain, state[:, :4])
        eta, xi, eta_b, t = self.constants
        c = float(self.cohesion)
        tol = YIELD_RTOL * max(xi * c, float(E) * 1e-9)
        sj_tr = q_tr / SQRT3
        f1 = sj_tr + eta * p_tr - xi * c
        f2 = p_tr - t
        A = G + K * eta * eta_b
        dg = np.maximum(f1, 0.0) / A
        p1 = p_tr - K * eta_b * dg
        sj_c = max(xi * c - eta * t, 0.0) if np.isfinite(t) else np.inf
        plastic = (f1 > tol) | (f2 > tol)
        on_cone = (f1 > tol) & (p1 <= t)
        on_cut = ~on_cone & (f2 > tol) & (sj_tr <= sj_c)
        region = np.where(~plastic, 0, np.where(on_cone, 1, np.where(on_cut, 2, 3)))
        region = region.astype(np.int8)
        p = np.where(region == 0, p_tr, np.where(region == 1, p1, t))
        sj = np.where(region == 0, sj_tr, np.where(region == 1, sj_tr - G * dg,
                                                    np.where(region == 2, sj_tr, sj_c)))
        q = SQRT3 * sj
        J = np.zeros((q.size, 2, 2))
        J[:, 0, 0] = np.where(region == 0, 1.0, np.where(region == 1, 1.0 - K * eta_b * eta / A,
                                                         0.0))
        J[:, 0, 1] = np.where(region == 1, -K * eta_b / (SQRT3 * A), 0.0)
        J[:, 1, 0] = np.where(region == 1, -SQRT3 * G * eta / A, 0.0)
        J[:, 1, 1] = np.where((region == 0) | (region == 2), 1.0,
                              np.where(region == 1, 1.0 - G / A, 0.0))
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.where((region == 0) | (region == 2), 1.0,
                             np.where(q_tr > 0, q / q_tr, 0.0))
        stress = stress_of(p, q, n)
        new = state.copy()
        new[:, :4] = np.where(plastic[:, None], strain - elastic_strain(K, G, stress),
                              state[:, :4])
        dep = new[:, :4] - state[:, :4]
        new[:, 4] += np.where(plastic, SQRT_2_3 * np.sqrt(np.einsum("ni,ni->n", dep, dep)), 0.0)
        return Update(stress, pq_tangent(K, G, n, J, ratio), new, plastic, region)

    def yield_ratio(self, stress: np.ndarray, state: np.ndarray) -> np.ndarray:
        """``max((sqrt(J2) + eta p) / (xi c), p / t)`` (n,): 1 on the yield surface (inf
        where a cohesionless cone is reached at positive ``sqrt(J2) + eta p``).

        Parameters
        ----------
        stress : numpy.ndarray
            Stresses (Mandel, Pa), (n, 4).
        state : numpy.ndarray
            States, (n, 5) (column 4: the hardening variable).

        Returns
        -------
        numpy.ndarray
            Yield ratio, (n,): 1 on the yield surface, below 1 inside.
        """
        eta, xi, _, t = self.constants
        p, q = invariants(stress)
        lhs = q / SQRT3 + eta * p
        with np.errstate(invalid="ignore", divide="ignore"):
            r1 = lhs / (xi * self.cohesion) if self.cohesion > 0 else np.where(
                lhs > 0, np.inf, 0.0)
            r2 = np.where(np.isfinite(t) & (t > 0), p / t, np.where(p > 0, np.inf, 0.0))
        return np.maximum(r1, r2)


def elastic_strain(K: float, G: float, stress: np.ndarray) -> np.ndarray:
    """``C^-1 sigma = p / (3 K) ONE + s / (2 G)`` (n, 4).

    Parameters
    ----------
    K : float
        Bulk modulus (Pa).
    G : float
        Shear modulus (Pa).
    stress : numpy.ndarray
        Stresses (Mandel, Pa), (n, 4).

    Returns
    -------
    numpy.ndarray
        Elastic strains (Mandel), (n, 4).
    """
    p = stress @ ONE / 3.0
    return (p / (3.0 * K))[:, None] * ONE + (stress - p[:, None] * ONE) / (2.0 * G)
