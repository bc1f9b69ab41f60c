"""Linear elasticity as a constitutive model (no yield): the reference the others reduce to
below their yield surface."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ssw.constitutive.base import Update
from ssw.constitutive.tensors import bulk_shear, elastic_tangent


@dataclass(frozen=True)
class LinearElastic:
    """Isotropic linear elasticity: ``sigma = (K ONE ONE^T + 2 G P_DEV) eps``."""

    name: ClassVar[str] = "linear-elastic"
    #: no plastic flow, so no plastic volume change (the contact solver's mixed u-p form is
    #: exact)
    isochoric: ClassVar[bool] = True

    @property
    def key(self) -> str:
        """Short file-name-safe text that tells two models apart (enters the scene id)."""
        return "elastic"

    @property
    def strength(self) -> float:
        """Reference strength (Pa): infinite, an elastic sample never yields."""
        return float("inf")

    def params(self) -> dict[str, Any]:
        """The model's parameters as a plain dict (SI units, angles in degrees).

        Returns
        -------
        dict
            ``model`` (the registry name) and each parameter.
        """
        return {"model": self.name}

    def update(self, E: float, nu: float, strain: np.ndarray, state: np.ndarray) -> Update:
        """Stress and tangent of ``strain`` (n, 4); the state is kept.

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
            Elastic stress (Pa), elastic tangent (Pa), the state unchanged, no yield.

        Raises
        ------
        ConfigError
            If ``E`` is not > 0 or ``nu`` lies outside (-1, 0.5).
        """
        K, G = bulk_shear(E, nu)
        C = elastic_tangent(K, G)
        n = strain.shape[0]
        return Update(strain @ C, np.broadcast_to(C, (n, 4, 4)).copy(), state.copy(),
                      np.zeros(n, bool), np.zeros(n, np.int8))

    def yield_ratio(self, stress: np.ndarray, state: np.ndarray) -> np.ndarray:
        """Zero at every point: an elastic sample never yields.

        Parameters
        ----------
        stress : numpy.ndarray
            Stresses (Mandel, Pa), (n, 4).
        state : numpy.ndarray
            States, (n, 5) (column 4: the hardening variable).

        Returns
        -------
        numpy.ndarray
            Zeros, (n,).
        """
        return np.zeros(stress.shape[0])
