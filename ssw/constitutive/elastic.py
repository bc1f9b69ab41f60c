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
        return "elastic"

    @property
    def strength(self) -> float:
        return float("inf")

    def params(self) -> dict[str, Any]:
        return {"model": self.name}

    def update(self, E: float, nu: float, strain: np.ndarray, state: np.ndarray) -> Update:
        """Stress and tangent of ``strain`` (n, 4); the state is kept."""
        K, G = bulk_shear(E, nu)
        C = elastic_tangent(K, G)
        n = strain.shape[0]
        return Update(strain @ C, np.broadcast_to(C, (n, 4, 4)).copy(), state.copy(),
                      np.zeros(n, bool), np.zeros(n, np.int8))

    def yield_ratio(self, stress: np.ndarray, state: np.ndarray) -> np.ndarray:
        return np.zeros(stress.shape[0])
