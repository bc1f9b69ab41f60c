"""LU factorizations of the contact solvers, with their fallbacks and backward errors.

One place for the LU kernels of :mod:`ssw.contact`:

* **sparse, diagonal pivots** (:func:`diagonal_lu`): SuperLU in a given column order with
  ``diag_pivot_thresh = 0`` and SymmetricMode, the symmetric structure's fill, for the
  symmetric quasi-definite u-p matrices of the FEM bodies (SPD displacement block,
  negative definite pressure block: every order is stable in exact arithmetic, Vanderbei
  1995, but not every order in floating point); ``None`` when a pivot is exactly zero;
* **sparse, threshold-pivoted** (:func:`pivoted_lu`): SuperLU in the COLAMD column order
  with partial pivoting, the stable fallback;
* **checked** (:func:`checked_lu`): the diagonal-pivot factorization when its backward
  error on a probe vector is at most :data:`BACKWARD_ERROR_TOL`, else the pivoted one;
* **backward errors**: normwise (:func:`backward_error`, Rigal and Gaches 1967) and
  componentwise (:func:`componentwise_ok`, Oettli and Prager 1964);
* **dense, no pivoting** (:func:`lu_nopivot`): the factors whose leading blocks factor the
  matrix's leading blocks, which the ring LCP's active sets are
  (:mod:`ssw.contact.layered_lcp`). LAPACK's ``getrf`` pivots rows, which breaks that
  property; a pivot-free LU has no library routine in scipy, so it is written here.

References
----------
Rigal, J. L. and Gaches, J. (1967). On the compatibility of a given solution with the data
of a linear system. J. ACM 14(3), 543-548. Oettli, W. and Prager, W. (1964). Compatibility
of approximate solution of linear equations with given error bounds for coefficients and
right-hand sides. Numer. Math. 6, 405-409. Vanderbei, R. J. (1995). Symmetric
quasidefinite matrices. SIAM J. Optim. 5(1), 100-113. Li, X. S. (2005). An overview of
SuperLU. ACM TOMS 31(3), 302-325. Higham, N. J. (2002). *Accuracy and Stability of
Numerical Algorithms*, 2nd ed., SIAM, secs. 7.1 and 9.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: Largest normwise backward error accepted from a diagonal-pivot factorization (machine
#: epsilon is 2.2e-16; measured on the thesis meshes: 1e-17 to 1e-16).
BACKWARD_ERROR_TOL = 1e-11
#: Seed of the backward-error probe vector (any fixed seed: deterministic).
PROBE_SEED = 20241130
#: Leading-block size below which :func:`lu_nopivot` eliminates row by row.
LU_BLOCK = 48


def probe(n: int) -> np.ndarray:
    """The probe vector of a backward-error check: (n,) uniform in [-1, 1], seeded with
    :data:`PROBE_SEED`.

    Parameters
    ----------
    n : int
        Its length.

    Returns
    -------
    numpy.ndarray
        (n,) dimensionless.
    """
    return np.random.default_rng(PROBE_SEED).uniform(-1.0, 1.0, n)


def inf_norm(A: Any) -> float:
    """``||A||_inf``, the largest row sum of ``|A|`` (dense or scipy sparse).

    Parameters
    ----------
    A : numpy.ndarray or scipy.sparse matrix
        (m, n).

    Returns
    -------
    float
        In ``A``'s unit.
    """
    return float(np.max(abs(A).sum(axis=1)))


def backward_error(A: Any, x: np.ndarray, residual: np.ndarray,
                   rhs: np.ndarray | None = None) -> float:
    """Normwise backward error of ``x`` as a solution of ``A x = b``.

    Parameters
    ----------
    A : numpy.ndarray or scipy.sparse matrix
        (n, n) the matrix.
    x : numpy.ndarray
        (n,) or (n, k) the computed solution.
    residual : numpy.ndarray
        ``A x - b`` (the caller's, or ``A x - L U x`` for a factorization's own error).
    rhs : numpy.ndarray or None
        ``b``; None: its term is left out (a factorization's error, or a bound that
        errs on the large side).

    Returns
    -------
    float
        ``max|r| / (||A||_inf max|x| + max|b|)`` (Rigal and Gaches 1967; Higham 2002,
        thm. 7.1, in the infinity norm); 0 for a zero residual over a zero denominator,
        infinity for a non-zero one (or a non-finite ``x``).
    """
    denom = inf_norm(A) * float(np.max(np.abs(x)))
    if rhs is not None:
        denom += float(np.max(np.abs(rhs)))
    top = float(np.max(np.abs(residual)))
    if denom > 0:
        return top / denom
    return 0.0 if top == 0 else float("inf")


def componentwise_ok(A: np.ndarray, x: np.ndarray, residual: np.ndarray, rhs: np.ndarray,
                     tol: float) -> bool:
    """Whether ``x`` solves ``A x = b`` to the componentwise backward error ``tol``:
    ``|r| <= tol (|A| |x| + |b|)`` in every row (Oettli and Prager 1964).

    Parameters
    ----------
    A : numpy.ndarray
        (n, n) dense.
    x : numpy.ndarray
        (n,) or (n, k).
    residual : numpy.ndarray
        ``A x - b``.
    rhs : numpy.ndarray
        ``b``.
    tol : float
        Relative tolerance (dimensionless).

    Returns
    -------
    bool
    """
    scale = np.abs(A) @ np.abs(x) + np.abs(rhs)
    return bool(np.all(np.abs(residual) <= tol * scale))


def diagonal_lu(A: Any, permc_spec: str = "NATURAL") -> Any | None:
    """SuperLU of ``A`` with its diagonal pivots, in the column order ``permc_spec``
    (``NATURAL``: ``A``'s own; ``MMD_AT_PLUS_A``: minimum degree of ``A + A^T``).

    Parameters
    ----------
    A : scipy.sparse matrix
        (n, n), CSC preferred.
    permc_spec : str
        SuperLU's column ordering.

    Returns
    -------
    scipy.sparse.linalg.SuperLU or None
        The factors (SymmetricMode: the row order is the column order unless a pivot
        failed the test), or None when SuperLU met an exactly zero pivot.
    """
    from scipy.sparse.linalg import splu

    try:
        return splu(A, permc_spec=permc_spec, diag_pivot_thresh=0.0,
                    options={"SymmetricMode": True})
    except RuntimeError:  # "Factor is exactly singular"
        return None


def pivoted_lu(A: Any) -> Any:
    """SuperLU of ``A`` with partial pivoting (threshold 1) in the COLAMD column order: the
    stable fallback.

    Parameters
    ----------
    A : scipy.sparse matrix
        (n, n), CSC preferred.

    Returns
    -------
    scipy.sparse.linalg.SuperLU
        The factors.
    """
    from scipy.sparse.linalg import splu

    return splu(A, permc_spec="COLAMD", diag_pivot_thresh=1.0)


def checked_lu(A: Any, tol: float | None = None) -> Any:
    """The diagonal-pivot SuperLU of ``A`` in its own order (:func:`diagonal_lu`) when its
    solve of the probe (:func:`probe`) has a backward error (:func:`backward_error`, the
    ``b`` term left out: on the large side) at most ``tol``; else :func:`pivoted_lu`.

    Parameters
    ----------
    A : scipy.sparse matrix
        (n, n) CSC.
    tol : float or None
        Largest backward error accepted; None: :data:`BACKWARD_ERROR_TOL`.

    Returns
    -------
    scipy.sparse.linalg.SuperLU
        The factors.
    """
    tol = BACKWARD_ERROR_TOL if tol is None else tol
    lu = diagonal_lu(A)
    if lu is not None:
        b = probe(A.shape[0])
        y = lu.solve(b)
        if backward_error(A, y, A @ y - b) <= tol:
            return lu
    return pivoted_lu(A)


def lu_nopivot(C: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """``C = L U`` without pivoting (``L`` unit lower, ``U`` upper), dense, and the size of
    the largest leading block the factors are valid for (a pivot below ``1e-14`` of its
    row's largest entry stops them).

    Parameters
    ----------
    C : numpy.ndarray
        (n, n).

    Returns
    -------
    tuple
        ``(L, U, k)``: (n, n), (n, n) and the valid leading size ``k <= n``; the leading
        ``j x j`` blocks of ``L`` and ``U`` factor ``C[:j, :j]`` for every ``j <= k``.

    Notes
    -----
    Recursive: the leading half, its off-diagonal blocks by triangular solves, the
    trailing Schur complement (Higham 2002, sec. 9.5: block LU); rows eliminated one by
    one below :data:`LU_BLOCK`. Without pivoting, LU exists and is stable for a matrix
    with dominant or positive definite leading blocks (Higham 2002, sec. 9.3); the
    callers check each solve's residual and solve again with pivoting otherwise.
    """
    from scipy.linalg import solve_triangular

    n = C.shape[0]
    L, U = np.eye(n), np.zeros((n, n))
    if n <= LU_BLOCK:
        for i in range(n):
            U[i, i:] = C[i, i:] - L[i, :i] @ U[:i, i:]
            if not abs(U[i, i]) > 1e-14 * np.abs(C[i]).max():
                return L, U, i
            L[i + 1:, i] = (C[i + 1:, i] - L[i + 1:, :i] @ U[:i, i]) / U[i, i]
        return L, U, n
    k = n // 2
    L11, U11, ok = lu_nopivot(C[:k, :k])
    L[:k, :k], U[:k, :k] = L11, U11
    if ok < k:
        return L, U, ok
    U[:k, k:] = solve_triangular(L11, C[:k, k:], lower=True, unit_diagonal=True)
    L[k:, :k] = solve_triangular(U11, C[k:, :k].T, trans="T", lower=False).T
    L22, U22, ok2 = lu_nopivot(C[k:, k:] - L[k:, :k] @ U[:k, k:])
    L[k:, k:], U[k:, k:] = L22, U22
    return L, U, k + ok2
