"""Frictionless contact of a rigid sphere on ring influence coefficients: the exact LCP.

Unknowns are the ring pressures ``p >= 0`` (Pa); at the collocation radii ``r_i`` the gap
between the sphere, pushed down by ``delta``, and the deflected surface is

    ``g = s - delta + C p >= 0``,  ``s(r) = r^2 / (R + sqrt(R^2 - r^2))``  (exact sphere),

with ``p_i g_i = 0`` (a linear complementarity problem, solved by ssw's one LCP solver,
:func:`ssw.contact.contact_lcp.solve_lcp`, warm-started from the previous active set, with
its tolerance policy). Its solution on an active set ``A`` (the rings in contact) is
linear in ``delta``: ``p_A = delta u - v`` with ``C_AA u = 1`` and ``C_AA v = s_A``; the
gap is ``g = g0 + delta g1``. So the active set is found once and every increment up to
the first ``delta`` at which a pressure or a gap changes sign is filled at once.

Active sets are almost always the leading rings ``0..k-1``; their systems are the leading
blocks of ``C``, solved from one LU factorization without pivoting of ``C`` (the leading
blocks of ``L U`` are the LU factors of the leading blocks of ``C``,
:func:`ssw.contact.lu.lu_nopivot`; LAPACK's pivoted ``getrf`` loses that property):
``O(k^2)`` each, checked by their componentwise backward error (a general solve otherwise).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ssw.contact.contact_lcp import solve_lcp
from ssw.contact.lu import componentwise_ok, lu_nopivot
from ssw.contact.retained import sphere_gap0
from ssw.errors import SolverError

#: Gap tolerance, relative to the largest indentation of the curve.
GAP_TOL = 1e-11
#: Componentwise backward error (:func:`ssw.contact.lu.componentwise_ok`) above which a
#: leading-block solve is redone by a pivoted solve.
RESIDUAL_TOL = 1e-9


class ZoneError(SolverError):
    """The contact reached the outermost rings: the candidate zone is too small."""


@dataclass
class LcpResult:
    """Force (N), contact radius (m), the pressures (Pa) of chosen increments and counts.

    Parameters
    ----------
    force : numpy.ndarray
        Force per increment (N).
    contact_radius : numpy.ndarray
        Contact radius per increment (m).
    profiles : dict
        Pressure profiles of chosen increments (Pa), by increment.
    active_sets : int
        Number of active sets visited.
    iterations : int
        Number of LCP iterations.
    general_solves : int
        Number of general solves.
    max_ring : int
        Outermost active ring.
    """

    force: NDArray[np.float64]
    contact_radius: NDArray[np.float64]
    profiles: dict[int, NDArray[np.float64]] = field(default_factory=dict)
    active_sets: int = 0
    iterations: int = 0
    general_solves: int = 0
    max_ring: int = 0


def sphere_surface(r: NDArray, radius: float) -> NDArray[np.float64]:
    """Height (m) of a sphere of ``radius`` above its lowest point at radius ``r`` (m):
    the gap at zero indentation of the contact operators
    (:func:`ssw.contact.retained.sphere_gap0`, ``r^2 / (R + sqrt((R - r)(R + r)))``).

    Parameters
    ----------
    r : numpy.ndarray
        Radii (m), < ``radius``.
    radius : float
        Sphere radius (m).

    Returns
    -------
    numpy.ndarray
        Heights (m).

    Raises
    ------
    SolverError
        If a radius is not below the sphere's.
    """
    return sphere_gap0(r, radius)


class _ActiveSolver:
    """``C_AA^{-1} b`` for active sets A, from the LU of the leading blocks."""

    def __init__(self, C: NDArray, s: NDArray) -> None:
        from scipy.linalg import solve_triangular

        self.C, self.rhs = C, np.stack([np.ones_like(s), s], axis=1)
        self.L, U, self.valid = lu_nopivot(C)
        k = self.valid
        # the leading blocks of U^-1 are the inverses of U's leading blocks
        self.U_inv = solve_triangular(U[:k, :k], np.eye(k), lower=False)
        self.general = 0

    def solve_rhs(self, idx: NDArray, rhs: NDArray) -> NDArray:
        """``x`` with ``C[idx, idx] x = rhs`` (``rhs`` (k,) or (k, r)): the leading factors
        when ``idx`` are the leading rings ``0..k-1`` (checked by the residual), a pivoted
        solve otherwise."""
        from scipy.linalg import solve_triangular

        k = idx.size
        if k == 0:
            return np.zeros(rhs.shape)
        if idx[-1] == k - 1 and k <= self.valid:  # the leading rings 0..k-1
            y = solve_triangular(self.L[:k, :k], rhs, lower=True, unit_diagonal=True)
            x = self.U_inv[:k, :k] @ y
            Ck = self.C[:k, :k]
            if componentwise_ok(Ck, x, Ck @ x - rhs, rhs, RESIDUAL_TOL):
                return x
        self.general += 1
        try:
            return np.linalg.solve(self.C[np.ix_(idx, idx)], rhs)
        except np.linalg.LinAlgError as exc:
            raise SolverError(f"singular contact system on {k} rings ({exc})") from exc

    def solve(self, idx: NDArray) -> NDArray:
        """``C_AA^{-1} [1, s_A]`` (k, 2) on the rings ``idx``."""
        return self.solve_rhs(idx, self.rhs[idx])


def solve_sphere(C: NDArray, points: NDArray, areas: NDArray, radius: float,
                 deltas: NDArray, keep: NDArray | None = None) -> LcpResult:
    """Force-indentation curve of a rigid frictionless sphere on the influence matrix.

    Parameters
    ----------
    C : numpy.ndarray
        (n, n) influence coefficients, m/Pa, at the ring midpoints ``points``.
    points : numpy.ndarray
        (n,) the ring midpoints' radii, m.
    areas : numpy.ndarray
        (n,) ring areas, m^2: the force is ``areas @ p``.
    radius : float
        The sphere's radius, m.
    deltas : numpy.ndarray
        (m,) increasing indentations, m.
    keep : numpy.ndarray or None
        Increments whose pressure profile is returned.

    Returns
    -------
    LcpResult
        The curve and the kept pressure profiles.

    Raises
    ------
    ZoneError
        The contact reaches the last rings (the candidate zone is too small).
    ssw.errors.SolverError
        The active-set iteration does not converge.
    """
    n = len(points)
    s = sphere_surface(points, radius)
    solver = _ActiveSolver(C, s)
    deltas = np.asarray(deltas, float)
    tol = GAP_TOL * float(deltas[-1])
    keep_set = set() if keep is None else {int(k) for k in keep}
    out = LcpResult(np.zeros(deltas.size), np.zeros(deltas.size))
    active = np.zeros(n, dtype=bool)
    i = 0
    while i < deltas.size:
        d = deltas[i]
        active, u, v, g0, g1 = _active_set(solver, s, active, d, tol, out)
        idx = np.flatnonzero(active)
        out.active_sets += 1
        # the set stays the solution while p_A = delta u - v >= 0 and g = g0 + delta g1 >= -tol
        with np.errstate(divide="ignore", invalid="ignore"):
            lim_p = np.where(u < 0, v / u, np.inf)
            lim_g = np.where(~active & (g1 < 0), (-tol - g0) / g1, np.inf)
        d_hi = min(lim_p.min(initial=np.inf), lim_g.min(initial=np.inf))
        j = max(int(np.searchsorted(deltas, d_hi, side="right")), i + 1)
        seg = deltas[i:j]
        out.force[i:j] = seg * (areas[idx] @ u) - areas[idx] @ v
        if idx.size:
            k = int(idx[-1])
            out.max_ring = max(out.max_ring, k)
            if k >= n - 3:
                raise ZoneError(f"the contact reached ring {k} of {n} (r = {points[k]:.4g} m):"
                                " raise the candidate zone")
            out.contact_radius[i:j] = _edge_radius(points, g0, g1, k, seg)
        for m in keep_set.intersection(range(i, j)):
            p = np.zeros(n)
            p[idx] = deltas[m] * u - v
            out.profiles[m] = p
        i = j
    out.general_solves = solver.general
    return out


def _active_set(solver: _ActiveSolver, s: NDArray, active: NDArray, d: float, tol: float,
                out: LcpResult) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
    """The active set at indentation ``d`` from the guess ``active`` (the LCP of the
    module docstring), with ``u, v`` on it and the gap coefficients ``g0, g1`` on all
    rings."""
    _, active, pivots = solve_lcp(solver.C, s - d, active, tol, solve_active=solver.solve_rhs)
    out.iterations += pivots + 1
    idx = np.flatnonzero(active)
    uv = solver.solve(idx)
    u, v = uv[:, 0], uv[:, 1]
    C = solver.C
    cols = C[:, :idx.size] if idx.size == 0 or idx[-1] == idx.size - 1 else C[:, idx]
    return active, u, v, s - cols @ v, cols @ u - 1.0


def _edge_radius(points: NDArray, g0: NDArray, g1: NDArray, k: int,
                 seg: NDArray) -> NDArray[np.float64]:
    """Contact radius (m) for the indentations ``seg`` with last active ring ``k``: the
    gap opens as ``(r - a)^(3/2)`` at a smooth edge (Johnson 1985, eq. 3.42), so
    ``g^(2/3)`` is extrapolated linearly to zero from the next two collocation radii,
    and kept between the last active and the first inactive radius."""
    ga = np.clip(g0[k + 1] + seg * g1[k + 1], 0.0, None) ** (2.0 / 3.0)
    gb = np.clip(g0[k + 2] + seg * g1[k + 2], 0.0, None) ** (2.0 / 3.0)
    r1, r2 = points[k + 1], points[k + 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(gb > ga, r1 - ga * (r2 - r1) / (gb - ga), points[k])
    return np.clip(a, points[k], r1)
