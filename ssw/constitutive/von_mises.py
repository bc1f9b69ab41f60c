"""von Mises (J2) plasticity with linear isotropic hardening: the radial return.

Yield function ``f = q - (Y + H kappa)``, ``q = sqrt(3/2) |s|`` the von Mises stress,
``kappa`` the accumulated equivalent plastic strain; associated (Prandtl-Reuss) flow
``d eps_p = d lambda sqrt(3/2) n``, ``d kappa = d lambda``. Plastic flow is isochoric, so
the mean stress is elastic, ``p = p_tr``.

Return mapping (backward Euler, closed form; Wilkins 1964, Krieg & Key 1976; Simo &
Hughes 1998, Box 3.2): with the trial ``q_tr`` above ``Y_n = Y + H kappa_n``,

    d lambda = (q_tr - Y_n) / (3 G + H),   q = q_tr - 3 G d lambda,

and the consistent tangent (Simo & Taylor 1985) is the p-q form of
:func:`ssw.constitutive.tensors.pq_tangent` with ``dq/dq_tr = H / (3 G + H)`` and the
deviatoric shrink ``q / q_tr``.

References
----------
Simo, J. C. & Hughes, T. J. R. (1998). *Computational Inelasticity*. Springer.
Simo, J. C. & Taylor, R. L. (1985). *Comput. Methods Appl. Mech. Eng.* 48, 101-118.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ssw.constitutive.base import YIELD_RTOL, Update, check_stress, number_text
from ssw.constitutive.tensors import SQRT_3_2, invariants, pq_tangent, stress_of, trial


@dataclass(frozen=True)
class VonMises:
    """von Mises plasticity: uniaxial yield stress ``yield_stress`` (Pa) and linear
    isotropic hardening modulus ``hardening`` (Pa, ``dY / d kappa``; 0: perfectly
    plastic).

    Parameters
    ----------
    yield_stress : float
        Uniaxial yield stress (Pa).
    hardening : float
        Linear isotropic hardening modulus ``dY / d kappa`` (Pa); 0: perfectly plastic.
    """

    yield_stress: float
    hardening: float = 0.0
    name: ClassVar[str] = "von-mises"
    #: plastic flow keeps the volume (the contact solver's mixed u-p form is then exact)
    isochoric: ClassVar[bool] = True

    def __post_init__(self) -> None:
        check_stress(self, "yield_stress", "a stress > 0 Pa")
        check_stress(self, "hardening", "a hardening modulus >= 0 Pa", zero=True)

    @property
    def key(self) -> str:
        """Short file-name-safe text that tells two models apart (enters the scene id)."""
        text = f"vm-Y{number_text(self.yield_stress, 1e6)}MPa"
        if self.hardening:
            text += f"-H{number_text(self.hardening, 1e6)}MPa"
        return text

    @property
    def strength(self) -> float:
        """The uniaxial yield stress, Pa."""
        return float(self.yield_stress)

    def params(self) -> dict[str, Any]:
        """The model's parameters as a plain dict (SI units, angles in degrees).

        Returns
        -------
        dict
            ``model`` (the registry name) and each parameter.
        """
        return {"model": self.name, "yield_stress": self.yield_stress,
                "hardening": self.hardening}

    def update(self, E: float, nu: float, strain: np.ndarray, state: np.ndarray) -> Update:
        """Radial return of ``strain`` (n, 4) from ``state`` (n, 5) (module docstring).

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
        H = float(self.hardening)
        Yn = self.yield_stress + H * state[:, 4]
        f = q_tr - Yn
        yl = f > YIELD_RTOL * self.yield_stress
        dlam = np.where(yl, f / (3.0 * G + H), 0.0)
        q = q_tr - 3.0 * G * dlam
        new = state.copy()
        new[:, :4] += (SQRT_3_2 * dlam)[:, None] * n
        new[:, 4] += dlam
        J = np.zeros((q.size, 2, 2))
        J[:, 0, 0] = 1.0
        J[:, 1, 1] = np.where(yl, H / (3.0 * G + H), 1.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.where(yl, q / q_tr, 1.0)
        return Update(stress_of(p_tr, q, n), pq_tangent(K, G, n, J, ratio), new, yl,
                      yl.astype(np.int8))

    def yield_ratio(self, stress: np.ndarray, state: np.ndarray) -> np.ndarray:
        """``q / (Y + H kappa)`` (n,).

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
        _, q = invariants(stress)
        return q / (self.yield_stress + self.hardening * state[:, 4])
