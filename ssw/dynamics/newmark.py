"""Trapezoidal Newmark steps of ``M u'' + C u' + K u = G^T lam``, condensed on the contact dofs.

Scheme: Newmark's average-acceleration method (``beta = 1/4``, ``gamma = 1/2``; Newmark
1959; Hughes 2000, sec. 9.1): implicit, unconditionally stable, second order, without
numerical dissipation. Why it and not an explicit scheme: the Taylor-Hood u-p system has
massless pressure dofs (an algebraic constraint, exact up to ``nu = 0.5``) that an explicit
lumped-mass scheme cannot step, and the contact mesh's 5 um elements would make its
stability limit ``h / c_p`` ~1e-9 s, three orders below the chain's step. With a fixed
step ``dt`` the effective matrix

    K_eff = K + 4/dt^2 M + 2/dt C

is factored once (:class:`ssw.contact.petsc_solver.LUSolver`, the process's own); each
step is then one solve for the free motion ``u_free`` (no contact force) and, the contact
forces entering only through the candidate dofs, ``u = u_free + X lam`` with
``X = K_eff^-1 G^T`` computed once (``G^T``: a downward unit force on each candidate).
The candidates' gaps are affine in ``lam`` with the condensed compliance ``W = G X``: one
small LCP per step (:func:`ssw.contact.contact_lcp.solve_lcp`). Then

    a_(n+1) = 4/dt^2 (u_(n+1) - u_n) - 4/dt v_n - a_n,   v_(n+1) = 2/dt (u_(n+1) - u_n) - v_n.

Energy. For this scheme the discrete balance is exact (Hughes 2000, sec. 9.3): with
``E = v M v / 2 + u K u / 2``, ``E_(n+1) - E_n = (u_(n+1) - u_n) . G^T (lam_n +
lam_(n+1)) / 2 - dt vbar C vbar``, ``vbar = (u_(n+1) - u_n) / dt``; the last term is the
energy the boundary dashpots absorb (the radiated energy), accumulated in
``State.radiated``.

The step ``dt`` is the chain's (:func:`ssw.chain.integrate.time_step`, ~1/80 of a bead-bead
contact time, ~0.8 us): the scheme's relative period error ``(omega dt)^2 / 12`` is below
1e-4 up to 40 kHz, far above the last contact's spectrum (a few kHz).

Products of long vectors use ``numpy.einsum`` (single-threaded loops), not BLAS: on a
shared 2-core machine a threaded OpenBLAS ``gemv``/``dot`` of this size was measured 10-25x
slower than the plain loop (its threads spin against the other processes).

References
----------
Newmark, N. M. (1959). A method of computation for structural dynamics. J. Eng. Mech. Div.
ASCE 85(EM3), 67-94.
Hughes, T. J. R. (2000). The Finite Element Method. Dover.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ssw.contact.petsc_solver import LUSolver
from ssw.dynamics.system import DynamicSystem


@dataclass(frozen=True)
class State:
    """The discrete state at one time. ``u``, ``v``, ``a`` (ndof,) m, m/s, m/s^2 (the
    pressure entries are the scaled pressures and their rates); ``lam`` (m,) N, the contact
    forces; ``radiated`` J, the work absorbed by the dashpots so far; ``work`` J, the work
    of the contact forces on the plate/soil so far.

    Parameters
    ----------
    u : numpy.ndarray
        Displacements (m), (ndof,) (pressure entries: scaled pressures).
    v : numpy.ndarray
        Velocities (m/s), (ndof,).
    a : numpy.ndarray
        Accelerations (m/s^2), (ndof,).
    lam : numpy.ndarray
        Contact forces (N), (m,).
    radiated : float
        Work absorbed by the dashpots so far (J).
    work : float
        Work of the contact forces on the plate and soil so far (J).
    """

    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    lam: np.ndarray
    radiated: float = 0.0
    work: float = 0.0


def dot(a: np.ndarray, b: np.ndarray) -> float:
    """``a . b`` without threaded BLAS (module docstring).

    Parameters
    ----------
    a : numpy.ndarray
        First vector, (k,).
    b : numpy.ndarray
        Second vector, (k,).

    Returns
    -------
    float
        The dot product.
    """
    return float(np.einsum("i,i->", a, b))


#: Options prefix of the dynamic solver's KSP (users may add PETSc options under it).
PREFIX = "ssw_dynamics_"


def factor(rows: np.ndarray, cols: np.ndarray, vals: np.ndarray, system: DynamicSystem
           ) -> LUSolver:
    """The LU factors of a dynamic u-p matrix, the process's own (a dynamic wall is one
    scene; a sweep's ranks each step their own).

    Parameters
    ----------
    rows : numpy.ndarray
        Row indices of the nondimensional matrix's COO triplets.
    cols : numpy.ndarray
        Column indices of the triplets.
    vals : numpy.ndarray
        Values of the triplets (duplicates summed).
    system : DynamicSystem
        The operators (size ``ndof`` and unit ``scale``, N/m).

    Returns
    -------
    LUSolver
        Factors of ``scale * A``.
    """
    return LUSolver(rows, cols, vals, system.ndof, system.scale, parallel=False,
                    prefix=PREFIX, what="the dynamic u-p matrix")


class Newmark:
    """Average-acceleration Newmark steps with forces on the dofs ``load_dofs``.

    Parameters
    ----------
    system : ssw.dynamics.system.DynamicSystem
        The assembled operators.
    dt : float
        The fixed step, s.
    load_dofs : numpy.ndarray
        (m,) u_z dofs that carry the contact forces (downward = positive ``lam``).
    """

    def __init__(self, system: DynamicSystem, dt: float, load_dofs: np.ndarray) -> None:
        self.system, self.dt = system, float(dt)
        self.c0, self.c1, self.c2 = 4.0 / dt**2, 4.0 / dt, 2.0 / dt
        self.load_dofs = np.asarray(load_dofs, np.int64)
        rows, cols, vals = system.stiffness_triplets(self.c0, self.c2)
        self.lu = factor(rows, cols, vals, system)
        gt = np.zeros((system.ndof, self.load_dofs.size))
        gt[self.load_dofs, np.arange(self.load_dofs.size)] = -1.0
        self.X = self.lu.solve(gt)  # (ndof, m): displacement per unit downward force
        w = -self.X[self.load_dofs]
        self.W = 0.5 * (w + w.T)  # (m, m) compliance of the step, m/N
        self.Au = (self.c0 * system.M + self.c2 * system.C).tocsr()
        self.Av = (self.c1 * system.M + system.C).tocsr()

    def free(self, st: State) -> np.ndarray:
        """Displacement at ``t + dt`` with no contact force (ndof,).

        Parameters
        ----------
        st : State
            The state at ``t``.

        Returns
        -------
        numpy.ndarray
            Displacements (m), (ndof,).
        """
        rhs = self.Au @ st.u + self.Av @ st.v + self.system.M @ st.a
        return self.lu.solve(rhs)

    def finish(self, st: State, u_free: np.ndarray, lam: np.ndarray) -> State:
        """The state at ``t + dt`` once the contact forces ``lam`` are known.

        Parameters
        ----------
        st : State
            The state at ``t``.
        u_free : numpy.ndarray
            Contact-free displacements at ``t + dt`` (m), (ndof,).
        lam : numpy.ndarray
            Contact forces at ``t + dt`` (N), one per contact dof.

        Returns
        -------
        State
            The state at ``t + dt``, with its radiated energy and work (J).
        """
        u = u_free + np.einsum("ij,j->i", self.X, lam)
        du = u - st.u
        a = self.c0 * du - self.c1 * st.v - st.a
        v = self.c2 * du - st.v
        vbar = du / self.dt
        radiated = st.radiated + self.dt * dot(vbar, self.system.C @ vbar)
        # work of the forces lam on the displacements: downward force, u_z up
        work = st.work - 0.5 * dot(lam + st.lam, du[self.load_dofs])
        return replace(st, u=u, v=v, a=a, lam=lam.copy(), radiated=radiated, work=work)

    def destroy(self) -> None:
        """Free the factorization."""
        self.lu.destroy()


class Static:
    """The static problem ``(K + Kb) u = G^T lam`` on the same dofs (one factorization).

    Parameters
    ----------
    system : DynamicSystem
        The dynamic system (its stiffness).
    load_dofs : numpy.ndarray
        The dofs the contact forces act on.
    """

    def __init__(self, system: DynamicSystem, load_dofs: np.ndarray) -> None:
        self.system = system
        self.load_dofs = np.asarray(load_dofs, np.int64)
        rows, cols, vals = system.stiffness_triplets()
        self.lu = factor(rows, cols, vals, system)
        gt = np.zeros((system.ndof, self.load_dofs.size))
        gt[self.load_dofs, np.arange(self.load_dofs.size)] = -1.0
        self.X = self.lu.solve(gt)
        w = -self.X[self.load_dofs]
        self.W = 0.5 * (w + w.T)

    def state(self, lam: np.ndarray) -> State:
        """The state at rest under the contact forces ``lam``.

        Parameters
        ----------
        lam : numpy.ndarray
            Contact forces (N), one per contact dof.

        Returns
        -------
        State
            Displacements (m), zero velocity and acceleration.
        """
        n = self.system.ndof
        return State(u=self.X @ lam, v=np.zeros(n), a=np.zeros(n), lam=np.asarray(lam).copy())

    def destroy(self) -> None:
        """Free the factorization."""
        self.lu.destroy()
