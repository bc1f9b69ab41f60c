"""Contact constraints condensed onto their candidate dofs, with columns computed on demand
(the monolithic engine of :func:`ssw.contact.solve_curve`).

Constraint ``j`` has a gap ``g_j = g0_j + G_j x``; with ``K x = G^T lam`` the gaps are
``g = g0 + W lam``, ``W = G K^-1 G^T`` (m/N). The columns ``X = K^-1 G^T`` cost one solve
with the LU factors each. Sphere candidates (top-surface ``u_z`` dofs, sorted by radius,
``G_j = -e_{uz}``) are added lazily: the increments run with the candidates found needed
so far, and since ``x = X lam`` is known everywhere, the gaps of all other candidates are
checked after every LCP solve; violated ones (and a margin) get their columns and the
increment is solved again. The result is the LCP on the whole candidate set, exactly.
Interface pairs of the unilateral interface (``G_j = e_{uz, plate} - e_{uz, soil}``) are
all condensed from the start.
"""

from __future__ import annotations

import time

import numpy as np

from ssw.contact.petsc_solver import LUSolver

#: Sphere candidates added beyond the farthest violated one, at least (fewer re-solves;
#: a quarter of the needed count is added when that is more).
MARGIN = 6


class Condensed:
    """Condensed contact constraints (see the module docstring).

    Parameters
    ----------
    solver : ssw.contact.petsc_solver.LUSolver
        The LU factors of K.
    ndof : int
        The size of K.
    s_dofs : numpy.ndarray
        (ms,) u_z dofs of the sphere candidates, sorted by radius.
    s_r : numpy.ndarray
        (ms,) their radii, m.
    s_weight : numpy.ndarray
        (ms,) ``int N_j 2 pi r ds`` on the top surface, m^2 (pressure = lam / weight).
    i_dofs : numpy.ndarray
        (mi, 2) (plate, soil) u_z dofs of the unilateral interface pairs.
    k0 : int
        Sphere candidates condensed at the start.
    """

    def __init__(self, solver: LUSolver, ndof: int, s_dofs: np.ndarray, s_r: np.ndarray,
                 s_weight: np.ndarray, i_dofs: np.ndarray, k0: int) -> None:
        self.solver, self.ndof = solver, ndof
        self.s_dofs, self.r, self.weight = s_dofs, s_r, s_weight
        self.i_dofs = i_dofs
        self.k = 0
        self.wall = 0.0  # s spent in extend() (solves and W updates)
        self.Xs = np.zeros((ndof, 0))
        self.Xi = self._solve_interface() if len(i_dofs) else np.zeros((ndof, 0))
        self.solves = len(i_dofs)
        self.extend(k0)
        self.wall = 0.0

    def _solve_interface(self) -> np.ndarray:
        gt = np.zeros((self.ndof, len(self.i_dofs)))
        cols = np.arange(len(self.i_dofs))
        gt[self.i_dofs[:, 0], cols] += 1.0
        gt[self.i_dofs[:, 1], cols] -= 1.0
        return self.solver.solve(gt)

    @property
    def n_sphere(self) -> int:
        """Sphere candidates condensed so far (the first rows of W)."""
        return self.k

    @property
    def X(self) -> np.ndarray:
        """(ndof, m) displacements per unit constraint force, ``K^-1 G^T``."""
        return self._X

    def extend(self, k_new: int) -> None:
        """Condense the sphere candidates up to index ``k_new`` (exclusive).

        Parameters
        ----------
        k_new : int
            Number of sphere candidates to condense.
        """
        k_new = min(int(k_new), len(self.s_dofs))
        if k_new <= self.k:
            return
        t0 = time.perf_counter()
        gt = np.zeros((self.ndof, k_new - self.k))
        gt[self.s_dofs[self.k:k_new], np.arange(k_new - self.k)] = -1.0
        self.Xs = np.hstack([self.Xs, self.solver.solve(gt)])
        self.solves += k_new - self.k
        self.k = k_new
        self._build_w()
        self.wall += time.perf_counter() - t0

    def _rows(self, X: np.ndarray) -> np.ndarray:
        """``G X`` for the current constraints."""
        gs = -X[self.s_dofs[: self.k]]
        gi = X[self.i_dofs[:, 0]] - X[self.i_dofs[:, 1]]
        return np.vstack([gs, gi])

    def _build_w(self) -> None:
        self._X = np.hstack([self.Xs, self.Xi])
        self._XS = self._X[self.s_dofs]  # (ms, m) u_z of every sphere candidate
        w = self._rows(self._X)
        self.W = 0.5 * (w + w.T)

    def sphere_gap_change(self, lam: np.ndarray) -> np.ndarray:
        """(ms,) change of every sphere candidate's gap under forces ``lam`` (m).

        Parameters
        ----------
        lam : numpy.ndarray
            Constraint forces (N).

        Returns
        -------
        numpy.ndarray
            Gap changes (m), (ms,).
        """
        return -(self._XS @ lam)

    def violated(self, g0_all: np.ndarray, lam: np.ndarray, tol: float) -> int:
        """Candidates to condense so that the farthest penetrating one is included, with a
        margin (0 if none penetrates).

        Parameters
        ----------
        g0_all : numpy.ndarray
            Initial gaps of every sphere candidate (m), (ms,).
        lam : numpy.ndarray
            Constraint forces (N).
        tol : float
            Penetration tolerance (m).

        Returns
        -------
        int
            Number of candidates to condense; 0 if none penetrates.
        """
        if self.k == len(self.s_dofs):
            return 0
        rest = g0_all[self.k:] - self._XS[self.k:] @ lam
        bad = np.flatnonzero(rest < -tol)
        if len(bad) == 0:
            return 0
        need = self.k + int(bad[-1]) + 1
        return need + max(MARGIN, need // 4)
