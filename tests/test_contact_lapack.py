"""The contact path's direct LAPACK calls (ssw.contact.lapack) give scipy.linalg's numbers
bit for bit: the front ends they replace call the same routines with the same arguments."""

import numpy as np
import pytest
from scipy.linalg import cho_factor, cho_solve, cholesky, solve_triangular

from ssw.contact import lapack


def _spd(n: int, seed: int) -> np.ndarray:
    a = np.random.default_rng(seed).normal(size=(n, n))
    return a @ a.T + n * np.eye(n)


@pytest.mark.parametrize("n", [1, 3, 17])
def test_same_numbers_as_scipy(n):
    W = _spd(n, n)
    b = np.random.default_rng(1).normal(size=(n, 2))
    for lower in (True, False):
        assert np.array_equal(lapack.cholesky(W, lower=lower),
                              cholesky(W, lower=lower, check_finite=False))
        cf = cho_factor(W, lower=lower)
        c = lapack.cholesky(W, lower=lower, clean=False)
        assert np.array_equal(c, cf[0])
        assert np.array_equal(lapack.cho_solve(c, b, lower=lower), cho_solve(cf, b))
    L = cholesky(W, lower=True)
    # C-ordered, Fortran-ordered and strided (a leading block) triangles
    for a, lower in ((L, True), (L.T, False), (np.asfortranarray(L), True),
                     (L[: max(n - 1, 1), : max(n - 1, 1)], True)):
        rhs = b[: a.shape[0]]
        assert np.array_equal(lapack.triangular_solve(a, rhs, lower=lower),
                              solve_triangular(a, rhs, lower=lower, check_finite=False))


def test_errors():
    with pytest.raises(np.linalg.LinAlgError):
        lapack.cholesky(-np.eye(2), lower=True)
    with pytest.raises(np.linalg.LinAlgError):
        lapack.triangular_solve(np.zeros((2, 2)), np.ones(2), lower=True)
