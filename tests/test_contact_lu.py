"""The LU kernels of the contact solvers (ssw.contact.lu) against their definitions: the
normwise backward error is the size of a perturbation that makes the solution exact
(Rigal and Gaches 1967), the checked factorization falls back to pivoting where diagonal
pivots are unstable, and the pivot-free dense LU factors every leading block."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from ssw.contact import lu as ssw_lu


def test_backward_error_is_the_size_of_an_exact_perturbation():
    """With ``eta`` the backward error of ``x``, ``dA = -eta ||A|| sign(x_j) r e_j^T /
    ||r||`` (``j`` the largest entry of ``x``) and ``db = eta ||b|| r / ||r||`` make
    ``(A + dA) x = b + db`` exact, with ``||dA|| = eta ||A||`` and ``||db|| = eta ||b||``
    (infinity norms): the perturbation the definition promises exists."""
    rng = np.random.default_rng(3)
    A = rng.normal(size=(6, 6)) + 6 * np.eye(6)
    b = rng.normal(size=6)
    x = np.linalg.solve(A, b) + 1e-6 * rng.normal(size=6)
    r = A @ x - b
    eta = ssw_lu.backward_error(A, x, r, b)
    nA, nb, nr = np.abs(A).sum(1).max(), np.abs(b).max(), np.abs(r).max()
    j = np.argmax(np.abs(x))
    dA = np.zeros_like(A)
    dA[:, j] = -eta * nA * np.sign(x[j]) * r / nr
    db = eta * nb * r / nr
    assert np.max(np.abs((A + dA) @ x - (b + db))) <= 1e-15 * nb
    assert np.abs(dA).sum(1).max() == pytest.approx(eta * nA, rel=1e-12)
    assert 1e-9 < eta < 1e-5
    # exact data: no error; a zero denominator with a residual: infinite
    assert ssw_lu.backward_error(A, np.zeros(6), np.zeros(6)) == 0.0
    assert ssw_lu.backward_error(A, np.zeros(6), np.ones(6)) == np.inf


def test_componentwise_check_accepts_a_solve_and_rejects_a_wrong_answer():
    rng = np.random.default_rng(4)
    A = rng.normal(size=(5, 5)) + 5 * np.eye(5)
    b = rng.normal(size=5)
    x = np.linalg.solve(A, b)
    assert ssw_lu.componentwise_ok(A, x, A @ x - b, b, 1e-12)
    y = x * (1 + 1e-6)
    assert not ssw_lu.componentwise_ok(A, y, A @ y - b, b, 1e-9)


def test_checked_lu_keeps_diagonal_pivots_only_where_they_are_stable():
    """A quasi-definite u-p-like matrix (SPD block, negative definite block) keeps its
    diagonal pivots (identity permutations); a tiny leading pivot (1e-20 against entries
    of 1) makes the pivot-free factors useless and the checked LU pivots. Both solve to
    the precision of a dense pivoted solve."""
    rng = np.random.default_rng(5)
    n, m = 30, 10
    B = rng.normal(size=(n, n))
    K = B @ B.T + n * np.eye(n)
    G = rng.normal(size=(m, n))
    A = np.block([[K, G.T], [G, -np.eye(m)]])
    b = rng.normal(size=n + m)
    lu = ssw_lu.checked_lu(sp.csc_array(A))
    assert np.array_equal(lu.perm_r, np.arange(n + m))
    assert np.allclose(lu.solve(b), np.linalg.solve(A, b), rtol=1e-12, atol=1e-14)
    T = np.array([[1e-20, 1.0, 0.0], [1.0, 1.0, 1.0], [0.0, 1.0, 3.0]])
    bad = ssw_lu.diagonal_lu(sp.csc_array(T))
    c = np.array([1.0, 2.0, -1.0])
    y = bad.solve(c)
    assert ssw_lu.backward_error(T, y, T @ y - c) > ssw_lu.BACKWARD_ERROR_TOL
    good = ssw_lu.checked_lu(sp.csc_array(T))
    assert not np.array_equal(good.perm_r, np.arange(3))
    assert np.allclose(good.solve(c), np.linalg.solve(T, c), rtol=1e-14)
    # an exactly zero diagonal: no factorization on it (none, or SuperLU moved a row)
    Z = sp.csc_array(np.array([[0.0, 1.0], [1.0, 0.0]]))
    z = ssw_lu.diagonal_lu(Z)
    assert z is None or not np.array_equal(z.perm_r, np.arange(2))
    assert np.allclose(ssw_lu.checked_lu(Z).solve(np.array([1.0, 2.0])), [2.0, 1.0])


@pytest.mark.parametrize("n", [20, 130])
def test_pivot_free_lu_factors_every_leading_block(n):
    """Row by row (n <= LU_BLOCK) and recursive: ``L[:j, :j] U[:j, :j] = C[:j, :j]`` for
    every ``j``, to round-off; a zero pivot stops the valid size there."""
    rng = np.random.default_rng(n)
    C = rng.normal(size=(n, n)) + n * np.eye(n)
    L, U, k = ssw_lu.lu_nopivot(C)
    assert k == n
    assert np.allclose(np.triu(L, 1), 0) and np.allclose(np.diag(L), 1)
    assert np.allclose(np.tril(U, -1), 0)
    for j in (1, n // 3, n - 1, n):
        assert np.max(np.abs(L[:j, :j] @ U[:j, :j] - C[:j, :j])) <= 1e-13 * n
    C2 = C.copy()
    C2[7, :7] = 0.0
    C2[7, 7] = 0.0
    assert ssw_lu.lu_nopivot(C2)[2] == 7
