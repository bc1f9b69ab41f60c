"""The binary PETSc stack's MPI loaded first, whoever imports PETSc in ssw's venv.

Installed by ``scripts/setup.sh`` (binary route) into the venv's site-packages, with a
``.pth`` line that imports it at every start of the venv's Python.

Why: PETSc's library in the ``dolfinx-solver-real`` wheel (and petsc4py's, slepc4py's and
DOLFINx's extension modules) need ``libmpi.so.12``, which the ``mpich`` wheel installs in
the venv's ``lib/`` folder: on none of their RUNPATHs (``$ORIGIN/../../dolfinx_solver/lib``
and the wheel's ``.libs``) and on no default search path of the dynamic loader, so a bare
``from petsc4py import PETSc`` fails with "libmpi.so.12: cannot open shared object file".
The wheel's own package ``dolfinx_solver`` is what makes the stack load: it refuses a second
PETSc in the environment, then imports ``mpi4py.MPI``, whose loader opens the venv's
``lib/libmpi.so``; every library needing ``libmpi.so.12`` then binds to that copy.

What: a finder at the head of ``sys.meta_path`` that, on the first import of a module that
loads one of those libraries (:data:`TRIGGERS`), leaves ``sys.meta_path`` and imports
``dolfinx_solver``, then lets the usual finders import the module. Nothing else is imported
at start-up (its cost: one small module, a set lookup per import; ``tests/test_environment.py``
measures it); no environment variable is set; a venv without ``dolfinx_solver`` (the source
route's PETSc, built against the system's MPI) is left alone.
"""

import sys

#: Modules whose import loads a library linked against ``libmpi.so.12``: petsc4py's and
#: slepc4py's library loaders (``petsc4py.init()``, ``from petsc4py import PETSc``) and
#: DOLFINx.
TRIGGERS = frozenset({"petsc4py.lib", "slepc4py.lib", "dolfinx"})


class PetscFirst:
    """A ``sys.meta_path`` finder that finds nothing: it imports ``dolfinx_solver`` before
    the first of :data:`TRIGGERS` is looked for."""

    @staticmethod
    def find_spec(name, path=None, target=None):
        """None (the usual finders import ``name``); first ``dolfinx_solver``, once, when
        ``name`` is one of :data:`TRIGGERS`."""
        if name not in TRIGGERS:
            return None
        try:  # once (dolfinx_solver's own look for petsc4py must not come back here)
            sys.meta_path.remove(PetscFirst)
        except ValueError:
            pass
        try:
            import dolfinx_solver  # noqa: F401  (MPI first, and no second PETSc)
        except ModuleNotFoundError as exc:
            if exc.name != "dolfinx_solver":
                raise
        return None


sys.meta_path.insert(0, PetscFirst)
