"""Dense LAPACK calls of the contact path without scipy's per-call validation.

The parametric path (:mod:`ssw.contact.parametric`) and the active-set LCP
(:mod:`ssw.contact.contact_lcp`) solve tens of thousands of small dense systems per curve;
``scipy.linalg``'s front ends validate every call (array conversion, dtype and finiteness
checks) at a cost larger than the solves themselves. These functions call the same LAPACK
routines (``potrf``, ``potrs``, ``trtrs``) exactly as those front ends call them, so they
return the same numbers, bit for bit (tests/test_contact_lapack.py); only the validation
is left out (the callers' matrices are finite by construction: compliances of condensed
FEM operators).

References
----------
Anderson, E. et al. (1999). *LAPACK Users' Guide*, 3rd ed., SIAM (xPOTRF, xPOTRS, xTRTRS).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import LinAlgError, get_lapack_funcs

#: LAPACK's routines for float64.
_POTRF, _POTRS, _TRTRS = get_lapack_funcs(("potrf", "potrs", "trtrs"), (np.zeros((1, 1)),))


def cholesky(a: np.ndarray, lower: bool, clean: bool = True) -> np.ndarray:
    """The Cholesky factor of ``a``: ``scipy.linalg.cholesky(a, lower=lower,
    check_finite=False)`` (``clean``), or the factor of ``scipy.linalg.cho_factor(a,
    lower=lower)`` (``clean=False``: the other triangle keeps ``a``'s entries).

    Parameters
    ----------
    a : numpy.ndarray
        (n, n) symmetric, finite, n >= 1.
    lower : bool
        The lower factor ``L`` (``a = L L^T``), else the upper ``U`` (``a = U^T U``).
    clean : bool
        Zero the other triangle.

    Returns
    -------
    numpy.ndarray
        (n, n) the factor.

    Raises
    ------
    numpy.linalg.LinAlgError
        ``a`` is not positive definite.
    """
    c, info = _POTRF(a, lower=lower, overwrite_a=False, clean=clean)
    if info > 0:
        raise LinAlgError(f"{info}-th leading minor of the array is not positive definite")
    if info < 0:
        raise ValueError(f"illegal value in argument {-info} of LAPACK potrf")
    return c


def cho_solve(c: np.ndarray, b: np.ndarray, lower: bool) -> np.ndarray:
    """``scipy.linalg.cho_solve((c, lower), b, check_finite=False)``.

    Parameters
    ----------
    c : numpy.ndarray
        (n, n) a factor from :func:`cholesky`.
    b : numpy.ndarray
        (n,) or (n, k), not empty.
    lower : bool
        ``c`` is the lower factor.

    Returns
    -------
    numpy.ndarray
        ``x`` with ``(c c^T) x = b`` (lower) or ``(c^T c) x = b``, the shape of ``b``.
    """
    x, info = _POTRS(c, b, lower=lower, overwrite_b=False)
    if info != 0:
        raise ValueError(f"illegal value in argument {-info} of LAPACK potrs")
    return x


def triangular_solve(a: np.ndarray, b: np.ndarray, lower: bool) -> np.ndarray:
    """``scipy.linalg.solve_triangular(a, b, lower=lower, check_finite=False)``: ``trtrs``
    on ``a`` in Fortran order, or on its transpose (as scipy solves a C-ordered ``a``).

    Parameters
    ----------
    a : numpy.ndarray
        (n, n) triangular, finite.
    b : numpy.ndarray
        (n,) or (n, k), finite, not empty.
    lower : bool
        ``a`` is lower triangular.

    Returns
    -------
    numpy.ndarray
        ``x`` with ``a x = b``, the shape of ``b``.

    Raises
    ------
    numpy.linalg.LinAlgError
        ``a`` is singular.
    """
    if a.flags.f_contiguous:
        x, info = _TRTRS(a, b, lower=lower, trans=0)
    else:
        x, info = _TRTRS(a.T, b, lower=not lower, trans=1)
    if info > 0:
        raise LinAlgError(f"singular matrix: resolution failed at diagonal {info - 1}")
    if info < 0:
        raise ValueError(f"illegal value in argument {-info} of LAPACK trtrs")
    return x
