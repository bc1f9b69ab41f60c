"""The one PETSc LU wrapper (ssw.contact.petsc_solver.LUSolver) against dense LAPACK solves
(numpy.linalg.solve, an independent solver) on saddle-point matrices of the u-p kind."""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ssw.contact.petsc_solver import (
    BACKWARD_ERROR_TOL,
    SOLVERS,
    LUSolver,
    available_solvers,
    backward_error,
)
from ssw.errors import ConfigError, SolverError


def saddle_point(nu: int = 40, np_: int = 12, seed: int = 1) -> np.ndarray:
    """``[[K, B^T], [B, -C]]``, K and C symmetric positive definite: quasi-definite, so LU
    in the natural order (displacements first) meets no zero pivot (Vanderbei 1995)."""
    rng = np.random.default_rng(seed)
    G = rng.standard_normal((nu, nu))
    K = G @ G.T + nu * np.eye(nu)
    B = rng.standard_normal((np_, nu))
    H = rng.standard_normal((np_, np_))
    C = 0.1 * (H @ H.T) + np.eye(np_)
    return np.block([[K, B.T], [B, -C]])


def coo(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r, c = np.nonzero(A)
    return r, c, A[r, c]


CHOICES = [(s, "natural" if s == "petsc" else None) for s in SOLVERS] + [
    ("petsc", "nd"), ("auto", "natural")]


@pytest.mark.parametrize(("solver", "ordering"), CHOICES)
def test_single_and_block_solves_match_lapack(solver, ordering):
    if solver != "auto" and solver not in available_solvers():
        if importlib.util.find_spec("dolfinx_solver") is not None:
            pytest.fail(f"the binary PETSc stack lacks {solver}")
        pytest.skip(f"this PETSc build has no {solver} (the source route's default build)")
    A = saddle_point()
    n, scale = A.shape[0], 2.0**20
    rng = np.random.default_rng(2)
    b, B = rng.standard_normal(n), rng.standard_normal((n, 5))
    lu = LUSolver(*coo(A), n, scale, solver=solver, ordering=ordering, parallel=False)
    try:
        x = lu.solve(b)
        X = lu.solve(B)
        Ax = lu.matvec(x)
    finally:
        lu.destroy()
    assert x.shape == (n,) and X.shape == (n, 5)
    np.testing.assert_allclose(x, np.linalg.solve(scale * A, b), rtol=1e-10, atol=0)
    np.testing.assert_allclose(X, np.linalg.solve(scale * A, B), rtol=1e-10, atol=0)
    np.testing.assert_allclose(Ax, b, rtol=1e-9, atol=1e-12)
    assert lu.backward_error is not None and lu.backward_error <= BACKWARD_ERROR_TOL
    if solver == "auto":
        assert lu.solver == ("mumps" if "mumps" in available_solvers() else "petsc")


def test_duplicate_triplets_are_summed_and_the_world_mode_is_the_serial_one():
    A = saddle_point(20, 6)
    r, c, v = coo(A)
    # the same matrix as two halves of every entry
    rows, cols, vals = np.concatenate([r, r]), np.concatenate([c, c]), np.concatenate([v, v]) / 2
    b = np.arange(A.shape[0], dtype=float)
    out = []
    for parallel in (True, False):
        lu = LUSolver(rows, cols, vals, A.shape[0], parallel=parallel)
        out.append(lu.solve(b))
        lu.destroy()
    np.testing.assert_allclose(out[0], np.linalg.solve(A, b), rtol=1e-10)
    np.testing.assert_array_equal(out[0], out[1])


def test_zero_pivot_natural_order_fails_and_a_pivoting_package_solves_it():
    """[[0, 1], [1, 0]]: no LU without pivoting exists; MUMPS pivots."""
    A = np.array([[0.0, 1.0], [1.0, 0.0]])
    with pytest.raises(SolverError):
        lu = LUSolver(*coo(A), 2, parallel=False)
        lu.solve(np.ones(2))
    if "mumps" in available_solvers():
        lu = LUSolver(*coo(A), 2, solver="mumps", ordering=None, parallel=False)
        np.testing.assert_allclose(lu.solve(np.array([1.0, 2.0])), [2.0, 1.0])
        lu.destroy()


def test_an_unstable_pivot_free_factorization_is_refused():
    """A tiny first pivot: the pivot-free LU's growth ruins the solve, which the backward
    error catches (Higham 2002, sec. 9.3)."""
    eps = 1e-9
    A = np.array([[eps, 1.0, 0.0], [1.0, 1.0, 1.0], [0.0, 1.0, 3.0]])
    x_true = np.array([1.0, -2.0, 3.0])
    b = A @ x_true
    assert backward_error(coo(A), 3, np.linalg.solve(A, b), b) < 1e-15
    lu = LUSolver(*coo(A), 3, parallel=False)
    with pytest.raises(SolverError, match="backward error"):
        lu.solve(b)
    lu.destroy()


def test_bad_solver_and_ordering_name_the_field():
    A = saddle_point(4, 2)
    with pytest.raises(ConfigError, match="solver"):
        LUSolver(*coo(A), 6, solver="umfpack")
    with pytest.raises(ConfigError, match="ordering"):
        LUSolver(*coo(A), 6, solver="mumps", ordering="natural")


@pytest.mark.mpi
def test_two_ranks_factor_redundantly_and_give_the_serial_answer(tmp_path):
    """``mpiexec -n 2``: the world mode's redundant factorization on each rank (the MPI of
    the venv's PETSc stack), by PETSc's LU and by the block package (MUMPS where the build
    has it), gives the serial solution to round-off."""
    from conftest import require

    require(shutil.which("mpiexec") is not None, "no mpiexec")
    script = tmp_path / "lu2.py"
    script.write_text(f"""
import sys
import numpy as np
sys.path.insert(0, {str(Path(__file__).parent)!r})
from test_petsc_solver import coo, saddle_point
from ssw.contact.petsc_solver import LUSolver, comm_rank, comm_size
A = saddle_point(30, 9)
for solver in ("petsc", "auto"):
    lu = LUSolver(*coo(A), A.shape[0], solver=solver)
    x = lu.solve(np.arange(A.shape[0], dtype=float))
    X = lu.solve(np.ones((A.shape[0], 3)))
    lu.destroy()
    np.save({str(tmp_path)!r} + f"/{{solver}}{{comm_rank()}}.npy", np.column_stack([x, X]))
np.save({str(tmp_path)!r} + f"/size{{comm_rank()}}.npy", comm_size())
""")
    run = subprocess.run(["mpiexec", "-n", "2", sys.executable, str(script)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    A = saddle_point(30, 9)
    ref = np.column_stack([np.linalg.solve(A, np.arange(A.shape[0], dtype=float)),
                           np.linalg.solve(A, np.ones((A.shape[0], 3)))])
    for rank in (0, 1):
        assert np.load(tmp_path / f"size{rank}.npy") == 2
        for solver in ("petsc", "auto"):
            np.testing.assert_allclose(np.load(tmp_path / f"{solver}{rank}.npy"), ref,
                                       rtol=1e-10)
