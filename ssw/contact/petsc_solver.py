"""PETSc sparse direct solver (petsc4py): one LU factorization, many right-hand sides.

The one LU wrapper of ssw: the monolithic contact engine (``ssw.contact.solve_curve(...,
engine="monolithic")``, the independent check of the substructured one) and the dynamic
FEM wall's time stepper (:mod:`ssw.dynamics.newmark`) both factor through
:class:`LUSolver`, and this module is the one place ssw imports petsc4py (``_petsc``).

The matrix comes as COO triplets (``MatSetPreallocationCOO``, duplicates summed) of a
nondimensional ``A`` and a unit ``scale`` (a power of two, :mod:`ssw.contact.assembly`),
so that PETSc's absolute zero-pivot test keeps its meaning; :meth:`LUSolver.solve` solves
``scale A X = B``. By default it is factored with PCLU in the natural order of the given
numbering, which :mod:`ssw.contact.assembly` makes a nested dissection of the node graph
with each node's displacements before its pressure: the saddle-point u-p matrix then meets
no zero pivot, up to ``nu = 0.5``. A factorization package (``solver``: MUMPS,
SuperLU_DIST where the PETSc build has them) or another PETSc ordering can be asked for;
those packages order and pivot by themselves. ``ssw bench lu`` times them all on ssw's
matrices: MUMPS factors the contact's u-p matrices 20-35 % faster than PETSc's own LU and
solves a block of right-hand sides ~3x faster, at equal backward errors, so the monolithic
engine (which solves blocks) uses it (``solver="auto"``); PETSc's own LU solves a single
right-hand side ~1.6x faster, so the dynamic wall's time steps keep it.

Parallel runs. On ``PETSC_COMM_WORLD`` (``parallel=True``, the contact engine) the matrix
is distributed by rows over the ranks, and with more than one rank the factorization is
``PCREDUNDANT`` (every rank factors the gathered matrix with the same sequential LU), so
that ``mpiexec -n N`` reproduces the serial answer to round-off; the same work N times, for
no speed-up (docs/cluster.md): parallel runs distribute scenes over ranks instead (``ssw
contact --scene ... --output-dir``). With ``parallel=False`` the matrix is the process's
own (``COMM_SELF``): a dynamic wall is one scene, and a sweep's ranks each step their own.

Right-hand sides. A single one (shape (n,)) goes through PETSc vectors that wrap
persistent numpy buffers (no allocation per time step); a block (n, k) through one
``KSPMatSolve``. Every solve checks the KSP converged reason and raises
:class:`ssw.errors.SolverError` on failure.

A factorization without pivoting of an indefinite (saddle-point) matrix can be unstable
even when no pivot is zero, so the first solve after a factorization (with a nonzero
right-hand side) measures the backward error
``||A X - B||_inf / (||A||_inf ||X||_inf + ||B||_inf)`` (Higham 2002, ch. 7) and raises
SolverError above :data:`BACKWARD_ERROR_TOL`.

References
----------
Higham, N. J. (2002). *Accuracy and Stability of Numerical Algorithms*, 2nd ed. SIAM.
"""

from __future__ import annotations

import numpy as np

from ssw.errors import ConfigError, SolverError

#: Options prefix of the contact solver's KSP (users may add PETSc options under it).
PREFIX = "ssw_contact_"
#: Largest backward error accepted from the factorization (machine epsilon 2.2e-16;
#: measured 1e-17 to 1e-15 on the thesis's meshes).
BACKWARD_ERROR_TOL = 1e-10
#: Factorization packages :class:`LUSolver` accepts (PETSc's own LU, and the external
#: packages the binary PETSc stack carries).
SOLVERS = ("petsc", "mumps", "superlu_dist")
#: The package of ``solver="auto"``: MUMPS solves a block of right-hand sides ~3x faster
#: than PETSc's own LU (one column at a time) and factors the contact's u-p matrices 20-35 %
#: faster, with backward errors as small; PETSc's LU keeps the single solve (~1.6x faster:
#: the dynamic wall's time steps). ``ssw bench lu`` (its module docstring), 2 cores.
BLOCK_SOLVER = "mumps"


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
    """Number of MPI ranks of PETSC_COMM_WORLD (1 outside an MPI launcher).

    Returns
    -------
    int
        Number of ranks.
    """
    return _petsc().COMM_WORLD.getSize() if _under_mpi() else 1


def comm_rank() -> int:
    """Rank of this process in PETSC_COMM_WORLD (0 outside an MPI launcher).

    Returns
    -------
    int
        This process's rank.
    """
    return _petsc().COMM_WORLD.getRank() if _under_mpi() else 0


def available_solvers() -> tuple[str, ...]:
    """The entries of :data:`SOLVERS` this PETSc build can factor with.

    Returns
    -------
    tuple of str
        ``"petsc"`` always; ``"mumps"`` and ``"superlu_dist"`` where PETSc was built with
        them (the binary stack's wheel is; the source route's default build is not).
    """
    PETSc = _petsc()
    return ("petsc", *(s for s in SOLVERS[1:] if PETSc.Sys.hasExternalPackage(s)))


def nd_order(rows: np.ndarray, cols: np.ndarray, n: int) -> np.ndarray:
    """Nested-dissection permutation of a graph given as COO.

    Parameters
    ----------
    rows : numpy.ndarray
        Row indices of the graph's edges (int).
    cols : numpy.ndarray
        Column indices of the graph's edges (int).
    n : int
        Number of nodes.

    Returns
    -------
    numpy.ndarray
        (n,) new position -> node.
    """
    PETSc = _petsc()
    g = PETSc.Mat().createAIJ((n, n), comm=PETSc.COMM_SELF)
    g.setPreallocationCOO(rows.astype(PETSc.IntType), cols.astype(PETSc.IntType))
    g.setValuesCOO(np.ones(len(rows)), addv=PETSc.InsertMode.INSERT_VALUES)
    g.assemble()
    rperm, _ = g.getOrdering("nd")
    perm = rperm.getIndices().copy()
    g.destroy()
    return perm


def backward_error(coo: tuple[np.ndarray, np.ndarray, np.ndarray], n: int, X: np.ndarray,
                   rhs: np.ndarray) -> float:
    """Normwise backward error of a solve of ``A X = B`` (Higham 2002, ch. 7).

    Parameters
    ----------
    coo : tuple of numpy.ndarray
        ``(rows, cols, vals)``: ``A`` as COO triplets (duplicates summed).
    n : int
        Matrix size.
    X : numpy.ndarray
        The computed solution, (n,) or (n, k).
    rhs : numpy.ndarray
        The right-hand side ``B``, the shape of ``X``.

    Returns
    -------
    float
        ``||A X - B||_inf / (||A||_inf ||X||_inf + ||B||_inf)``
        (:func:`ssw.contact.lu.backward_error`, on ``A`` assembled from its triplets).
    """
    import scipy.sparse as sp

    from ssw.contact import lu

    rows, cols, vals = coo
    A = sp.csr_array((vals, (rows, cols)), shape=(n, n))
    X2, B2 = X.reshape(n, -1), rhs.reshape(n, -1)
    return lu.backward_error(A, X2, A @ X2 - B2, B2)


class LUSolver:
    """LU factors of ``scale * A``, ``A`` a sparse matrix given as COO triplets.

    PETSc factors ``A`` (whose zero-pivot test is absolute: give a nondimensional ``A``
    with pivots of order one, :mod:`ssw.contact.assembly`); :meth:`solve` and
    :meth:`matvec` work with ``scale * A`` (module docstring).

    Parameters
    ----------
    rows : numpy.ndarray
        Row indices of ``A``'s COO triplets (global; every rank passes all of them).
    cols : numpy.ndarray
        Column indices of the triplets.
    vals : numpy.ndarray
        Values of the triplets (duplicates are summed).
    n : int
        Matrix size.
    scale : float
        The matrix's unit (a power of two keeps the solves exact to the bit).
    solver : str
        Factorization package, one of :data:`SOLVERS` (``petsc``: PETSc's own LU), or
        ``auto``: :data:`BLOCK_SOLVER` where the build has it, else ``petsc`` with
        ``ordering`` (for a matrix solved mostly with blocks of right-hand sides).
    ordering : str or None
        PETSc's fill-reducing ordering of its own LU (``natural``: the given numbering,
        no pivoting; ``nd``, ``amd``, ``rcm``, ...), or None for the package's own choice
        (the only choice for ``mumps`` and ``superlu_dist``, which also pivot).
    parallel : bool
        True: on ``PETSC_COMM_WORLD`` (redundant factorizations on more than one rank);
        False: the process's own matrix (``COMM_SELF``).
    prefix : str
        PETSc options prefix of the KSP (users may add options under it).
    what : str
        The matrix's name in error messages.

    Raises
    ------
    ConfigError
        For a solver or an ordering this build cannot use.
    SolverError
        When the factorization fails (a zero pivot).
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray, n: int,
                 scale: float = 1.0, *, solver: str = "petsc", ordering: str | None = "natural",
                 parallel: bool = True, prefix: str = PREFIX, what: str = "the u-p matrix"
                 ) -> None:
        have = available_solvers()
        if solver == "auto":
            solver = BLOCK_SOLVER if BLOCK_SOLVER in have else "petsc"
            ordering = None if solver == BLOCK_SOLVER else ordering
        if solver not in SOLVERS:
            raise ConfigError("solver", solver, f"one of {', '.join(SOLVERS)} or auto")
        if solver != "petsc" and ordering is not None:
            raise ConfigError("ordering", ordering,
                              f"None with solver {solver} (it orders by itself)")
        if solver not in have:
            raise ConfigError("solver", solver,
                              f"a package this PETSc build has: {', '.join(have)}")
        PETSc = _petsc()
        self.PETSc = PETSc
        comm = PETSc.COMM_WORLD if parallel else PETSc.COMM_SELF
        self.size, rank = comm.getSize(), comm.getRank()
        self.n = int(n)
        self.scale = float(scale)
        self.solver = solver
        self.what = what
        self._coo = (rows, cols, vals)
        #: backward error of the first solve with a nonzero right-hand side
        self.backward_error: float | None = None
        # each rank inserts a slice of the triplets; PETSc sums and routes them
        lo, hi = (len(rows) * rank) // self.size, (len(rows) * (rank + 1)) // self.size
        a = PETSc.Mat().createAIJ((n, n), comm=comm)
        a.setPreallocationCOO(rows[lo:hi].astype(PETSc.IntType), cols[lo:hi].astype(PETSc.IntType))
        a.setValuesCOO(vals[lo:hi], addv=PETSc.InsertMode.ADD_VALUES)
        a.assemble()
        self.mat = a
        ksp = PETSc.KSP().create(comm=comm)
        ksp.setOptionsPrefix(prefix)
        ksp.setOperators(a)
        ksp.setType(PETSc.KSP.Type.PREONLY)
        pc = ksp.getPC()
        if self.size == 1:
            pc.setType(PETSc.PC.Type.LU)
            pc.setFactorSolverType(solver)
            if ordering is not None:
                pc.setFactorOrdering(ord_type=ordering)
        else:
            pc.setType(PETSc.PC.Type.REDUNDANT)
            opts = PETSc.Options()
            opts[f"{prefix}redundant_pc_type"] = "lu"
            opts[f"{prefix}redundant_pc_factor_mat_solver_type"] = solver
            key = f"{prefix}redundant_pc_factor_mat_ordering_type"
            if ordering is not None:
                opts[key] = ordering
            else:  # not an earlier solver's with the same prefix
                opts.delValue(key)
        ksp.setFromOptions()
        try:
            ksp.setUp()
        except PETSc.Error as exc:
            raise SolverError(f"PETSc LU factorization ({solver}) of {what} failed: "
                              f"{exc}") from exc
        self.ksp = ksp
        # persistent buffers of this rank's rows, wrapped by PETSc vectors
        self.lo, self.hi = a.getOwnershipRange()
        self._b = np.zeros(self.hi - self.lo)
        self._x = np.zeros(self.hi - self.lo)
        self._vb = PETSc.Vec().createWithArray(self._b, size=(self.hi - self.lo, n), comm=comm)
        self._vx = PETSc.Vec().createWithArray(self._x, size=(self.hi - self.lo, n), comm=comm)
        self._gather, self._xall = PETSc.Scatter.toAll(self._vx)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve ``scale A X = rhs``.

        Parameters
        ----------
        rhs : numpy.ndarray
            (n,) one right-hand side, or (n, k) a block of them; every rank passes all.

        Returns
        -------
        numpy.ndarray
            ``X``, the shape of ``rhs``; every rank gets all of it.

        Raises
        ------
        SolverError
            When PETSc fails, or the first solve's backward error exceeds
            :data:`BACKWARD_ERROR_TOL`.
        """
        rhs = np.asarray(rhs, dtype=float)
        if rhs.ndim == 1 and self.size == 1:
            np.divide(rhs, self.scale, out=self._b)
            self._solve_vec()
            out = self._x.copy()
        elif self.size == 1:
            out = self._solve_block(rhs.reshape(self.n, -1) / self.scale)
        else:
            B = rhs.reshape(self.n, -1) / self.scale
            out = np.empty_like(B)
            for j in range(B.shape[1]):
                self._b[:] = B[self.lo:self.hi, j]
                self._solve_vec()
                self._gather.scatter(self._vx, self._xall)
                out[:, j] = self._xall.getArray()
            out = out.reshape(rhs.shape)
        if self.backward_error is None and rhs.size and np.any(rhs):
            self.backward_error = backward_error(self._coo, self.n, out, rhs / self.scale)
            if not self.backward_error <= BACKWARD_ERROR_TOL:
                raise SolverError(
                    f"the LU factorization ({self.solver}) of {self.what} is unstable: "
                    f"backward error {self.backward_error:.3g} > {BACKWARD_ERROR_TOL:g}")
        return out

    def _solve_vec(self) -> None:
        """``x = A^-1 b`` on the persistent buffers."""
        try:
            self.ksp.solve(self._vb, self._vx)
        except self.PETSc.Error as exc:
            raise SolverError(f"PETSc solve failed: {exc}") from exc
        self._check()

    def _solve_block(self, rhs: np.ndarray) -> np.ndarray:
        """``A^-1 rhs`` for a dense (n, k) block, in one ``KSPMatSolve`` (sequential)."""
        PETSc, n, k = self.PETSc, self.n, rhs.shape[1]
        if k == 0:
            return np.zeros((n, 0))
        b = PETSc.Mat().createDense((n, k), array=np.asfortranarray(rhs), comm=PETSc.COMM_SELF)
        x = PETSc.Mat().createDense((n, k), comm=PETSc.COMM_SELF)
        x.setUp()
        try:
            self.ksp.matSolve(b, x)
        except PETSc.Error as exc:
            raise SolverError(f"PETSc solve failed: {exc}") from exc
        finally:
            b.destroy()
        out = x.getDenseArray().copy()
        x.destroy()
        self._check()
        return out

    def _check(self) -> None:
        """SolverError when the last solve diverged (a zero pivot)."""
        reason = self.ksp.getConvergedReason()
        if reason < 0:
            raise SolverError(f"PETSc KSP diverged (KSPConvergedReason {reason}); the LU "
                              f"factorization of {self.what} failed (zero pivot?)")

    def matvec(self, x: np.ndarray) -> np.ndarray:
        """``scale A x``.

        Parameters
        ----------
        x : numpy.ndarray
            (n,) a global vector (every rank passes all of it).

        Returns
        -------
        numpy.ndarray
            (n,) ``scale A x``; every rank gets the whole result.
        """
        self._x[:] = np.asarray(x, float)[self.lo:self.hi]
        self.mat.mult(self._vx, self._vb)
        self._gather.scatter(self._vb, self._xall)
        return self.scale * self._xall.getArray()

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for obj in (self.ksp, self.mat, self._vb, self._vx, self._gather, self._xall):
            obj.destroy()
