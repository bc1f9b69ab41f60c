"""The contact LCP of one time step: frictionless unilateral contact on condensed candidates.

With the step's effective matrix factored, the gaps of the contact candidates are affine
in their non-negative contact forces, ``g = g0 + W lam`` with ``W`` symmetric positive
definite (the condensed compliance). The linear complementarity problem (Cottle, Pang &
Stone 1992)

    lam >= 0,   g = g0 + W lam >= 0,   lam . g = 0

has a unique solution; it is found by principal pivoting on the active set (block pivots,
then Murty's (1974) least-index single pivots, which terminate for a P-matrix), warm
started from the previous step's active set. The Cholesky factor of the active block is
kept while the active set does not change (most steps).
"""

from __future__ import annotations

import numpy as np

from ssw.errors import SolverError

#: Block (all-at-once) pivots before single least-index pivots.
BLOCK_PIVOTS = 10
#: Single pivots allowed after the block phase.
MAX_PIVOTS = 2000


class ActiveSetLCP:
    """Solver of ``lam >= 0, g0 + W lam >= 0, complementary`` for one fixed ``W``.

    Parameters
    ----------
    W : numpy.ndarray
        (m, m) symmetric positive definite compliance, m/N.
    """

    def __init__(self, W: np.ndarray) -> None:
        self.W = np.asarray(W, float)
        self._key: bytes | None = None
        self._factor = None
        self.pivots = 0

    def _solve_active(self, idx: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        from scipy.linalg import LinAlgError, cho_factor, cho_solve

        key = idx.tobytes()
        if key != self._key:
            try:
                self._factor = cho_factor(self.W[np.ix_(idx, idx)])
            except LinAlgError as exc:
                raise SolverError(f"contact compliance not positive definite: {exc}") from exc
            self._key = key
        return cho_solve(self._factor, rhs)

    def solve(self, g0: np.ndarray, active: np.ndarray, tol: float
              ) -> tuple[np.ndarray, np.ndarray]:
        """Contact forces ``lam`` (N) and the active set (bool), from the guess ``active``.

        ``tol`` (m): a gap above ``-tol`` counts as open (the round-off of the gaps).
        """
        act = np.asarray(active, bool).copy()
        lam = np.zeros_like(g0)
        for it in range(BLOCK_PIVOTS + MAX_PIVOTS):
            lam[:] = 0.0
            if act.any():
                idx = np.flatnonzero(act)
                lam[idx] = self._solve_active(idx, -g0[idx])
            g = g0 + self.W @ lam
            bad = (act & (lam < 0.0)) | (~act & (g < -tol))
            if not bad.any():
                self.pivots += it
                return lam, act
            if it < BLOCK_PIVOTS:
                act ^= bad
            else:
                k = int(np.flatnonzero(bad)[0])
                act[k] = not act[k]
        raise SolverError(
            f"the contact LCP did not converge in {BLOCK_PIVOTS + MAX_PIVOTS} active-set changes"
        )
