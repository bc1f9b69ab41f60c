"""The Taylor test of a constitutive model's consistent tangent, shared by the model tests:
the remainders of a strain-driven update along a direction, over halving steps."""

from __future__ import annotations

from typing import Any

import numpy as np

#: The steps of the Taylor test (halving from 1e-3 of the strain direction's scale).
STEPS = 1e-3 * 0.5 ** np.arange(5)


def remainders(model: Any, E: float, nu: float, strain: np.ndarray, state: np.ndarray,
               d: np.ndarray) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray]:
    """``(base, r1, r2, same)``: the update at ``strain``; per step ``h`` of :data:`STEPS`
    and point, ``r1 = |sigma(e + h d) - sigma(e)|`` and ``r2 = |... - h D d|`` (arrays
    (steps, n)); ``same`` (n,) the points whose return region stays that of ``base`` at
    every step (the others cross a kink of the return)."""
    base = model.update(E, nu, strain, state)
    r1, r2, same = [], [], np.ones(len(strain), bool)
    for h in STEPS:
        up = model.update(E, nu, strain + h * d, state)
        same &= up.region == base.region
        diff = up.stress - base.stress
        r1.append(np.linalg.norm(diff, axis=1))
        r2.append(np.linalg.norm(diff - h * np.einsum("nij,nj->ni", base.tangent, d), axis=1))
    return base, np.array(r1), np.array(r2), same


def rates(r1: np.ndarray, r2: np.ndarray, sel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The observed orders ``log2`` of the ratios of successive remainders at the points
    ``sel``: ``(rate1, rate2)`` of ``r1`` (1 expected) and ``r2`` (2 expected)."""
    return (np.log2(r1[:-1, sel] / r1[1:, sel]), np.log2(r2[:-1, sel] / r2[1:, sel]))
