"""Frictionless unilateral contact as a linear complementarity problem: the one LCP solver.

The gaps of the contact candidates are affine in their (non-negative) contact forces
``lam``, ``g = g0 + W lam``: ``W`` the compliance of the candidates (m/N) condensed from a
factored stiffness (``W = G K^-1 G^T``, ``G`` the gap gradients; symmetric positive
definite), or the influence coefficients of a ring discretization (a P-matrix, not
symmetric). Every contact of ssw solves the linear complementarity problem (Cottle, Pang &
Stone 1992)

    lam >= 0,   g = g0 + W lam >= 0,   lam . g = 0

with :func:`solve_lcp`: the static contact per increment (:mod:`ssw.contact.scene`), the
directional problems at the breakpoints of the exact path (:mod:`ssw.contact.parametric`),
the dynamic FEM wall per time step (:mod:`ssw.dynamics.fem_wall`) and the layered oracle's
rings (:mod:`ssw.contact.layered_lcp`). For a P-matrix the solution is unique; it is found
exactly (up to round-off) by principal pivoting on the active set, warm-started from a
guess (the previous increment's or step's set): :data:`BLOCK_PIVOTS` block updates (every
negative force out, every closed gap in), then Murty's (1974) least-index rule, one
constraint at a time, which terminates for a P-matrix.

Tolerances (one policy for every caller): a gap counts as closed below ``-tol``, an
absolute length (m) the caller sets from its problem's scale (a few ulp of its
indentations); a force counts as negative below ``-FORCE_RTOL`` times the largest force of
the solve (a force that vanishes exactly at an increment is round-off, not a reason to
leave the set: without it such a constraint cycles in and out).

The gap of the rigid sphere at a top node of radius ``r`` is the exact spherical gap
``g0 = R - sqrt(R^2 - r^2) - delta``, computed as ``r^2 / (R + sqrt(R^2 - r^2)) - delta``
(no cancellation at small ``r``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ssw.errors import SolverError

#: Block (all-at-once) pivots tried before falling back to single least-index pivots.
BLOCK_PIVOTS = 10
#: Single pivots allowed per solve after the block phase (Murty's rule terminates).
MAX_PIVOTS = 2000
#: A force below ``-FORCE_RTOL`` x the largest force of a solve counts as negative.
FORCE_RTOL = 1e-12


def sphere_gap(r: np.ndarray, radius: float, delta: float) -> np.ndarray:
    """Initial gap (m) between a rigid sphere of ``radius`` pushed by ``delta`` and a flat.

    Parameters
    ----------
    r : numpy.ndarray
        Radii (m), < ``radius``.
    radius : float
        Sphere radius (m).
    delta : float
        Indentation (m).

    Returns
    -------
    numpy.ndarray
        Gaps (m), the shape of ``r``.

    Raises
    ------
    SolverError
        If a radius is not below the sphere's.
    """
    from ssw.contact.operators import sphere_gap0

    return sphere_gap0(r, radius) - delta


def _cholesky_solve(W: np.ndarray, idx: np.ndarray, rhs: np.ndarray, cache: dict
                    ) -> np.ndarray:
    """Solve ``W[idx, idx] x = rhs`` by Cholesky, reusing the factor of the same active set
    (most increments keep the previous one)."""
    from ssw.contact.lapack import cho_solve, cholesky

    key = (W.shape[0], idx.tobytes())
    if cache.get("key") != key or cache.get("W") is not W:
        block = W[idx[:, None], idx]
        if not np.all(np.isfinite(block)):
            raise SolverError("contact compliance with non-finite entries on the active set")
        try:
            cache["cf"] = cholesky(block, lower=False, clean=False)
        except np.linalg.LinAlgError as exc:
            raise SolverError(f"contact compliance not positive definite on the active set: "
                              f"{exc}") from exc
        cache["key"], cache["W"] = key, W
    return cho_solve(cache["cf"], np.asarray(rhs, float), lower=False)


def solve_lcp(
    W: np.ndarray, g0: np.ndarray, active: np.ndarray, tol: float, cache: dict | None = None,
    *, solve_active: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Solve ``lam >= 0, g0 + W lam >= 0, complementary`` by active sets (module docstring).

    Parameters
    ----------
    W : ndarray
        (m, m) compliance (m/N), a P-matrix; symmetric positive definite unless
        ``solve_active`` is given.
    g0 : ndarray
        (m,) gaps at zero force (m).
    active : ndarray
        (m,) bool, the initial guess of the active set (warm start).
    tol : float
        Gap tolerance (m): a gap above ``-tol`` counts as open.
    cache : dict, optional
        Kept between calls with the same ``W``: the Cholesky factor of the last active
        block (default solver only).
    solve_active : callable, optional
        ``solve_active(idx, rhs) -> x`` solving ``W[idx, idx] x = rhs`` (a solver that
        knows the structure of ``W``); default: Cholesky, cached in ``cache``.

    Returns
    -------
    lam : ndarray
        (m,) contact forces, N.
    active : ndarray
        (m,) bool, the active set of the solution.
    pivots : int
        Number of active-set changes.

    Raises
    ------
    SolverError
        The pivoting did not terminate, or an active block is singular.
    """
    act = np.asarray(active, bool).copy()
    lam = np.zeros_like(g0, dtype=float)
    if solve_active is None:
        store = {} if cache is None else cache

        def solve_active(idx: np.ndarray, rhs: np.ndarray) -> np.ndarray:
            return _cholesky_solve(W, idx, rhs, store)

    for it in range(BLOCK_PIVOTS + MAX_PIVOTS):
        lam[:] = 0.0
        if act.any():
            idx = np.flatnonzero(act)
            lam[idx] = solve_active(idx, -g0[idx])
        g = g0 + W @ lam
        neg = act & (lam < -FORCE_RTOL * np.max(np.abs(lam), initial=0.0))
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

    Parameters
    ----------
    r : numpy.ndarray
        Radii of the sphere candidates (m), sorted.
    gap : numpy.ndarray
        Their gaps (m).
    active : numpy.ndarray
        Which are in contact (bool).

    Returns
    -------
    float
        Contact radius (m).

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, Cambridge University Press, eq. (3.42).
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
