"""Crushable foam (Deshpande & Fleck 2000): a yield ellipse in (p, q) that crushes under
pressure as well as shear, with hardening.

Yield function (Deshpande & Fleck 2000, eq. 2.4; perfectly plastic when ``H = 0``):

    f = sigma_hat - Y(kappa) <= 0,   sigma_hat^2 = (q^2 + alpha^2 p^2) / (1 + (alpha/3)^2),

so ``sigma_hat`` is the stress in uniaxial compression or tension (``q = 3 |p|``) and ``Y``
the uniaxial compressive strength (the plateau stress of a rigid foam: the catalogue's
compressive strength). The shape factor follows from the plastic Poisson's ratio ``nu_p``
of uniaxial compression (Deshpande & Fleck 2000, eq. 2.7):
``alpha^2 = 9 (1 - 2 nu_p) / (2 (1 + nu_p))``; rigid polymer foams crush with ``nu_p ~ 0``
(``alpha = 3 / sqrt(2)``, the default), ``nu_p = 1/2`` is von Mises. Flow is associated;
``kappa`` is the work-conjugate equivalent plastic strain (``sigma_hat d kappa = sigma :
d eps_p``), ``Y = Y0 + H kappa``: in uniaxial crushing with ``nu_p = 0`` it equals the
volumetric compaction, the volumetric hardening of the foam's densification.

Return mapping (backward Euler). With ``d eps_p = x (3 s + (2 alpha^2 / 3) p ONE)``
(``x >= 0``, 1/Pa) the trial's deviator and mean stress shrink independently,

    q = q_tr / (1 + 6 G x),   p = p_tr / (1 + 2 K alpha^2 x),

(the deviatoric direction is the trial's) and consistency is the scalar equation
``g(x) = sigma_hat(x) (1 - 2 H c x) - Y_n = 0``, ``c = 1 + (alpha/3)^2``, monotone in ``x``
on its bracket; it is solved by the safeguarded Newton iteration of
:func:`ssw.roots.newton_bracketed`, vectorized over the yielding points.
The consistent tangent is the p-q form (:func:`ssw.constitutive.tensors.pq_tangent`) with
``J = d(p, q)/d(p_tr, q_tr)`` by implicit differentiation of ``g(x) = 0``.

References
----------
Deshpande, V. S. & Fleck, N. A. (2000). Isotropic constitutive models for metallic foams.
*J. Mech. Phys. Solids* 48, 1253-1283.
de Souza Neto, E. A., Peric, D. & Owen, D. R. J. (2008). *Computational Methods for
Plasticity*. Wiley, sec. 8.3 (implicit return on a smooth surface and its tangent).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ssw.constitutive.base import YIELD_RTOL, Update, check_stress, number_text
from ssw.constitutive.tensors import (
    ONE,
    SQRT_2_3,
    invariants,
    pq_tangent,
    stress_of,
    trial,
)
from ssw.errors import ConfigError, SolverError
from ssw.roots import newton_bracketed

#: Newton iterations of the consistency equation (quadratic convergence takes < 10).
MAX_ITER = 60
#: Relative tolerance of the consistency equation, on ``g / Y_n``.
RTOL = 1e-13


def shape_factor(plastic_poisson: float) -> float:
    """``alpha = sqrt(9 (1 - 2 nu_p) / (2 (1 + nu_p)))`` (Deshpande & Fleck 2000, eq. 2.7).

    Parameters
    ----------
    plastic_poisson : float
        Plastic Poisson's ratio ``nu_p``, in [0, 0.5].

    Returns
    -------
    float
        Shape factor ``alpha`` of the yield ellipse.

    References
    ----------
    Deshpande, V. S. and Fleck, N. A. (2000). Isotropic constitutive models for metallic
    foams. *J. Mech. Phys. Solids* 48, 1253-1283.
    """
    nu = float(plastic_poisson)
    return float(np.sqrt(9.0 * (1.0 - 2.0 * nu) / (2.0 * (1.0 + nu))))


@dataclass(frozen=True)
class CrushableFoam:
    """Deshpande-Fleck crushable foam (module docstring).

    Parameters
    ----------
    compressive_strength : float
        ``Y0`` (Pa), the uniaxial compressive plateau.
    hardening : float
        ``H = dY / d kappa`` (Pa), >= 0.
    plastic_poisson : float
        The plastic Poisson's ratio in uniaxial compression, [0, 0.5].
    """

    compressive_strength: float
    hardening: float = 0.0
    plastic_poisson: float = 0.0
    name: ClassVar[str] = "crushable-foam"

    def __post_init__(self) -> None:
        check_stress(self, "compressive_strength", "a stress > 0 Pa")
        check_stress(self, "hardening", "a hardening modulus >= 0 Pa", zero=True)
        if not 0.0 <= self.plastic_poisson <= 0.5:
            raise ConfigError("soil_model.plastic_poisson", self.plastic_poisson,
                              "a plastic Poisson's ratio in [0, 0.5]")

    @property
    def alpha(self) -> float:
        """Shape factor ``alpha`` of the yield ellipse, dimensionless
        (:func:`ssw.constitutive.crushable_foam.shape_factor`)."""
        return shape_factor(self.plastic_poisson)

    @property
    def key(self) -> str:
        """Short file-name-safe text that tells two models apart (enters the scene id)."""
        text = f"foam-Y{number_text(self.compressive_strength, 1e6)}MPa"
        if self.hardening:
            text += f"-H{number_text(self.hardening, 1e6)}MPa"
        if self.plastic_poisson:
            text += f"-nup{number_text(self.plastic_poisson)}"
        return text

    @property
    def strength(self) -> float:
        """The uniaxial compressive strength, Pa."""
        return float(self.compressive_strength)

    def params(self) -> dict[str, Any]:
        """The model's parameters as a plain dict (SI units, angles in degrees).

        Returns
        -------
        dict
            ``model`` (the registry name) and each parameter.
        """
        return {"model": self.name, "compressive_strength": self.compressive_strength,
                "hardening": self.hardening, "plastic_poisson": self.plastic_poisson}

    def equivalent(self, p: np.ndarray, q: np.ndarray) -> np.ndarray:
        """``sigma_hat`` (n,), Pa.

        ``sigma_hat = sqrt((q^2 + alpha^2 p^2) / (1 + (alpha/3)^2))`` (Deshpande & Fleck
        2000).

        Parameters
        ----------
        p : numpy.ndarray
            Mean stresses (Pa), (n,).
        q : numpy.ndarray
            Von Mises stresses (Pa), (n,).

        Returns
        -------
        numpy.ndarray
            Equivalent stress (Pa), (n,).
        """
        a2 = self.alpha ** 2
        return np.sqrt((q * q + a2 * p * p) / (1.0 + a2 / 9.0))

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
        a2, H = self.alpha ** 2, float(self.hardening)
        c = 1.0 + a2 / 9.0
        Yn = self.compressive_strength + H * state[:, 4]
        s_tr = self.equivalent(p_tr, q_tr)
        yl = s_tr - Yn > YIELD_RTOL * self.compressive_strength
        m = 6.0 * G if a2 == 0 else min(6.0 * G, 2.0 * K * a2)
        hi = np.where(yl, (s_tr / Yn - 1.0) / m, 0.0)
        if H > 0:
            hi = np.minimum(hi, 1.0 / (2.0 * H * c))

        def parts(x: np.ndarray, rows: Any = slice(None)) -> tuple[np.ndarray, ...]:
            """The shrink factors, ``p``, ``q`` and ``sigma_hat`` of the points ``rows`` at
            ``x``."""
            ap, aq = 1.0 / (1.0 + 2.0 * K * a2 * x), 1.0 / (1.0 + 6.0 * G * x)
            p, q = p_tr[rows] * ap, q_tr[rows] * aq
            sh = np.sqrt((q * q + a2 * p * p) / c)
            return ap, aq, p, q, sh

        def minus_g(x: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, Any]:
            """``-g(x)`` and ``-g'(x)`` of the points ``rows``: increasing on the bracket."""
            ap, aq, p, q, sh = parts(x, rows)
            h = 1.0 - 2.0 * H * c * x
            dsh = -(a2 * p * p * 2.0 * K * a2 * ap + q * q * 6.0 * G * aq) / (c * sh)
            return Yn[rows] - sh * h, 2.0 * H * c * sh - dsh * h, rows

        x = np.zeros_like(hi)
        rows = np.flatnonzero(yl)
        if rows.size:
            try:
                x[rows] = newton_bracketed(minus_g, 0.0, 0.0, hi[rows], rows,
                                           ftol=RTOL * Yn[rows], max_steps=MAX_ITER,
                                           x0=0.0).x
            except SolverError as exc:
                raise SolverError("the crushable-foam return mapping did not converge in "
                                  f"{MAX_ITER} iterations ({exc})") from exc
        ap, aq, p, q, sh = parts(x)
        h = 1.0 - 2.0 * H * c * x
        # implicit differentiation of g(x; p_tr, q_tr) = sh (1 - 2 H c x) - Y_n = 0
        with np.errstate(invalid="ignore", divide="ignore"):
            px, qx = -2.0 * K * a2 * p * ap, -6.0 * G * q * aq
            gp = h * a2 * p * ap / (c * sh)
            gq = h * q * aq / (c * sh)
            gx = h * (a2 * p * px + q * qx) / (c * sh) - 2.0 * H * c * sh
            xp, xq = -gp / gx, -gq / gx
        J = np.zeros((q.size, 2, 2))
        J[:, 0, 0] = np.where(yl, ap + px * xp, 1.0)
        J[:, 0, 1] = np.where(yl, px * xq, 0.0)
        J[:, 1, 0] = np.where(yl, qx * xp, 0.0)
        J[:, 1, 1] = np.where(yl, aq + qx * xq, 1.0)
        stress = stress_of(p, q, n)
        new = state.copy()
        new[:, :4] += x[:, None] * (3.0 * SQRT_2_3 * q[:, None] * n
                                    + (2.0 * a2 / 3.0) * (p[:, None] * ONE))
        new[:, 4] += 2.0 * x * c * sh
        return Update(stress, pq_tangent(K, G, n, J, np.where(yl, aq, 1.0)), new, yl,
                      yl.astype(np.int8))

    def yield_ratio(self, stress: np.ndarray, state: np.ndarray) -> np.ndarray:
        """``sigma_hat / (Y0 + H kappa)`` (n,).

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
        p, q = invariants(stress)
        return self.equivalent(p, q) / (self.compressive_strength
                                        + self.hardening * state[:, 4])
