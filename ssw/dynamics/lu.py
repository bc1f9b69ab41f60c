"""One sparse LU factorization (PETSc, petsc4py), many solves: the time stepper's workhorse.

The matrix comes as COO triplets of a nondimensional ``A`` (duplicates summed) and a unit
``scale`` (a power of two, :mod:`ssw.contact.assembly`), so that PETSc's absolute
zero-pivot test keeps its meaning; :meth:`LU.solve` solves ``scale A x = b``. The
factorization is PCLU in the natural order of the given numbering, which
:mod:`ssw.contact.assembly` makes a nested dissection of the node graph with a node's
displacements before its pressure: the saddle-point u-p matrix then meets no zero pivot,
up to ``nu = 0.5``. Sequential (``COMM_SELF``): a dynamic wall is one scene, and a batch
of scenes runs as separate processes.

Single right-hand sides go through PETSc vectors that wrap persistent numpy buffers (no
allocation per time step); blocks of right-hand sides through ``KSPMatSolve``.
"""

from __future__ import annotations

import numpy as np

from ssw.contact.petsc_solver import (
    _petsc,
    backward_error,
    check_backward_error,
    check_converged,
    dense_solve,
)
from ssw.errors import SolverError

#: Options prefix of the dynamic solver's KSP (users may add PETSc options under it).
PREFIX = "ssw_dynamics_"


def petsc():
    """The initialized ``petsc4py.PETSc`` module (``ssw.contact.petsc_solver._petsc``)."""
    return _petsc()


class LU:
    """LU factors of ``scale * A`` (``A`` from COO triplets, nondimensional).

    Parameters
    ----------
    rows : numpy.ndarray
        Row indices of the COO triplets of ``A``.
    cols : numpy.ndarray
        Column indices of the triplets.
    vals : numpy.ndarray
        Values of the triplets.
    n : int
        The matrix size.
    scale : float
        The matrix's unit, N/m, a power of two.
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray, n: int,
                 scale: float = 1.0) -> None:
        PETSc = petsc()
        self.PETSc, self.n, self.scale = PETSc, int(n), float(scale)
        a = PETSc.Mat().createAIJ((n, n), comm=PETSc.COMM_SELF)
        a.setPreallocationCOO(rows.astype(PETSc.IntType), cols.astype(PETSc.IntType))
        a.setValuesCOO(vals, addv=PETSc.InsertMode.ADD_VALUES)
        a.assemble()
        ksp = PETSc.KSP().create(comm=PETSc.COMM_SELF)
        ksp.setOptionsPrefix(PREFIX)
        ksp.setOperators(a)
        ksp.setType(PETSc.KSP.Type.PREONLY)
        pc = ksp.getPC()
        pc.setType(PETSc.PC.Type.LU)
        pc.setFactorOrdering(ord_type="natural")
        ksp.setFromOptions()
        try:
            ksp.setUp()
        except PETSc.Error as exc:
            raise SolverError(f"PETSc LU factorization failed: {exc}") from exc
        self.mat, self.ksp = a, ksp
        self._coo = (rows, cols, vals)
        #: backward error of the first solve (the factorization is pivot-free on an
        #: indefinite matrix: checked once, as in ssw.contact.petsc_solver)
        self.backward_error: float | None = None
        self._b = np.zeros(n)
        self._x = np.zeros(n)
        self._vb = PETSc.Vec().createWithArray(self._b, comm=PETSc.COMM_SELF)
        self._vx = PETSc.Vec().createWithArray(self._x, comm=PETSc.COMM_SELF)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``x`` with ``scale A x = rhs``; ``rhs`` (n,) or (n, k)."""
        rhs = np.asarray(rhs, float)
        if rhs.ndim == 1:
            np.divide(rhs, self.scale, out=self._b)
            try:
                self.ksp.solve(self._vb, self._vx)
            except self.PETSc.Error as exc:
                raise SolverError(f"PETSc solve failed: {exc}") from exc
            self._check()
            out = self._x.copy()
        else:
            out = self._solve_block(rhs / self.scale)
        if self.backward_error is None and rhs.size and np.any(rhs):
            self.backward_error = backward_error(self._coo, self.n, out, rhs / self.scale)
            check_backward_error(self.backward_error, "the dynamic u-p matrix")
        return out

    def _solve_block(self, rhs: np.ndarray) -> np.ndarray:
        out = dense_solve(self.PETSc, self.ksp, self.n, rhs)
        self._check()
        return out

    def _check(self) -> None:
        check_converged(self.ksp, "the dynamic u-p matrix")

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for obj in (self.ksp, self.mat, self._vb, self._vx):
            obj.destroy()
