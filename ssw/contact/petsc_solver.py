"""PETSc sparse direct solver (petsc4py): one LU factorization, many right-hand sides.

The matrix is assembled from COO triplets (``MatSetPreallocationCOO``) as AIJ, distributed
by rows over the ranks of ``PETSC_COMM_WORLD``. It is factored once with PCLU in the
natural order of the given numbering (which :mod:`ssw.contact.assembly` makes a nested
dissection of the node graph with each node's displacements before its pressure, so that
the saddle-point matrix has no zero pivot; it is also scaled there so that PETSc's absolute
zero-pivot threshold means "zero relative to the problem"). With more than one rank the
factorization is ``PCREDUNDANT`` (every rank factors the gathered matrix with the same
sequential LU), so that ``mpiexec -n N`` reproduces the serial answer to round-off. Every
solve checks the KSP converged reason and raises :class:`ssw.errors.SolverError` on failure.

A factorization without pivoting of an indefinite (saddle-point) matrix can be unstable
even when no pivot is zero, so the first solve after a factorization measures the
backward error ``||A X - B||_inf / (||A||_inf ||X||_inf + ||B||_inf)`` (Higham 2002, ch. 7)
and raises SolverError above :data:`BACKWARD_ERROR_TOL`.

This is the monolithic engine (``ssw.contact.solve_curve(..., engine="monolithic")``), the
independent check of the substructured one. Under MPI, ``PCREDUNDANT`` factors the whole
matrix on every rank: the same work N times, for no speed-up (docs/cluster.md); parallel
runs distribute scenes over ranks instead (``ssw contact --scene ... --output-dir``).
"""

from __future__ import annotations

import numpy as np

from ssw.errors import SolverError

#: Options prefix of the contact solver's KSP (users may add PETSc options under it).
PREFIX = "ssw_contact_"
#: Largest backward error accepted from the factorization (machine epsilon 2.2e-16;
#: measured 1e-17 to 1e-15 on the thesis's meshes).
BACKWARD_ERROR_TOL = 1e-10


def _petsc():
    """The initialized ``petsc4py.PETSc`` module, the one place ssw imports it.

    With the binary stack (the ``dolfinx-solver-real`` wheel, ``scripts/setup.sh``'s
    default) its package must be imported first: it loads the ``mpich`` wheel's MPI ahead
    of PETSc's shared library. A from-source PETSc (``SSW_PETSC=source``) has no such
    package and needs nothing first.
    """
    try:
        import dolfinx_solver  # noqa: F401  (orders MPI ahead of petsc4py)
    except ImportError:
        pass
    import petsc4py

    petsc4py.init()
    from petsc4py import PETSc

    return PETSc


#: Environment variables an MPI launcher sets in its ranks (MPICH/Hydra and Intel MPI,
#: PMIx, Open MPI): without any, the process is a serial run and PETSc is not imported just
#: to learn so (~0.3 s).
MPI_ENV = ("PMI_RANK", "PMI_SIZE", "PMIX_RANK", "OMPI_COMM_WORLD_SIZE", "MPI_LOCALNRANKS")


def _under_mpi() -> bool:
    import os

    return any(k in os.environ for k in MPI_ENV)


def comm_size() -> int:
    """Number of MPI ranks of PETSC_COMM_WORLD (1 outside an MPI launcher)."""
    return _petsc().COMM_WORLD.getSize() if _under_mpi() else 1


def comm_rank() -> int:
    """Rank of this process in PETSC_COMM_WORLD (0 outside an MPI launcher)."""
    return _petsc().COMM_WORLD.getRank() if _under_mpi() else 0


def nd_order(rows: np.ndarray, cols: np.ndarray, n: int) -> np.ndarray:
    """Nested-dissection permutation (new position -> node) of a graph given as COO."""
    PETSc = _petsc()
    g = PETSc.Mat().createAIJ((n, n), comm=PETSc.COMM_SELF)
    g.setPreallocationCOO(rows.astype(PETSc.IntType), cols.astype(PETSc.IntType))
    g.setValuesCOO(np.ones(len(rows)), addv=PETSc.InsertMode.INSERT_VALUES)
    g.assemble()
    rperm, _ = g.getOrdering("nd")
    perm = rperm.getIndices().copy()
    g.destroy()
    return perm


def dense_solve(PETSc, ksp, n: int, rhs: np.ndarray) -> np.ndarray:
    """``X`` with ``A X = rhs`` for a factored sequential ``ksp``, ``rhs`` dense (n, k), in
    one ``KSPMatSolve``. Raises SolverError when PETSc fails (the caller checks the KSP's
    converged reason)."""
    k = rhs.shape[1]
    if k == 0:
        return np.zeros((n, 0))
    b = PETSc.Mat().createDense((n, k), array=np.asfortranarray(rhs), comm=PETSc.COMM_SELF)
    x = PETSc.Mat().createDense((n, k), comm=PETSc.COMM_SELF)
    x.setUp()
    try:
        ksp.matSolve(b, x)
    except PETSc.Error as exc:
        raise SolverError(f"PETSc solve failed: {exc}") from exc
    finally:
        b.destroy()
    out = x.getDenseArray().copy()
    x.destroy()
    return out


def backward_error(coo: tuple[np.ndarray, np.ndarray, np.ndarray], n: int, X: np.ndarray,
                   rhs: np.ndarray) -> float:
    """``||A X - B||_inf / (||A||_inf ||X||_inf + ||B||_inf)`` (Higham 2002, ch. 7) of a
    solve of ``A X = B``, ``A`` given as COO triplets (duplicates summed)."""
    import scipy.sparse as sp

    rows, cols, vals = coo
    A = sp.csr_array((vals, (rows, cols)), shape=(n, n))
    X2, B2 = X.reshape(n, -1), rhs.reshape(n, -1)
    r = A @ X2 - B2
    norm_a = float(np.max(np.abs(A).sum(axis=1)))
    denom = norm_a * float(np.max(np.abs(X2))) + float(np.max(np.abs(B2)))
    return float(np.max(np.abs(r)) / denom) if denom > 0 else 0.0


def check_converged(ksp, what: str) -> None:
    """SolverError when the last solve of a factored ``ksp`` diverged (a zero pivot)."""
    reason = ksp.getConvergedReason()
    if reason < 0:
        raise SolverError(f"PETSc KSP diverged (KSPConvergedReason {reason}); the LU "
                          f"factorization of {what} failed (zero pivot?)")


def check_backward_error(value: float, what: str) -> None:
    """SolverError when a factorization's backward error exceeds
    :data:`BACKWARD_ERROR_TOL`."""
    if not value <= BACKWARD_ERROR_TOL:
        raise SolverError(
            f"the LU factorization (natural order, no pivoting) of {what} is unstable: "
            f"backward error {value:.3g} > {BACKWARD_ERROR_TOL:g}")


class LUSolver:
    """LU factors of ``scale * A``, ``A`` a sparse matrix given as COO triplets (duplicates
    are summed).

    PETSc factors ``A`` (whose zero-pivot test is absolute: give a nondimensional ``A``
    with pivots of order one, :mod:`ssw.contact.assembly`); :meth:`solve` and
    :meth:`matvec` work with ``scale * A``.

    Parameters
    ----------
    rows : numpy.ndarray
        Row indices of the COO triplets of ``A`` (global indices, every rank passes all
        of them).
    cols : numpy.ndarray
        Column indices of the triplets.
    vals : numpy.ndarray
        Values of the triplets.
    n : int
        The matrix size.
    scale : float
        The matrix's unit (a power of two keeps the solves exact to the bit).
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray, n: int,
                 scale: float = 1.0) -> None:
        PETSc = _petsc()
        self.PETSc = PETSc
        comm = PETSc.COMM_WORLD
        self.size, rank = comm.getSize(), comm.getRank()
        self.n = n
        self.scale = float(scale)
        self._coo = (rows, cols, vals)
        self.backward_error: float | None = None
        # each rank inserts a slice of the triplets; PETSc sums and routes them
        lo, hi = (len(rows) * rank) // self.size, (len(rows) * (rank + 1)) // self.size
        a = PETSc.Mat().createAIJ((n, n), comm=comm)
        a.setPreallocationCOO(rows[lo:hi].astype(PETSc.IntType), cols[lo:hi].astype(PETSc.IntType))
        a.setValuesCOO(vals[lo:hi], addv=PETSc.InsertMode.ADD_VALUES)
        a.assemble()
        self.mat = a
        ksp = PETSc.KSP().create(comm=comm)
        ksp.setOptionsPrefix(PREFIX)
        ksp.setOperators(a)
        ksp.setType(PETSc.KSP.Type.PREONLY)
        pc = ksp.getPC()
        opts = PETSc.Options()
        if self.size == 1:
            pc.setType(PETSc.PC.Type.LU)
            pc.setFactorOrdering(ord_type="natural")
        else:
            pc.setType(PETSc.PC.Type.REDUNDANT)
            opts[f"{PREFIX}redundant_pc_type"] = "lu"
            opts[f"{PREFIX}redundant_pc_factor_mat_ordering_type"] = "natural"
        ksp.setFromOptions()
        try:
            ksp.setUp()
        except PETSc.Error as exc:
            raise SolverError(f"PETSc LU factorization failed: {exc}") from exc
        self.ksp = ksp
        self.x, self.b = a.createVecs()
        self.lo, self.hi = a.getOwnershipRange()
        self._gather, self._xall = PETSc.Scatter.toAll(self.x)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve ``scale A X = rhs`` for a dense (n, k) right-hand side; every rank gets all
        of X."""
        rhs = np.asarray(rhs, dtype=float).reshape(self.n, -1) / self.scale
        if self.size == 1:
            out = self._solve_dense(rhs)
        else:
            out = np.empty_like(rhs)
            for j in range(rhs.shape[1]):
                self.b.setArray(rhs[self.lo:self.hi, j])
                self._solve_vec()
                self._gather.scatter(self.x, self._xall)
                out[:, j] = self._xall.getArray()
        if self.backward_error is None and rhs.size:
            self._check_backward_error(rhs, out)
        return out

    def _check_backward_error(self, rhs: np.ndarray, X: np.ndarray) -> None:
        """Measure the first solve's backward error (module docstring); SolverError if large."""
        self.backward_error = backward_error(self._coo, self.n, X, rhs)
        check_backward_error(self.backward_error, "the u-p matrix")

    def _solve_vec(self) -> None:
        PETSc = self.PETSc
        try:
            self.ksp.solve(self.b, self.x)
        except PETSc.Error as exc:
            raise SolverError(f"PETSc solve failed: {exc}") from exc
        self._check()

    def _solve_dense(self, rhs: np.ndarray) -> np.ndarray:
        out = dense_solve(self.PETSc, self.ksp, self.n, rhs)
        self._check()
        return out

    def _check(self) -> None:
        check_converged(self.ksp, "the u-p matrix")

    def matvec(self, x: np.ndarray) -> np.ndarray:
        """``scale A x`` for a global vector ``x`` (n,); every rank gets the whole result."""
        self.x.setArray(np.asarray(x, float)[self.lo:self.hi])
        self.mat.mult(self.x, self.b)
        self._gather.scatter(self.b, self._xall)
        return self.scale * self._xall.getArray()

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for obj in (self.ksp, self.mat, self.x, self.b, self._gather, self._xall):
            obj.destroy()
