"""Frictionless unilateral contact, condensed onto the candidate dofs: a small LCP per increment.

With the stiffness ``K`` factored once, the gaps of the candidate constraints are affine in
their (non-negative) contact forces ``lam``: ``g = g0 + W lam`` with the compliance
``W = G K^-1 G^T`` (``G`` the gap gradients). Each increment solves the linear
complementarity problem (Cottle, Pang & Stone 1992)

    lam >= 0,   g = g0 + W lam >= 0,   lam . g = 0,

exactly (up to round-off) by an active-set (principal pivoting) method warm-started from
the previous increment's active set; ``W`` is symmetric positive definite, so the solution
is unique and the method terminates (Murty 1974's least-index rule backs up the faster block
updates). The gap of the rigid sphere at a top node of radius ``r`` is the exact spherical
gap ``g0 = R - sqrt(R^2 - r^2) - delta``, computed as ``r^2 / (R + sqrt(R^2 - r^2)) - delta``
(no cancellation at small ``r``).
"""

from __future__ import annotations

import numpy as np

from ssw.errors import SolverError

#: Block (all-at-once) pivots tried before falling back to single least-index pivots.
BLOCK_PIVOTS = 10
#: Single pivots allowed per increment after the block phase (Murty's rule terminates).
MAX_PIVOTS = 2000


def sphere_gap(r: np.ndarray, radius: float, delta: float) -> np.ndarray:
    """Initial gap (m) between a rigid sphere of ``radius`` pushed by ``delta`` and a flat."""
    from ssw.contact.operators import sphere_gap0

    return sphere_gap0(r, radius) - delta


def _active_solve(W: np.ndarray, idx: np.ndarray, rhs: np.ndarray, cache: dict) -> np.ndarray:
    """Solve ``W[idx, idx] x = rhs`` by Cholesky, reusing the factor of the same active set
    (most increments keep the previous one)."""
    from scipy.linalg import LinAlgError, cho_factor, cho_solve

    key = (W.shape[0], idx.tobytes())
    if cache.get("key") != key or cache.get("W") is not W:
        try:
            cache["cf"] = cho_factor(W[np.ix_(idx, idx)])
        except LinAlgError as exc:
            raise SolverError(f"contact compliance not positive definite on the active set: "
                              f"{exc}") from exc
        cache["key"], cache["W"] = key, W
    return cho_solve(cache["cf"], rhs)


def solve_lcp(
    W: np.ndarray, g0: np.ndarray, active: np.ndarray, tol: float, cache: dict | None = None
) -> tuple[np.ndarray, np.ndarray, int]:
    """Solve ``lam >= 0, g0 + W lam >= 0, complementary`` by active sets.

    Parameters
    ----------
    W : numpy.ndarray
        (m, m) symmetric positive definite compliance, m/N.
    g0 : numpy.ndarray
        (m,) gaps at zero force, m.
    active : numpy.ndarray
        (m,) bool, the initial guess of the active set (warm start).
    tol : float
        Gap and force-scale tolerance, m (a few ulp of the problem's lengths).
    cache : dict or None
        Kept between calls with the same ``W``: the Cholesky factor of the last active
        block.

    Returns
    -------
    lam : numpy.ndarray
        (m,) contact forces, N.
    active : numpy.ndarray
        (m,) bool, the active set.
    pivots : int
        The number of active-set changes.
    """
    act = active.copy()
    lam = np.zeros_like(g0)
    cache = {} if cache is None else cache
    for it in range(BLOCK_PIVOTS + MAX_PIVOTS):
        lam[:] = 0.0
        if act.any():
            idx = np.flatnonzero(act)
            lam[idx] = _active_solve(W, idx, -g0[idx], cache)
        g = g0 + W @ lam
        neg = act & (lam < 0.0)
        pen = ~act & (g < -tol)
        if not neg.any() and not pen.any():
            return lam, act, it
        if it < BLOCK_PIVOTS:
            act[neg] = False
            act[pen] = True
        else:  # Murty's least-index rule: flip the first infeasible constraint
            k = int(np.flatnonzero(neg | pen)[0])
            act[k] = not act[k]
    raise SolverError(
        f"the contact LCP did not converge in {BLOCK_PIVOTS + MAX_PIVOTS} active-set changes"
    )


def edge_radius(r: np.ndarray, gap: np.ndarray, active: np.ndarray) -> float:
    """Contact radius (m) from the candidate nodes on the top surface, sorted by r.

    The edge lies between the last active node and the next; near the edge of a smooth
    contact the gap opens as ``(r - a)^(3/2)`` (Johnson 1985, eq. 3.42), so ``gap^(2/3)``
    is extrapolated linearly from the two nodes beyond the last active one.
    """
    if not active.any():
        return 0.0
    k = int(np.flatnonzero(active)[-1])
    if k + 2 >= len(r):
        return float(r[k])
    s1, s2 = np.cbrt(gap[k + 1] ** 2), np.cbrt(gap[k + 2] ** 2)
    if s2 <= s1:
        return float(r[k])
    a = r[k + 1] - s1 * (r[k + 2] - r[k + 1]) / (s2 - s1)
    return float(np.clip(a, r[k], r[k + 1]))
