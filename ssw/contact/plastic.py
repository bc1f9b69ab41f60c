"""Elasto-plastic contact: a rigid frictionless sphere pressed into (and lifted off) a plastic
sample (any model of :mod:`ssw.constitutive`), directly or through a plate (elastic or
yielding), with an active set on the contact inside Newton's iteration.

Discretization. The scene's mesh (:func:`ssw.contact.mesh.build_mesh`) and the
Taylor-Hood u-p element of the elastic engine (:mod:`ssw.contact.elements`: P2
displacements, continuous P1 mean stress ``p``), written for a nonlinear deviatoric law
(Simo & Hughes 1998, sec. 4.4; de Souza Neto et al. 2008, sec. 15.4):

    R_u = sum_e int B^T (dev sigma(eps) + p ONE) dV - f = 0,
    R_p = sum_e int N_p (tr eps - p / K) dV = 0,

``sigma(eps)`` the model's return mapping at the quadrature points and its consistent
tangent ``D``; the Newton matrix is ``[[int B^T P_DEV D B, int B^T ONE N_p],
[int N_p ONE^T B, -int N_p N_p / K]]``. Von Mises flow is isochoric, so ``dev sigma`` depends
on ``dev eps`` alone and ``p = K tr eps`` stays elastic: the mixed form is exact and free of
volumetric locking for any ``nu < 0.5`` and any plastic flow (a pure displacement P2 element
locks as the plastic zone becomes incompressible). Below yield the equations and the mesh
are the elastic engine's, so the curve is that engine's (tests/test_contact_plastic.py).
Models with plastic volume change (Drucker-Prager, crushable foam) take their mean stress
from the return mapping: for them the solver uses the displacement form of the same P2
element (``R_u = sum_e int B^T sigma(eps) dV``, the whole consistent tangent), free of
locking as long as neither the elastic nor the plastic response is near incompressible
(foams crush with a plastic Poisson's ratio near 0; a dilatant soil changes volume); below
yield it differs from the elastic engine by the P2 discretization error.

Plate. A plate on the sample (the thesis's device) is meshed as by the elastic engine and
tied to the sample by the contact config's ``interface``: ``frictionless`` (the thesis's;
the two surfaces share ``u_z`` and slide freely) or ``bonded``. The tie is bilateral, as
the elastic engine's: on unloading the plate follows the dent it pressed (a plate that
springs back off a permanent dent, the ``unilateral`` interface, is refused). The plate is
elastic, or yields by its own model (``plate_model``: von Mises with the plate material's
strength; the sample may then be elastic, ``model=None``). Below yield the curve is the
elastic engine's with the same plate (tests); a plate of the sample's own material bonded
to it yields as the half-space does (Johnson's first yield, tests). The residual
indentation splits into the interface's depth on the axis and the plate's thinning there.

Contact. The sphere's candidates are the top-surface nodes with ``r < R / 2``; at an
indentation ``delta`` the gap of a node is ``g = g0(r) - delta - u_z`` (``g0`` the exact
spherical gap). Each Newton iteration prescribes ``u_z = g0 - delta`` on the active set and
solves for the rest; at convergence the contact forces are the reactions ``lam = -f_int,z``;
the set gains the nodes with ``g < 0`` and loses those with ``lam < 0`` (a primal-dual active
set, Hintermueller, Ito & Kunisch 2003) until it is stable and the residual is below
``rtol`` times the load scale. An increment that does not converge in ``max_iter``
iterations is cut in two (at most ``max_cuts`` times), unless its best iterate stalled
within :data:`STALL_RTOL` of the load scale (accepted), then raises SolverError.

Path. Loading through ``delta`` then, with ``unload``, back in the same steps until the
sphere leaves the surface; the residual indentation is the axis's depth then (contact is
lost; the body stays as it is). Per increment: force, contact radius, the plastic zone
(volume, depth below the loaded surface, radius), the plastic work ``sum int sigma_{n+1} :
d eps_p dV`` (backward Euler) and Newton's iterations. First yield: the elastic
increments' largest yield ratio ``q / Y`` scales as the Hertz pressure ``p0 ~ F^(1/3)``
(self-similar elastic contact), so ``F_y = F / ratio^3`` of the last elastic increment.

Cost. Exact reductions of the same discrete problem (the curve is the one the increments'
Newton iterations on the whole mesh give, to round-off within the Newton tolerance; tests):

* the far field: the elements beyond a near zone about the contact point (radius
  :func:`near_radius`, doubled when the plastic zone or the contact reaches its edge) stay
  elastic and unloaded, so they are condensed once onto the dofs they share with the near
  zone (their Schur complement, ``_Model._condense``); the Newton iterations see the
  near zone only;
* elastic spans: while no point yields and the active set holds, the path is affine in the
  indentation (loading before first yield, unloading, elastic reloading); one solve with
  the elastic matrix's kept LU gives every increment of the span (``_elastic_span``);
* the Newton steps: GMRES preconditioned by the newest factorization of an earlier tangent
  while that is cheaper than factorizing (``_Model.solve``), to the linear residual the
  Newton test needs (a tenth of its tolerance, :data:`KRYLOV_FORCING`), and each plastic
  increment starts from the last one's rate (a predictor);
* the Newton matrix: assembled only when a step needs it, as the elastic matrix plus the
  plastic elements' change (``_Model.matrix``), and factored in the elimination order
  the first factorization of its free set chose (``_OrderedLU``).

A study config's plastic curve (``ssw contact --soil-model``) is solved on the config's
domain and growth with its element at the contact point scaled to the path
(:func:`path_mesh_settings`; ``--plastic-mesh study``: the elastic engine's mesh, whose
element at the contact point resolves indentations down to 3e-7 m); times and errors
against a converged mesh: ``ssw bench plastic --plastic-study``.

References
----------
Eisenstat, S. C. & Walker, H. F. (1996). Choosing the forcing terms in an inexact Newton
method. *SIAM J. Sci. Comput.* 17, 16-32.
Hintermueller, M., Ito, K. & Kunisch, K. (2003). The primal-dual active set strategy as a
semismooth Newton method. *SIAM J. Optim.* 13, 865-888.
Johnson, K. L. (1985). *Contact Mechanics*. Cambridge, sec. 4.2, 6.1.
Przemieniecki, J. S. (1963). Matrix structural analysis of substructures. *AIAA J.* 1,
138-147.
Saad, Y. & Schultz, M. H. (1986). GMRES: a generalized minimal residual algorithm for
solving nonsymmetric linear systems. *SIAM J. Sci. Stat. Comput.* 7, 856-869.
Simo, J. C. & Hughes, T. J. R. (1998). *Computational Inelasticity*. Springer.
de Souza Neto, E. A., Peric, D. & Owen, D. R. J. (2008). *Computational Methods for
Plasticity*. Wiley.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from ssw.constitutive.base import Update, initial_state
from ssw.constitutive.elastic import LinearElastic
from ssw.constitutive.tensors import ONE, P_DEV, SQRT2
from ssw.contact.assembly import (
    element_sizes,
    fixed_free,
    geometric_tolerance,
    pow2,
    split_interface,
    top_surface_weights,
)
from ssw.contact.contact_lcp import edge_radius
from ssw.contact.elements import (
    QUAD_POINTS,
    QUAD_WEIGHTS,
    lame,
    p1_shape,
    p2_shape,
    physical_gradients,
)
from ssw.contact.mesh import Mesh
from ssw.contact.operators import sphere_gap0
from ssw.errors import ConfigError, SolverError

#: Newton iterations allowed per increment (active-set changes included).
MAX_ITER = 40
#: Iterations of an increment in which the active set follows every iterate; later it
#: changes only at equilibrium (no cycling).
SET_UPDATES = 8
#: A Newton step moving a node by more than this many indentation steps is taken as a
#: leap along a nearly singular tangent and replaced by an elastic-tangent step.
STEP_BOUND = 10.0
#: An increment whose Newton iteration stalls (cycling between the branches of a
#: non-smooth return, e.g. Drucker-Prager's apex and cone, with the set of points at the
#: apex changing by a few from one iterate to the next) is accepted after ``max_iter``
#: iterations when its residual is below this share of the load scale
#: (``stats['stalled']`` counts them; the force then carries an error of that order).
STALL_RTOL = 1e-6
#: Halvings of a Newton step that does not lower the residual.
LINE_SEARCH = 4
#: Halvings of an increment whose Newton iteration fails, before SolverError.
MAX_CUTS = 5
#: Candidates of a condensed path: the top-surface nodes within this share of the near
#: zone's radius (the rest of it: the ring of elements that meets the far field).
NEAR_CANDIDATES = 0.9
#: Elastic LUs kept per path (one per free set: the contact's active set).
LU_CACHE = 8
#: Residual tolerance relative to the load scale (the largest nodal internal force): the
#: study's curve moves by 4e-11 of its peak force from 1e-9 (docs/physics/plastic.md),
#: far below its discretization errors (1e-3).
RTOL = 1e-8
#: Relative residual of a Newton step's GMRES solve (an inexact Newton step: the
#: iteration's own residual test sets the path's accuracy).
KRYLOV_RTOL = 1e-6
#: GMRES iterations a solve may take, at most, before a new factorization replaces the
#: preconditioner: a factorization costs about 35 solves with its factors (measured from
#: 2e3 to 2e4 dofs), a GMRES iteration one solve plus a fixed overhead worth a solve with
#: :data:`KRYLOV_NNZ` factor entries; so a matrix with ``nnz`` factor entries allows
#: ``KRYLOV_MAX nnz / (nnz + KRYLOV_NNZ)`` iterations.
KRYLOV_MAX = 30
#: Factor entries of a solve as costly as a GMRES iteration's overhead (0.1 ms).
KRYLOV_NNZ = 75_000
#: The linear residual a Newton step's GMRES solve may leave, at most, as a share of the
#: increment's residual tolerance (2-norm against the max-norm test: the step's linear
#: error stays below the tolerance the next iterate is tested against: an inexact Newton
#: step's forcing term, Eisenstat & Walker 1996, held to this share).
KRYLOV_FORCING = 0.1
#: Fewer GMRES iterations allowed than this: factorize instead.
KRYLOV_MIN = 4


class ContactZoneError(SolverError):
    """The contact reached the candidates' edge (half the sphere's radius): the indentation
    lies beyond what the small-strain contact of a sphere models."""


@dataclass(frozen=True)
class PlasticCurve:
    """A loading (and unloading) path. SI units; arrays of shape (n,) per increment.

    ``branch`` 0 loading, 1 unloading; ``dissipated`` the cumulative plastic work (J);
    ``plastic_volume`` (m^3), ``plastic_depth`` and ``plastic_radius`` (m) the extent of the
    points that have yielded so far; ``iterations`` Newton's per increment.
    """

    delta: np.ndarray
    force: np.ndarray
    branch: np.ndarray
    contact_radius: np.ndarray
    dissipated: np.ndarray
    plastic_volume: np.ndarray
    plastic_depth: np.ndarray
    plastic_radius: np.ndarray
    iterations: np.ndarray
    yield_ratio: np.ndarray
    first_yield_force: float | None
    first_yield_delta: float | None
    residual_indentation: float | None
    stored_energy: float
    stats: dict[str, Any] = field(default_factory=dict)
    #: the plate-sample interface's residual depth on the axis (m; the residual indentation
    #: less the plate's permanent thinning there; without a plate the residual indentation)
    interface_residual: float | None = None

    @property
    def dissipated_work(self) -> float:
        """Plastic work of the whole path, J."""
        return float(self.dissipated[-1]) if self.dissipated.size else 0.0

    @property
    def external_work(self) -> float:
        """``int F d delta`` over the path (trapezoids), J."""
        d = np.concatenate([[0.0], self.delta])
        f = np.concatenate([[0.0], self.force])
        return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(d)))


class _Model:
    """The discrete u-p problem of one mesh and material: constant blocks, dof maps.

    A plate (``mesh.body == 1``, ``plate = (E Pa, nu)``) is tied to the sample by
    ``interface``: its interface nodes are copies of the sample's (:func:`split_interface`)
    that share ``u_z`` (``frictionless``, the thesis's interface) or both components
    (``bonded``) with them; the plate's points follow ``plate_model`` (None: elastic), the
    sample's the sample's model."""

    def __init__(self, mesh: Mesh, E: float, nu: float, radius: float,
                 punch: str | None = None, mixed: bool = True,
                 plate: tuple[float, float] | None = None,
                 interface: str = "frictionless", plate_model: Any = None,
                 near: float | None = None) -> None:
        if mesh.subgrade is not None:
            raise ConfigError("sample.base", "elastic",
                              "a rigid base for a plastic sample (no subgrade)")
        has_plate = bool(np.any(mesh.body != 0))
        if has_plate and plate is None:
            raise ConfigError("plate", None, "the plate's (E Pa, nu) on a mesh with a plate")
        if has_plate and interface not in ("bonded", "frictionless"):
            raise ConfigError("contact.interface", interface,
                              "bonded | frictionless with a plastic sample (the plate stays "
                              "on the sample)")
        nodes, tri, pairs = split_interface(mesh)
        n, ne = len(nodes), len(tri)
        self.nodes, self.tri = nodes, tri
        body = mesh.body.astype(np.int64)
        if has_plate:
            E_el = np.where(body == 1, float(plate[0]), float(E))
            nu_el = np.where(body == 1, float(plate[1]), float(nu))
        else:
            E_el, nu_el = np.full(ne, float(E)), np.full(ne, float(nu))
        G_e, inv_K_e = (np.asarray(x, float) for x in lame(E_el, nu_el))
        n2, g2 = p2_shape(QUAD_POINTS)
        n1 = p1_shape(QUAD_POINTS)
        xy = nodes[tri]
        dn, det = physical_gradients(xy, g2)
        r = np.einsum("qa,ea->eq", n2, xy[:, :, 0])
        self.rq = r
        self.zq = np.einsum("qa,ea->eq", n2, xy[:, :, 1])
        self.w = 2.0 * np.pi * r * QUAD_WEIGHTS[None, :] * np.abs(det)[:, None]  # (ne, nq)
        nq = r.shape[1]
        #: (ne * nq,) the sample's points (the model's); the others are the plate's
        self.sample_pts = np.repeat(body == 0, nq)
        self.Gq = np.repeat(G_e, nq)
        self.inv_Kq = np.repeat(inv_K_e, nq)
        Kp = 1.0 / float(inv_K_e[body == 1][0]) if has_plate else 0.0
        Gp = float(G_e[body == 1][0]) if has_plate else 0.0
        #: the plate's elastic matrix (Mandel), Pa
        self.D_plate = 2.0 * Gp * P_DEV + Kp * np.outer(ONE, ONE)
        self.plate = (float(plate[0]), float(plate[1])) if has_plate else None
        self.plate_model = plate_model if has_plate else None
        # Mandel strain rows (e_rr, e_zz, e_tt, sqrt(2) e_rz) of (ur_0..5, uz_0..5)
        B = np.zeros((ne, nq, 4, 12))
        B[:, :, 0, :6] = dn[..., 0]
        B[:, :, 1, 6:] = dn[..., 1]
        B[:, :, 2, :6] = n2[None] / r[:, :, None]
        B[:, :, 3, :6] = dn[..., 1] / SQRT2
        B[:, :, 3, 6:] = dn[..., 0] / SQRT2
        self.B = B
        # pressure unknown of a vertex: p = ps * pi (ps = G / h, a power of two times G; a
        # vertex belongs to one body, the interface's being split)
        h = element_sizes(nodes, tri)
        h_node = np.full(n, np.inf)
        np.minimum.at(h_node, tri[:, :3], h[:, None])
        G_node = np.zeros(n)
        G_node[tri[:, :3]] = G_e[:, None]
        vert = np.unique(tri[:, :3])
        pid = np.full(n, -1)
        pid[vert] = np.arange(vert.size)
        self.ps = G_node[vert] * pow2(1.0 / h_node[vert])
        self.scale = float(pow2(float(np.min(G_e)) * float(np.min(h))))
        div = B[:, :, 0] + B[:, :, 1] + B[:, :, 2]  # (ne, nq, 12)
        ps_e = self.ps[pid[tri[:, :3]]]  # (ne, 3)
        self.Bp = np.einsum("qi,eq,eqj->eij", n1, self.w, div) * ps_e[:, :, None]
        self.Cp = np.einsum("qi,qj,eq->eij", n1, n1, self.w * inv_K_e[:, None]) * (
            ps_e[:, :, None] * ps_e[:, None, :])
        self.N1 = n1
        self.ps_e = ps_e
        self.mixed = mixed
        # displacement form: the pressure unknowns decouple (B_p = 0, so p = 0) and the
        # displacement block takes the whole stress and tangent
        self.proj = P_DEV if mixed else np.eye(4)
        if not mixed:
            self.Bp = np.zeros_like(self.Bp)
        # dofs: u_r, u_z of node i at 2i, 2i+1 (a plate copy of an interface node takes its
        # twin's shared components; its own stay unused and fixed); pressure of vertex k at
        # 2n + k
        udof = np.arange(2 * n).reshape(n, 2)
        soil_n, plate_n = pairs[:, 0], pairs[:, 1]
        if interface == "bonded":
            udof[plate_n] = udof[soil_n]
        else:
            udof[plate_n, 1] = udof[soil_n, 1]
        self.n = n
        self.ndof = 2 * n + vert.size
        self.edof_u = np.concatenate([udof[tri, 0], udof[tri, 1]], axis=1)  # (ne, 12)
        self.edof = np.concatenate([self.edof_u, 2 * n + pid[tri[:, :3]]], axis=1)  # (ne, 15)
        tol = geometric_tolerance(nodes, tri)
        free = fixed_free(nodes, tol, mesh.soil_radius, mesh.soil_depth, mesh.base,
                          mesh.lateral)
        unused = np.setdiff1d(np.arange(2 * n), self.edof_u)
        self.fixed = np.union1d(udof[~free], unused)
        weight = top_surface_weights(nodes, tri, np.arange(ne), mesh.top, tol)
        top = np.flatnonzero(weight > 0)
        top = top[np.argsort(nodes[top, 0])]
        reach = 0.5 * radius if near is None else min(0.5 * radius, NEAR_CANDIDATES * near)
        #: the candidates stop short of half the sphere's radius: at the near zone's edge
        self.cand_short = punch is None and reach < 0.5 * radius
        self.near = near
        self.n_elements = ne
        self.top = float(mesh.top)
        if punch is None:
            self.cand = top[nodes[top, 0] < reach]
        else:  # a rigid flat punch of radius ``radius``: the nodes under its face
            self.cand = top[nodes[top, 0] <= radius + tol]
            if punch == "rough":  # no slip under the face
                self.fixed = np.union1d(self.fixed, udof[self.cand, 0])
        self.cand_r = nodes[self.cand, 0]
        self.cand_dof = udof[self.cand, 1]
        self.g0 = sphere_gap0(self.cand_r, radius) if punch is None else np.zeros(
            self.cand.size)
        self.axis_dof = int(udof[top[0], 1])
        #: u_z of the plate-sample interface on the axis (the top without a plate)
        self.interface_axis_dof = (int(udof[soil_n[np.argmin(nodes[soil_n, 0])], 1])
                                   if has_plate else self.axis_dof)
        self.h_min = float(np.min(h))
        D_e = 2.0 * G_e[:, None, None] * P_DEV
        if not mixed:
            D_e = D_e + np.outer(ONE, ONE)[None] / inv_K_e[:, None, None]
        D_el = np.broadcast_to(D_e[:, None], (ne, nq, 4, 4))
        self.ke = np.zeros((ne, 15, 15))
        self.ke[:, :12, :12] = self._kuu(np.arange(ne), D_el)
        self.ke[:, 12:, :12] = self.Bp
        self.ke[:, :12, 12:] = np.transpose(self.Bp, (0, 2, 1))
        self.ke[:, 12:, 12:] = -self.Cp
        #: the elastic far field condensed onto the near zone (``_condense``): its
        #: retained dofs, stiffness (N/m) and the near elements at its boundary
        self.far_dofs, self.far_S = np.zeros(0, np.int64), np.zeros((0, 0))
        self.ring = np.zeros(ne, bool)
        self.far_stats: dict[str, Any] = {}
        if near is not None:
            self._condense(float(near), float(mesh.top))
        self.kuu_el = self.ke[:, :12, :12].copy()
        rows = np.concatenate([np.repeat(self.edof, 15, axis=1).ravel(),
                               np.repeat(self.far_dofs, self.far_dofs.size)])
        cols = np.concatenate([np.tile(self.edof, (1, 15)).ravel(),
                               np.tile(self.far_dofs, self.far_dofs.size)])
        keys, self.slot = np.unique(rows * self.ndof + cols, return_inverse=True)
        self.row_u, self.col_u = keys // self.ndof, keys % self.ndof  # CSR order
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(self.row_u,
                                                                 minlength=self.ndof))])
        self.nnz = keys.size
        #: the slots (CSR order) of the elements' displacement blocks (ne, 12, 12)
        self.slot_uu = self.slot[:self.ke.size].reshape(-1, 15, 15)[:, :12, :12]
        self.patterns: dict[bytes, tuple] = {}  # of restricted(): the newest few
        self._elastic_data: np.ndarray | None = None  # the elastic matrix, once assembled
        self._lus: dict[bytes, Any] = {}
        #: a fill-reducing order per free set (its first factorization's): later ones
        #: of the same free set skip the ordering
        self._orders: dict[bytes, np.ndarray] = {}
        self._pre: tuple | None = None  # the newest factorization: (lu, free, data)
        self._stale = self._direct = False
        self.factorizations = self.lu_reused = self.krylov = 0

    def _condense(self, near: float, top: float) -> None:
        """Condense the elements farther than ``near`` (m) from the contact point ``(0,
        top)`` (the far field, elastic) onto the dofs they share with the rest (the near
        zone), and keep the near zone alone: its elements, its dofs renumbered, and the far
        field's Schur complement ``S = K_II - K_IL K_LL^-1 K_LI`` (N/m; Przemieniecki 1963)
        on the shared dofs ``I`` (the far field's interior ``L`` eliminated;
        :func:`ssw.contact.substructure.schur_complement`, the far field's dofs in a
        minimum-degree order). The far field carries no load but what the near zone passes
        it, so the near zone's equations are those of the whole mesh: the solution is the
        same to round-off, at the cost of the near zone's."""
        from ssw.contact.substructure import min_degree_order, schur_complement

        xy = self.nodes[self.tri[:, :3]].mean(axis=1)
        keep = np.hypot(xy[:, 0], xy[:, 1] - top) < near
        if keep.all():
            return
        fixed = np.zeros(self.ndof, bool)
        fixed[self.fixed] = True
        inner = np.zeros(self.ndof, bool)
        inner[self.edof[keep].ravel()] = True
        outer = np.zeros(self.ndof, bool)
        outer[self.edof[~keep].ravel()] = True
        L = np.flatnonzero(outer & ~inner & ~fixed)
        shared = np.flatnonzero(outer & inner & ~fixed)
        if not np.all(inner[self.cand_dof]):
            raise ConfigError("near", near, "a near zone that holds the contact candidates")
        far = self.edof[~keep]
        rows, cols = np.repeat(far, 15, axis=1).ravel(), np.tile(far, (1, 15)).ravel()
        vals = self.ke[~keep].ravel() / self.scale
        pos = np.full(self.ndof, -1)
        pos[L] = np.arange(L.size)
        m = (pos[rows] >= 0) & (pos[cols] >= 0)
        order = min_degree_order(pos[rows[m]], pos[cols[m]], L.size)
        pos[L[order]] = np.arange(L.size)
        pos[shared] = L.size + np.arange(shared.size)
        m = (pos[rows] >= 0) & (pos[cols] >= 0)
        n_far = L.size + shared.size
        K = sp.csc_array((vals[m], (pos[rows[m]], pos[cols[m]])), shape=(n_far, n_far))
        K.sum_duplicates()
        S, berr, _, pivoted = schur_complement(K, L.size)
        new = np.full(self.ndof, -1)
        kept = np.flatnonzero(inner)
        new[kept] = np.arange(kept.size)
        nq = self.w.shape[1]
        for name in ("rq", "zq", "w", "B", "Bp", "Cp", "ps_e", "ke", "tri"):
            setattr(self, name, getattr(self, name)[keep])
        for name in ("sample_pts", "Gq", "inv_Kq"):
            setattr(self, name, getattr(self, name).reshape(-1, nq)[keep].ravel())
        self.edof = new[self.edof[keep]]
        self.edof_u = self.edof[:, :12]
        self.fixed = new[self.fixed[inner[self.fixed]]]
        self.cand_dof = new[self.cand_dof]
        self.axis_dof, self.interface_axis_dof = int(new[self.axis_dof]), int(
            new[self.interface_axis_dof])
        self.ndof = kept.size
        self.far_dofs = new[shared]
        self.far_S = 0.5 * (S + S.T) * self.scale
        self.ring = np.isin(self.edof, self.far_dofs).any(axis=1)
        self.far_stats = {"far_dofs": int(n_far), "far_retained": int(shared.size),
                          "far_backward_error": berr, "far_pivoted": bool(pivoted)}

    def free_dofs(self, active: np.ndarray) -> np.ndarray:
        """The dofs that are neither fixed nor prescribed by the ``active`` candidates."""
        known = np.zeros(self.ndof, bool)
        known[self.fixed] = True
        known[self.cand_dof[active]] = True
        return np.flatnonzero(~known)

    def elastic_matrix(self) -> np.ndarray:
        """The elastic Newton matrix's entries (CSR order, divided by ``scale``), assembled
        once."""
        if self._elastic_data is None:
            weights = np.concatenate([self.ke.ravel(), self.far_S.ravel()])
            self._elastic_data = np.bincount(self.slot, weights=weights,
                                             minlength=self.nnz) / self.scale
        return self._elastic_data

    def matrix(self, tangent: np.ndarray | None, plastic: np.ndarray) -> np.ndarray:
        """The Newton matrix's entries (CSR order, divided by ``scale``): the elements with
        a ``plastic`` point take the model's ``tangent`` (``(ne * nq, 4, 4)``, Pa), the
        others the elastic one; the elastic matrix itself (the same array) when no point
        is plastic. Assembled as the elastic matrix plus the plastic elements' change, so
        that the cost follows the plastic zone."""
        ne, nq = self.w.shape
        el = np.flatnonzero(plastic.reshape(ne, nq).any(axis=1))
        data = self.elastic_matrix()
        if not el.size:
            return data
        Dd = self.proj @ tangent.reshape(ne, nq, 4, 4)[el] @ self.proj
        change = self._kuu(el, Dd) - self.kuu_el[el]
        return data + np.bincount(self.slot_uu[el].ravel(), weights=change.ravel(),
                                  minlength=self.nnz) / self.scale

    def factor(self, data: np.ndarray, free: np.ndarray) -> Any:
        """The LU of the Newton matrix ``data`` (CSR order) on ``free``. The elastic
        matrix's (no plastic element: the unloading and elastic reloading branches) is kept
        per free set, at most :data:`LU_CACHE` of them, and reused: the same factorization
        bit for bit. The first factorization of a free set chooses its fill-reducing
        order (:func:`_factor`); the later ones keep it (:class:`_OrderedLU`). The newest
        factorization is also the preconditioner of :meth:`solve`. Counts
        ``factorizations`` and ``lu_reused``."""
        elastic = data is self._elastic_data
        key = free.tobytes()
        if elastic and key in self._lus:
            self.lu_reused += 1
            return self._lus[key]
        order = self._orders.get(key)
        lu = None
        if order is not None:
            lu = _OrderedLU.factor(self.restricted(data, free, order), order)
        if lu is None:
            lu = _factor(self.restricted(data, free))
            order = _symmetric_order(lu)
            if order is not None:
                self._orders[key] = order
        self.factorizations += 1
        self._pre = (lu, free, np.asarray(data))
        if elastic:
            if len(self._lus) >= LU_CACHE:
                self._lus.pop(next(iter(self._lus)))
            self._lus[key] = lu
        return lu

    def solve(self, data: np.ndarray, free: np.ndarray, rhs: np.ndarray,
              atol: float = 0.0) -> np.ndarray:
        """``x`` with ``A[free][:, free] x = rhs`` (``A`` the Newton matrix ``data``, CSR
        order): the elastic matrix's kept LU when there is one for ``free``; else GMRES
        right-preconditioned by the newest factorization (of an earlier tangent, possibly on
        another free set: the dofs it lacks take their diagonal) to :data:`KRYLOV_RTOL`
        or the absolute residual ``atol`` (the 2-norm, in ``rhs``'s units), whichever is
        reached first, within the iterations a factorization is worth
        (:data:`KRYLOV_MAX`); a new factorization when GMRES fails (and for the rest of
        the increment, :meth:`begin_increment`), or the next time when it needed more
        than half its allowance. Raises RuntimeError on a singular matrix."""
        from scipy.sparse.linalg import LinearOperator, gmres

        key = free.tobytes()
        allowed = 0 if self._pre is None else int(
            KRYLOV_MAX * self._pre[0].nnz / (self._pre[0].nnz + KRYLOV_NNZ))
        if (data is self._elastic_data and key in self._lus) or self._stale \
                or self._direct or allowed < KRYLOV_MIN:
            self._stale = False
            return self.factor(data, free).solve(rhs, trans="T")
        lu, free0, data0 = self._pre
        if data0 is data and free0.size == free.size and np.array_equal(free0, free):
            self.lu_reused += 1
            return lu.solve(rhs, trans="T")
        A = self.restricted(data, free).T  # CSR of A[free][:, free]
        if free0.size == free.size and np.array_equal(free0, free):
            def apply(r: np.ndarray) -> np.ndarray:
                return lu.solve(r, trans="T")
        else:
            pos0 = np.full(self.ndof, -1)
            pos0[free0] = np.arange(free0.size)
            p = pos0[free]
            inside = p >= 0
            diag = A.diagonal()
            outside = ~inside

            def apply(r: np.ndarray) -> np.ndarray:
                r0 = np.zeros(free0.size)
                r0[p[inside]] = r[inside]
                x = np.empty(free.size)
                x[inside] = lu.solve(r0, trans="T")[p[inside]]
                x[outside] = r[outside] / diag[outside]
                return x

        # right preconditioning: GMRES on ``A M`` (``x = M y``) minimizes the true
        # residual, the one tested below, with one factor solve per iteration
        AM = LinearOperator(A.shape, matvec=lambda y: A @ apply(y), dtype=float)
        count = [0]

        def tick(_: Any) -> None:
            count[0] += 1

        y, info = gmres(AM, rhs, rtol=KRYLOV_RTOL, atol=atol, restart=allowed, maxiter=1,
                        callback=tick, callback_type="pr_norm")
        x = apply(y)
        self.krylov += count[0]
        bnorm = float(np.linalg.norm(rhs))
        if info != 0 or not np.linalg.norm(rhs - A @ x) <= 10 * max(KRYLOV_RTOL * bnorm,
                                                                     atol):
            self._direct = True
            return self.factor(data, free).solve(rhs, trans="T")
        self._stale = 2 * count[0] > allowed
        return x

    def begin_increment(self) -> None:
        """A new increment: GMRES may serve again (after a failure it is left out for the
        rest of the increment)."""
        self._direct = False

    def _kuu(self, elems: np.ndarray, Dd: np.ndarray) -> np.ndarray:
        """``int B^T Dd B dV`` (len(elems), 12, 12) of deviatoric tangents Dd."""
        B = self.B[elems]
        WDB = np.matmul(Dd * self.w[elems][:, :, None, None], B)  # (m, nq, 4, 12)
        return np.matmul(np.swapaxes(B, 2, 3), WDB).sum(axis=1)

    def restricted(self, data: np.ndarray, free: np.ndarray,
                   order: np.ndarray | None = None) -> Any:
        """The CSC matrix of the transpose of ``A[free][:, free]`` (``A`` in CSR order
        ``data``): splu's ``trans='T'`` solve then solves with ``A``; with ``order`` (the
        free dofs' positions, :class:`_OrderedLU`) its rows and columns permuted to
        ``A[free[order]][:, free[order]]``'s."""
        key = free.tobytes() + (b"" if order is None else b"o")
        if key not in self.patterns:
            if len(self.patterns) >= 4:
                self.patterns.pop(next(iter(self.patterns)))
            mask = np.zeros(self.ndof, bool)
            mask[free] = True
            new = np.full(self.ndof, -1)
            new[free] = np.arange(free.size) if order is None else np.argsort(order)
            sel = np.flatnonzero(mask[self.row_u] & mask[self.col_u])
            ri, ci = new[self.row_u[sel]], new[self.col_u[sel]]
            if order is not None:  # CSC by the new rows: sort the entries by them
                srt = np.lexsort((ci, ri))
                sel, ri, ci = sel[srt], ri[srt], ci[srt]
            indptr = np.concatenate([[0], np.cumsum(np.bincount(ri, minlength=free.size))])
            self.patterns[key] = (sel, ci, indptr)
        sel, ci, indptr = self.patterns[key]
        return sp.csc_matrix((data[sel], ci, indptr), shape=(free.size, free.size))

    def update(self, model: Any, E: float, nu: float, u: np.ndarray, state: np.ndarray
               ) -> Update:
        """The model's return mapping at the sample's points and the plate's (its model's,
        or its elastic law) at the plate's, for the displacements ``u`` from ``state`` (all
        points)."""
        eps = self.strain(u)
        s = self.sample_pts
        if s.all():
            return model.update(E, nu, eps, state)
        up = model.update(E, nu, eps[s], state[s])
        if self.plate_model is None:
            stress = eps @ self.D_plate
            tangent = np.repeat(self.D_plate[None], eps.shape[0], axis=0)
            new = state.copy()
            plastic = np.zeros(eps.shape[0], bool)
            region = np.zeros(eps.shape[0], np.int8)
        else:
            pp = ~s
            upp = self.plate_model.update(*self.plate, eps[pp], state[pp])
            stress, tangent = np.empty_like(eps), np.empty((eps.shape[0], 4, 4))
            new, plastic = np.empty_like(state), np.empty(eps.shape[0], bool)
            region = np.empty(eps.shape[0], np.int8)
            stress[pp], tangent[pp], new[pp] = upp.stress, upp.tangent, upp.state
            plastic[pp], region[pp] = upp.plastic, upp.region
        stress[s], tangent[s], new[s] = up.stress, up.tangent, up.state
        plastic[s], region[s] = up.plastic, up.region
        return Update(stress, tangent, new, plastic, region)

    def yield_ratio(self, model: Any, stress: np.ndarray, state: np.ndarray) -> float:
        """The largest yield ratio of the sample's points and, with a plate model, the
        plate's."""
        s = self.sample_pts
        ratio = float(np.max(model.yield_ratio(stress[s], state[s]), initial=0.0))
        if self.plate_model is not None:
            pp = ~s
            ratio = max(ratio, float(np.max(self.plate_model.yield_ratio(stress[pp],
                                                                        state[pp]))))
        return ratio

    def strain(self, u: np.ndarray) -> np.ndarray:
        """(ne * nq, 4) Mandel strains of the displacements ``u`` (the full dof vector)."""
        ue = u[self.edof_u]
        return np.einsum("eqij,ej->eqi", self.B, ue).reshape(-1, 4)

    def residual_only(self, u: np.ndarray, stress: np.ndarray) -> tuple[np.ndarray, float]:
        """The residual (ndof,), N (pressure rows scaled by ``ps``), and its load scale, N: the
        largest element force (the far field's on the near zone included)."""
        res, fu = self._residual(u, stress)
        load = float(np.max(np.abs(fu)))
        if self.far_dofs.size:
            f_far = self.far_S @ u[self.far_dofs]
            res[self.far_dofs] += f_far
            load = max(load, float(np.max(np.abs(f_far))))
        return res, max(load, 1e-300)

    def far_energy(self, u: np.ndarray) -> float:
        """The elastic energy of the condensed far field, J."""
        x = u[self.far_dofs]
        return 0.5 * float(x @ self.far_S @ x)

    def stored_energy(self, u: np.ndarray, stress: np.ndarray) -> float:
        """The elastic energy stored at the displacements ``u`` and stresses ``stress``
        (J): ``int s:s / (4 G) dV`` and the volumetric ``int p^2 / (2 K) dV``, with the
        condensed far field's (:meth:`far_energy`).

        In the mixed form the volumetric part is taken as the element sums of ``int (p tr
        eps - p^2 / (2 K)) dV``, which equals ``int p^2 / (2 K) dV`` over the whole mesh
        once the pressure equations hold (they are assembled over the elements: ``p``
        is continuous), and so adds up exactly with the far field's energy, whose
        condensed form carries the same terms of its own elements.
        """
        s = stress @ P_DEV
        dev = float(np.sum(np.einsum("gi,gi->g", s, s) / (4.0 * self.Gq) * self.w.ravel()))
        if self.mixed:
            ue, pe = u[self.edof_u], u[self.edof[:, 12:]]
            vol = float(np.einsum("ei,eij,ej->", pe, self.Bp, ue)
                        - 0.5 * np.einsum("ei,eij,ej->", pe, self.Cp, pe))
        else:
            p = stress @ ONE / 3.0
            vol = float(np.sum(0.5 * self.inv_Kq * p * p * self.w.ravel()))
        return dev + vol + self.far_energy(u)

    def _residual(self, u: np.ndarray, stress: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The near zone's assembled residual (ndof,) and its elements' displacement forces
        (ne, 12), N."""
        ne, nq = self.w.shape
        s = (stress @ self.proj).reshape(ne, nq, 4)
        ue, pe = u[self.edof_u], u[self.edof[:, 12:]]
        fu = np.matmul(np.swapaxes(self.B, 2, 3), (s * self.w[:, :, None])[..., None]
                       ).sum(axis=1)[..., 0] + np.matmul(pe[:, None, :], self.Bp)[:, 0]
        fp = np.matmul(self.Bp, ue[..., None])[..., 0] - np.matmul(self.Cp, pe[..., None])[..., 0]
        res = np.bincount(self.edof.ravel(), weights=np.concatenate([fu, fp], axis=1).ravel(),
                          minlength=self.ndof)
        return res, fu

    def matvec(self, data: np.ndarray, x: np.ndarray) -> np.ndarray:
        """``A x`` of the entries ``data`` (CSR order)."""
        return sp.csr_matrix((data, self.col_u, self.indptr), shape=(self.ndof, self.ndof)) @ x


class _NearZoneTooSmall(Exception):
    """The plastic zone, or the contact, reached the edge of the condensed near zone."""


def solve_path(
    mesh: Mesh, E: float, nu: float, model: Any, radius: float, deltas: np.ndarray,
    unload: bool = False, *, rtol: float = RTOL, max_iter: int = MAX_ITER,
    punch: str | None = None, max_cuts: int = MAX_CUTS,
    plate: tuple[float, float] | None = None, interface: str = "frictionless",
    plate_model: Any = None, near: float | None = -1.0,
) -> PlasticCurve:
    """Load a rigid sphere into a plastic sample and, with ``unload``, lift it back in the
    same steps until it leaves the surface (module docstring).

    Parameters
    ----------
    mesh : Mesh
        The sample (and plate) mesh, :func:`ssw.contact.mesh.build_mesh`.
    E : float
        The sample's Young's modulus, Pa.
    nu : float
        The sample's Poisson's ratio.
    model : model of :mod:`ssw.constitutive` or None
        The sample's constitutive law (None: linear elastic).
    radius : float
        The sphere's radius, m (``punch``: the punch's).
    deltas : array_like
        Increasing indentations > 0, m: the loading increments.
    unload : bool
        Lift the sphere back after loading, in the loading's step.
    rtol : float
        Residual tolerance relative to the load scale.
    max_iter : int
        Newton iterations per increment.
    punch : str or None
        ``smooth`` or ``rough``: a rigid flat punch of radius ``radius`` instead of the
        sphere (frictionless, or without slip under its face; the limit-load check of Eason
        & Shield 1960).
    max_cuts : int
        Halvings of an increment whose Newton iteration fails (``stats['cutbacks']`` counts
        them; the path then holds the intermediate indentations).
    plate : tuple of float or None
        A plate's ``(E Pa, nu)`` on a mesh with a plate.
    interface : str
        Plate-sample tie: ``frictionless`` | ``bonded`` (``_Model``).
    plate_model : model of :mod:`ssw.constitutive` or None
        The plate's constitutive law (None: elastic).
    near : float or None
        Radius (m) of the near zone about the contact point outside which the mesh is
        condensed (the elastic far field, ``_Model._condense``); -1 (default):
        :func:`near_radius` of the path, doubled while the plastic zone or the contact
        reaches its edge; None: no condensation.

    Returns
    -------
    PlasticCurve
        Per increment and the path's scalars.

    Raises
    ------
    ConfigError
        On bad arguments.
    SolverError
        On an increment that does not converge; :class:`ContactZoneError` when the contact
        reaches the last candidate node (half the sphere's radius).
    """
    if model is None:
        model = LinearElastic()
    if not hasattr(model, "update"):
        raise ConfigError("soil_model", model, "a model of ssw.constitutive")
    if plate_model is not None and not hasattr(plate_model, "update"):
        raise ConfigError("plate_model", plate_model, "a model of ssw.constitutive")
    deltas = np.asarray(deltas, float)
    if deltas.ndim != 1 or deltas.size < 1 or np.any(np.diff(deltas) <= 0) or deltas[0] <= 0:
        raise ConfigError("deltas", deltas, "increasing indentations > 0 m")
    if punch not in (None, "smooth", "rough"):
        raise ConfigError("punch", punch, "smooth | rough (or none: the sphere)")
    if near is not None and near < 0:
        near = near_radius(mesh, E, nu, radius, float(deltas[-1]), punch, plate)
    extent = float(np.max(np.hypot(mesh.nodes[:, 0], mesh.nodes[:, 1] - mesh.top)))
    t0 = time.perf_counter()
    restarts = 0
    while True:
        if near is not None and near >= extent:
            near = None
        try:
            curve = _path(mesh, E, nu, model, radius, deltas, unload, rtol, max_iter, punch,
                          max_cuts, plate, interface, plate_model, near, t0)
            curve.stats["near_restarts"] = restarts
            return curve
        except _NearZoneTooSmall:
            near, restarts = 2.0 * near, restarts + 1


#: Near zone of a condensed path: this many times the larger of ``sqrt(2 R delta)`` at the
#: last indentation (the sphere's section at the depth delta below the flat surface: the
#: contact radius of a plastic indentation without pile-up; Hertz's is ``sqrt(R delta)``)
#: and the plate's spreading length, plus the size of the mesh's elements there (the ring
#: of elements that meets the far field then lies beyond). The plastic zone is checked
#: against its edge (the path is solved again with a zone twice as large when it reaches
#: it, ``stats['near_restarts']``). A von Mises half-space yields to 0.81 (E/Y 20) and
#: 0.87 (E/Y 100) times ``sqrt(2 R delta)`` below the surface; a larger zone only costs
#: time (1.5 took 1.6 times as long on the study's curve; the condensation is exact).
NEAR = 1.0


def near_radius(mesh: Mesh, E: float, nu: float, radius: float, d_end: float,
                punch: str | None = None, plate: tuple[float, float] | None = None) -> float:
    """The near zone's radius (m) of a path to ``d_end`` (m): :data:`NEAR` times the larger
    of ``sqrt(2 R d_end)`` (``R`` the sphere's ``radius``; a punch: its radius) and, with a
    plate, the length over which it spreads a load on the sample, ``(2 D (1 - nu^2) /
    E)^(1/3)``, ``D = E_p t^3 / (12 (1 - nu_p^2))`` (a plate on an elastic half-space),
    plus the largest element size of the mesh about that distance from the contact point.

    Parameters
    ----------
    mesh : Mesh
        The mesh (its plate's thickness).
    E : float
        The sample's Young's modulus, Pa.
    nu : float
        The sample's Poisson's ratio.
    radius : float
        The sphere's (or punch's) radius, m.
    d_end : float
        The path's largest indentation, m.
    punch : str or None
        A flat punch (``smooth`` | ``rough``), or None: the sphere.
    plate : tuple of float or None
        The plate's ``(E Pa, nu)``.

    Returns
    -------
    float
        The radius, m.
    """
    a = float(radius) if punch is not None else float(np.sqrt(2.0 * radius * d_end))
    t = float(mesh.top)
    if plate is not None and t > 0:
        D = plate[0] * t**3 / (12.0 * (1.0 - plate[1] ** 2))
        a = max(a, (2.0 * D * (1.0 - nu * nu) / E) ** (1.0 / 3.0))
    r = NEAR * a
    # the ring of elements that meets the far field lies beyond r: one element size more
    xy = mesh.nodes[mesh.tri[:, :3]].mean(axis=1)
    dist = np.hypot(xy[:, 0], xy[:, 1] - t)
    h = element_sizes(mesh.nodes, mesh.tri)[(dist > 0.8 * r) & (dist < 1.25 * r)]
    return r + (float(np.max(h)) if h.size else 0.0)


def _path(mesh: Mesh, E: float, nu: float, model: Any, radius: float, deltas: np.ndarray,
          unload: bool, rtol: float, max_iter: int, punch: str | None, max_cuts: int,
          plate: tuple[float, float] | None, interface: str, plate_model: Any,
          near: float | None, t0: float) -> PlasticCurve:
    """The path of :func:`solve_path` with the near zone ``near`` (m; None: the whole
    mesh). Raises ``_NearZoneTooSmall`` when the plastic zone reaches the near zone's
    edge elements, or the contact its last candidate short of half the sphere's radius."""
    mixed = all(getattr(m, "isochoric", False) for m in (model, plate_model) if m is not None)
    fe = _Model(mesh, E, nu, radius, punch, mixed=mixed, plate=plate, interface=interface,
                plate_model=plate_model, near=near)
    ne, nq = fe.w.shape
    state = initial_state(ne * nq)
    last = (None, np.zeros(ne * nq, bool))  # the last converged tangent (elastic at first)
    u = np.zeros(fe.ndof)
    res = np.zeros(fe.ndof)  # the residual at u
    tol = 0.0  # the residual tolerance of the last increment, N
    trend = None  # du / d delta of the last increment when it was plastic
    active = np.zeros(fe.cand.size, bool)
    path = list(deltas)
    branch = [0] * deltas.size
    if unload:
        down = deltas[-1] - (deltas[-1] / deltas.size) * np.arange(1, deltas.size + 1)
        path += [*down[down > 0], 0.0]
        branch += [1] * int(np.count_nonzero(down > 0) + 1)
    out: dict[str, list] = {k: [] for k in (
        "delta", "force", "a", "work", "vol", "depth", "rad", "it", "ratio")}
    work = 0.0
    first = (None, None)
    last_elastic = None
    residual = interface_residual = None
    load_ref = 0.0  # the largest load scale of the path: a floor once the load is gone
    k, d_prev, cuts, spans, spanned, stalled = 0, 0.0, 0, 0, 0, 0
    h0 = float(deltas[0])  # the first (and uniform) step
    ring = np.repeat(fe.ring, nq)
    upd = fe.update(model, E, nu, u, state)
    while k < len(path):
        if k > 0 and not last[1].any():
            # elastic: the path is affine in delta while the active set holds and no point
            # yields; those increments need no Newton iteration (_elastic_span)
            span = _elastic_span(fe, model, E, nu, u, res, state, active, path, k, d_prev,
                                 tol)
            for d, u_d, res_d, upd_d in span:
                u, res, upd, d_prev = u_d, res_d, upd_d, d
                force = float(-res[fe.cand_dof][active].sum())
                ratio = fe.yield_ratio(model, upd.stress, state)
                if first[0] is None and force > 0:
                    last_elastic = (force, d, ratio)
                gap = np.clip(fe.g0 - d - u[fe.cand_dof], 0.0, None)
                _record(out, fe, state, d, force, edge_radius(fe.cand_r, gap, active), work,
                        0, ratio)
                k += 1
            if span:
                last = (upd.tangent, upd.plastic)
                spans, spanned = spans + 1, spanned + len(span)
            if k >= len(path):
                break
        d = path[k]
        target = fe.g0 - d
        tol_g = 1e-9 * max(abs(d), fe.h_min * 1e-6)
        step = abs(d - d_prev)
        u_start, active_start = u.copy(), active.copy()
        fe.begin_increment()
        if trend is not None and branch[k] == branch[k - 1]:
            u = u + (d - d_prev) * trend  # the last plastic increment's rate: a predictor
        prev, was_elastic = np.inf, False
        ahead = None  # the update and residual at u, when the line search computed them
        best: tuple | None = None  # the equilibrium iterate of least residual (a stall)
        for it in range(max_iter):
            upd, known = ahead if ahead is not None else (fe.update(model, E, nu, u, state),
                                                          None)
            ahead = None
            # the first iteration of an increment takes the last converged tangent (at the
            # committed state the return cannot tell loading from unloading)
            tangent, plastic = (last if it == 0 else (upd.tangent, upd.plastic))
            res, load = known if known is not None else fe.residual_only(u, upd.stress)
            lam = -res[fe.cand_dof]
            load_ref = max(load_ref, load)
            tol = rtol * max(load, 1e-6 * load_ref)
            gap = target - u[fe.cand_dof]
            new_active = np.where(active, lam > tol, gap < -tol_g)
            if 0 < it < SET_UPDATES and not np.array_equal(new_active, active):
                # semismooth Newton: the set follows the iterate (Hintermueller et al. 2003)
                active = new_active
            free = fe.free_dofs(active)
            jump = np.zeros(fe.ndof)
            jump[fe.cand_dof[active]] = target[active] - u[fe.cand_dof[active]]
            err = float(np.max(np.abs(res[free]), initial=0.0))
            if it > 0 and (best is None or err < best[0]) and not np.any(jump) \
                    and np.array_equal(new_active, active):
                best = (err, u.copy(), upd, res, lam, load)
            if it > 0 and err <= tol and not np.any(jump):
                if np.array_equal(new_active, active):
                    break
                active, prev = new_active, np.inf
                continue
            elastic = err > prev and not was_elastic  # one elastic step, then Newton again
            prev = err
            # the Newton matrix, assembled only now that a step is needed
            data = fe.elastic_matrix() if elastic else fe.matrix(tangent, plastic)
            for _ in range(2):
                if elastic:
                    # Newton stalls or leaps (a nearly singular perfectly plastic tangent):
                    # a step with the elastic tangent, a contraction for the return mapping
                    data = fe.elastic_matrix()
                rhs = -res / fe.scale
                if np.any(jump):
                    rhs -= fe.matvec(data, jump)
                try:
                    # an inexact Newton step: its linear residual a tenth of the tolerance
                    du = fe.solve(data, free, rhs[free], KRYLOV_FORCING * tol / fe.scale)
                except RuntimeError:  # a singular consistent tangent (e.g. a region at
                    if elastic:       # the apex): the elastic tangent's step instead
                        raise SolverError(f"plastic contact: singular Newton matrix at "
                                          f"delta = {d:.4g} m") from None
                    elastic = True
                    continue
                if elastic or (np.all(np.isfinite(du))
                               and np.max(np.abs(du), initial=0.0) <= STEP_BOUND * step):
                    break
                elastic = True
            if not np.all(np.isfinite(du)):
                raise SolverError(f"plastic contact: singular Newton matrix at delta = {d:.4g} m")
            if not np.any(jump) and not elastic:
                # backtracking on the residual: a step that does not lower it is halved, and
                # after LINE_SEARCH halvings replaced by an elastic-tangent step
                for _ in range(LINE_SEARCH):
                    trial_u = u.copy()
                    trial_u[free] += du
                    t_upd = fe.update(model, E, nu, trial_u, state)
                    r_t = fe.residual_only(trial_u, t_upd.stress)
                    if np.max(np.abs(r_t[0][free]), initial=0.0) < err:
                        ahead = (t_upd, r_t)
                        break
                    du = 0.5 * du
                else:
                    du = fe.solve(fe.elastic_matrix(), free, -res[free] / fe.scale)
            was_elastic = elastic
            u[free] += du
            u += jump
        else:
            if best is not None and best[0] <= STALL_RTOL * best[5]:  # a stall: accepted
                _, u, upd, res, lam, load = best
                stalled += 1
            elif step > h0 * 0.5 ** max_cuts * (1 + 1e-9):
                # cut the increment in two: back to the last converged state
                u, active, trend = u_start, active_start, None
                path.insert(k, 0.5 * (d_prev + d))
                branch.insert(k, branch[k])
                cuts += 1
                continue
            else:
                hint = ("; a perfectly plastic model with corners (tresca) may stall there: "
                        "a small hardening (e.g. E/100) restores Newton's convergence"
                        if getattr(model, "hardening", None) == 0.0 else "")
                raise SolverError(
                    f"plastic contact: increment {k} (delta = {d:.6g} m) did not converge in "
                    f"{max_iter} Newton iterations (residual {err:.3g} N, load scale "
                    f"{load:.3g} N), its step cut to {step:.3g} m{hint}")
        trend = (u - u_start) / (d - d_prev) if upd.plastic.any() else None
        d_prev = d
        last = (upd.tangent, upd.plastic)
        dep = upd.state[:, :4] - state[:, :4]
        work += float(np.sum(np.einsum("gi,gi->g", upd.stress, dep) * fe.w.ravel()))
        state = upd.state
        if np.any(state[ring, 4] > 0):
            raise _NearZoneTooSmall
        force = float(lam[active].sum())
        ratio = fe.yield_ratio(model, upd.stress, state)
        if first[0] is None:
            if np.any(upd.plastic):
                if last_elastic is not None:
                    f_el, d_el, r_el = last_elastic
                    first = (f_el / r_el ** 3, d_el / r_el ** 2)
            else:
                last_elastic = (force, d, ratio) if force > 0 else last_elastic
        gap = np.clip(target - u[fe.cand_dof], 0.0, None)
        if active.size and active[-1]:
            if fe.cand_short:
                raise _NearZoneTooSmall
            if punch is None:
                raise ContactZoneError(
                    f"the contact zone reached the last candidate node (r = "
                    f"{fe.cand_r[-1]:.4g} m, half the sphere's radius): an indentation "
                    f"beyond the small-strain contact's reach")
        _record(out, fe, state, d, force, edge_radius(fe.cand_r, gap, active), work, it, ratio)
        if branch[k] == 1 and not active.any():
            residual = float(-u[fe.axis_dof])
            interface_residual = float(-u[fe.interface_axis_dof])
            branch = branch[: k + 1]
            break
        k += 1
    stored = fe.stored_energy(u, upd.stress)
    stats = {"nodes": fe.n, "elements": fe.n_elements, "near_elements": ne, "dofs": fe.ndof,
             "candidates": fe.cand.size, "near_radius": near,
             "increments": len(out["delta"]), "newton_iterations": int(np.sum(out["it"])),
             "elastic_spans": spans, "spanned_increments": spanned,
             "factorizations": fe.factorizations, "lu_reused": fe.lu_reused,
             "krylov_iterations": fe.krylov, "cutbacks": cuts, "stalled": stalled,
             **fe.far_stats,
             "wall_total": time.perf_counter() - t0}
    return PlasticCurve(
        np.array(out["delta"]), np.array(out["force"]), np.array(branch, np.int8),
        np.array(out["a"]), np.array(out["work"]), np.array(out["vol"]),
        np.array(out["depth"]), np.array(out["rad"]), np.array(out["it"]),
        np.array(out["ratio"]), first[0], first[1], residual, stored, stats, interface_residual)


def _record(out: dict[str, list], fe: _Model, state: np.ndarray, d: float, force: float,
            a: float, work: float, it: int, ratio: float) -> None:
    """Append one increment's outputs to ``out``."""
    yielded = state[:, 4] > 0
    out["delta"].append(d)
    out["force"].append(force)
    out["a"].append(a)
    out["work"].append(work)
    out["vol"].append(float(np.sum(fe.w.ravel()[yielded])))
    out["depth"].append(float(fe.top - np.min(fe.zq.ravel()[yielded], initial=fe.top)))
    out["rad"].append(float(np.max(fe.rq.ravel()[yielded], initial=0.0)))
    out["it"].append(it)
    out["ratio"].append(ratio)


def _elastic_span(fe: _Model, model: Any, E: float, nu: float, u: np.ndarray,
                  res: np.ndarray, state: np.ndarray, active: np.ndarray, path: list,
                  k: int, d0: float, tol: float) -> list[tuple]:
    """The increments ``path[k:]`` reached from the converged elastic state ``(u, res)`` at
    ``d0`` with the active set ``active`` unchanged and no point yielding.

    In that span the problem is linear: ``u(d) = u + (d - d0) v`` with ``v`` the response
    to a unit indentation on the active set (one solve with the elastic matrix's kept LU),
    ``res(d) = res + (d - d0) K v`` (``K v`` vanishes on the free dofs, so each increment
    keeps the converged residual), the gaps and contact forces affine in ``d``. An increment
    joins the span while its gaps stay open, its contact forces stay above the tolerance
    ``tol`` (N) (the active set's test of the Newton iteration) and the return mapping at
    its strain leaves every point elastic; the span stops before the first that fails (it
    is solved by Newton's iteration).

    Returns
    -------
    list of tuple
        Per increment of the span: ``(delta m, u, residual N, Update)``.
    """
    out: list[tuple] = []
    if not active.any():
        return out
    free = fe.free_dofs(active)
    data = fe.elastic_matrix()
    jump = np.zeros(fe.ndof)
    jump[fe.cand_dof[active]] = -1.0
    v = jump.copy()
    v[free] = fe.factor(data, free).solve(-fe.matvec(data, jump)[free], trans="T")  # exact
    dres = fe.matvec(data, v) * fe.scale
    dres[free] = 0.0
    for j in range(k, len(path)):
        d = path[j]
        u_d = u + (d - d0) * v
        res_d = res + (d - d0) * dres
        lam = -res_d[fe.cand_dof]
        gap = fe.g0 - d - u_d[fe.cand_dof]
        tol_g = 1e-9 * max(abs(d), fe.h_min * 1e-6)
        if np.any(active & ~(lam > tol)) or np.any(~active & (gap < -tol_g)):
            break
        upd = fe.update(model, E, nu, u_d, state)
        if upd.plastic.any():
            break
        out.append((d, u_d, res_d, upd))
    return out


def contact_mesh(radius: float, d_max: float, *, fine: float = 8.0, growth: float = 0.3,
                 domain: float = 40.0, plate_thickness: float = 0.0,
                 plate_radius: float = 0.0, contact_radius: float | None = None) -> Mesh:
    """A mesh scaled to the contact: the plastic wall's tables and ``ssw bench contact
    --plastic`` (the elastic engine's meshes are graded for indentations down to 1e-9 m,
    far finer at the contact point than a plastic path needs).

    Parameters
    ----------
    radius : float
        The sphere's radius ``R``, m.
    d_max : float
        The largest indentation, m: the Hertz contact radius ``a = sqrt(R d_max)`` sets the
        domain (``domain x a``).
    fine : float
        The element at the contact point is ``a_c / fine``.
    growth : float
        Element size over the distance from the contact point beyond it.
    domain : float
        Domain size over ``a`` (a plate's: 4 plate radii at least).
    plate_thickness : float
        The plate's thickness, m (0: none; a plate has 2 element layers at least).
    plate_radius : float
        The plate's radius, m.
    contact_radius : float or None
        The contact radius ``a_c`` to resolve, m (default ``a``; on a stiff plate the
        sphere's own contact is smaller: :func:`plate_contact_radius`).

    Returns
    -------
    Mesh
        The mesh (:func:`ssw.contact.mesh.build_mesh`).
    """
    from ssw.contact.mesh import MeshSettings, build_mesh

    a = float(np.sqrt(radius * d_max))
    a_c = a if contact_radius is None else min(a, float(contact_radius))
    t, rp = float(plate_thickness), float(plate_radius)
    if t <= 0:
        return build_mesh(0.0, 0.0, MeshSettings(domain * a, domain * a, a_c / fine, growth,
                                                 8.0 * a, 1))
    dom = max(domain * a, 4.0 * rp)
    return build_mesh(t, rp, MeshSettings(dom, dom, min(a_c / fine, t / 2), growth,
                                          max(8.0 * a, 0.05 * dom), 2))


def plate_contact_radius(radius: float, d_max: float, soil: tuple[float, float],
                         plate: tuple[float, float]) -> float:
    """The sphere's contact radius on a plate stiffer than its sample, m: Hertz's on the
    plate's material at the force Hertz gives on the sample at ``d_max``,
    ``a_p = sqrt(R d_max) (E*_s / E*_p)^(1/3)`` (``F = 4/3 E*_s sqrt(R) d^1.5`` and
    ``a^3 = 3 F R / (4 E*_p)``; Johnson 1985, sec. 4.2), ``sqrt(R d_max)`` when the plate
    is the softer. A plate spreads the load, so the force is larger and the estimate a lower
    bound: a mesh that resolves it resolves the contact.

    Parameters
    ----------
    radius : float
        The sphere's radius ``R``, m.
    d_max : float
        The largest indentation, m.
    soil : tuple of float
        The sample's ``(E Pa, nu)``.
    plate : tuple of float
        The plate's ``(E Pa, nu)``.

    Returns
    -------
    float
        The contact radius, m.
    """
    es = soil[0] / (1.0 - soil[1] ** 2)
    ep = plate[0] / (1.0 - plate[1] ** 2)
    return float(np.sqrt(radius * d_max) * min(1.0, es / ep) ** (1.0 / 3.0))


def johnson_first_yield(E: float, nu: float, Y: float, radius: float) -> tuple[float, float]:
    """Hertz force (N) and indentation (m) at first yield of a von Mises half-space under a
    rigid sphere (Johnson 1985, sec. 6.1): ``p0 = k Y`` with ``k`` the peak of
    ``(sigma_r - sigma_z) / p0`` on the axis (1.61 at nu 0.3), ``a = pi p0 R / (2 E*)``,
    ``F = 2/3 pi a^2 p0``, ``delta = a^2 / R``; ``k`` computed from the axis stresses."""
    from ssw.constitutive.yield_index import first_yield_ratio

    k = first_yield_ratio(nu)
    Es = E / (1.0 - nu * nu)
    p0 = k * Y
    a = np.pi * p0 * radius / (2.0 * Es)
    return float(2.0 / 3.0 * np.pi * a * a * p0), float(a * a / radius)


#: The mesh of a plastic path (``mesh="path"``) resolves the contact radii from that of
#: this share of the path's last indentation on: its element at the contact point is
#: ``mesh_growth sqrt(R share delta_end)`` (at least the config's ``mesh_size_contact``);
#: the error this costs against a converged mesh is stated in ssw/bench/plastic.py.
PATH_RESOLVED = 1.0
#: Plastic mesh choices of :func:`solve_plastic_scene`.
PLASTIC_MESHES = ("path", "study")


def path_mesh_settings(settings: Any, radius: float, d_end: float,
                       plate_thickness: float = 0.0, contact_radius: float | None = None
                       ) -> Any:
    """The mesh settings of a plastic path: the study's (domain, boundaries, growth,
    largest element, plate layers) with the element at the contact point scaled to the
    path (:data:`PATH_RESOLVED`; at most a plate layer).

    Parameters
    ----------
    settings : ssw.contact.mesh.MeshSettings
        The study's mesh settings (:func:`ssw.contact.mesh.mesh_settings`).
    radius : float
        The sphere's radius, m.
    d_end : float
        The path's largest indentation, m.
    plate_thickness : float
        The plate's thickness, m (0: none).
    contact_radius : float or None
        A smaller contact radius at ``d_end`` to resolve, m (a yielding plate's own,
        :func:`plate_contact_radius`).

    Returns
    -------
    ssw.contact.mesh.MeshSettings
        The settings with ``size_contact`` replaced.
    """
    from dataclasses import replace

    a = float(np.sqrt(radius * d_end))
    if contact_radius is not None:
        a = min(a, float(contact_radius))
    h = settings.growth * a * float(np.sqrt(PATH_RESOLVED))
    if plate_thickness > 0:
        h = min(h, plate_thickness / settings.plate_layers)
    return replace(settings, size_contact=max(settings.size_contact, h))


def solve_plastic_scene(
    soil: tuple[float, float], model: Any, radius: float, contact_cfg: dict[str, Any],
    unload: bool = False, plate: tuple[float, float] | None = None,
    plate_thickness: float = 0.0, plate_model: Any = None, mesh: str = "path",
) -> PlasticCurve:
    """The plastic curve of a sphere on a sample, through a plate, with the contact
    config's domain (a finite block's boundaries included), mesh growth and increments
    (:func:`ssw.contact.scene.settings_of`, :func:`ssw.contact.scene.indentation_steps`).

    Parameters
    ----------
    soil : tuple of float
        The sample's ``(E Pa, nu)``.
    model : model of :mod:`ssw.constitutive` or None
        The sample's law (None: elastic).
    radius : float
        The sphere's radius, m.
    contact_cfg : dict
        The config's ``contact`` section (``plate_diameter`` and ``interface`` too).
    unload : bool
        Lift the sphere back after loading.
    plate : tuple of float or None
        The plate's ``(E Pa, nu)`` when ``plate_thickness > 0``.
    plate_thickness : float
        The plate's thickness, m (0: none).
    plate_model : model of :mod:`ssw.constitutive` or None
        The plate's law (None: elastic).
    mesh : str
        ``path``: the study's mesh with its element at the contact point scaled to the path
        (:func:`path_mesh_settings`); ``study``: the elastic engine's mesh as configured.

    Returns
    -------
    PlasticCurve
        The path (:func:`solve_path`).

    Raises
    ------
    ConfigError
        On a plate without its elastic constants, or an unknown ``mesh``.
    """
    from ssw.contact.mesh import build_mesh, mesh_settings
    from ssw.contact.scene import indentation_steps, settings_of

    if mesh not in PLASTIC_MESHES:
        raise ConfigError("--plastic-mesh", mesh, " | ".join(PLASTIC_MESHES))
    cfg = settings_of(contact_cfg)
    t = float(plate_thickness)
    if t > 0 and plate is None:
        raise ConfigError("plate", None, "the plate's (E Pa, nu) when plate_thickness > 0")
    deltas = indentation_steps(float(cfg["delta_max"]), int(cfg["steps"]))
    settings = mesh_settings(cfg)
    if mesh == "path":
        a_c = None
        if plate_model is not None and t > 0:
            a_c = plate_contact_radius(radius, float(deltas[-1]), soil, plate)
        settings = path_mesh_settings(settings, radius, float(deltas[-1]), t, a_c)
    m = build_mesh(t, 0.5 * float(cfg["plate_diameter"]) if t > 0 else 0.0, settings)
    curve = solve_path(m, float(soil[0]), float(soil[1]), model, radius, deltas, unload,
                       plate=plate if t > 0 else None, interface=str(cfg["interface"]),
                       plate_model=plate_model if t > 0 else None)
    curve.stats["mesh_size_contact"] = settings.size_contact
    return curve


#: ``ssw_kind`` of a plastic curve file.
KIND = "plastic_contact_curve"
#: Per-increment datasets of a plastic curve file: name -> (attribute, units, description).
DATASETS = {
    "delta": ("delta", "m", "indentation of the rigid sphere (loading, then unloading)"),
    "force": ("force", "N", "reaction force on the sphere"),
    "branch": ("branch", "1", "0 loading, 1 unloading"),
    "contact_radius": ("contact_radius", "m", "contact radius"),
    "dissipated": ("dissipated", "J", "cumulative plastic work"),
    "plastic_volume": ("plastic_volume", "m^3", "volume of the points that have yielded"),
    "plastic_depth": ("plastic_depth", "m", "depth of the plastic zone"),
    "plastic_radius": ("plastic_radius", "m", "radius of the plastic zone"),
    "iterations": ("iterations", "1", "Newton iterations of the increment"),
    "yield_ratio": ("yield_ratio", "1", "largest q / Y"),
}


def summary(curve: PlasticCurve) -> dict[str, Any]:
    """The scalars of a path (SI): first yield, permanent set, works."""
    under, total = curve.interface_residual, curve.residual_indentation
    return {"first_yield_force": curve.first_yield_force,
            "first_yield_delta": curve.first_yield_delta,
            "residual_indentation": total,
            "interface_residual_indentation": under,
            "plate_thinning": None if under is None or total is None else total - under,
            "dissipated_work": curve.dissipated_work, "external_work": curve.external_work,
            "stored_energy": curve.stored_energy,
            "force_max": float(np.max(curve.force)) if curve.force.size else 0.0}


def write_plastic_curve(path: Any, curve: PlasticCurve, inputs: dict[str, Any]) -> None:
    """Write ``curve`` (both branches) and its inputs to HDF5 ``path`` atomically."""
    from ssw.h5io import atomic_h5, write_dataset

    with atomic_h5(path, kind=KIND, inputs=inputs) as f:
        for name, (attr, units, text) in DATASETS.items():
            write_dataset(f, name, getattr(curve, attr), units, text)
        for k, v in summary(curve).items():
            f.attrs[k] = np.nan if v is None else v
        st = f.create_group("stats")
        for k, v in curve.stats.items():
            st.attrs[k] = v


def read_plastic_curve(path: Any) -> dict[str, Any]:
    """The datasets and scalars of a plastic curve file (None for an unknown scalar)."""
    import h5py

    from ssw.h5io import check_kind, read_inputs

    with h5py.File(path, "r") as f:
        check_kind(f, KIND)
        out = {name: f[name][()] for name in DATASETS}
        for k in ("first_yield_force", "first_yield_delta", "residual_indentation",
                  "interface_residual_indentation", "plate_thinning", "dissipated_work",
                  "external_work", "stored_energy", "force_max"):
            v = float(f.attrs.get(k, np.nan))
            out[k] = None if np.isnan(v) else v
        out["inputs"] = read_inputs(f)
    return out


def loading_curve(curve: PlasticCurve, inputs: dict[str, Any]) -> Any:
    """The loading branch of a plastic path as a :class:`ssw.curve.ForceCurve` (what a
    study's contact job writes for a scene with a ``soil_model``; the unloading branch is
    in the plastic curve file, :func:`write_plastic_curve`)."""
    from ssw.curve import ForceCurve

    m = curve.branch == 0
    return ForceCurve(curve.delta[m], curve.force[m], curve.contact_radius[m],
                      {**inputs, **summary(curve)}, dict(curve.stats))


def scene_path(scene: Any, contact_cfg: dict[str, Any], indenter_radius: float,
               plate: tuple[float, float] | None, unload: bool = False, mesh: str = "path"
               ) -> tuple[PlasticCurve, dict[str, Any]]:
    """The plastic path of a scene with a ``soil_model`` or a ``plate_model``, and its
    inputs: :func:`solve_plastic_scene` on the contact config's domain and increments (a
    finite block's settings already applied, :meth:`ssw.sample.Sample.contact_settings`).

    Parameters
    ----------
    scene : ssw.config.Scene
        The scene (its sample's model, None: elastic; its plate's model, None: elastic).
    contact_cfg : dict
        The config's ``contact`` section.
    indenter_radius : float
        The sphere's radius, m.
    plate : tuple of float or None
        The scene's plate ``(E Pa, nu)`` (:func:`ssw.contact.scene.scene_plate`).
    unload : bool
        Lift the sphere back until it leaves the surface.
    mesh : str
        ``path`` | ``study`` (:func:`solve_plastic_scene`).

    Returns
    -------
    tuple
        The :class:`PlasticCurve` and its inputs (dict).
    """
    from ssw.contact.scene import settings_of

    plate_key = scene.plate_material if scene.plate_thickness > 0 else "none"
    plate_model = getattr(scene, "plate_model", None)
    curve = solve_plastic_scene((scene.soil_E, scene.soil_nu), scene.soil_model,
                                indenter_radius, contact_cfg, unload=unload, plate=plate,
                                plate_thickness=scene.plate_thickness,
                                plate_model=plate_model, mesh=mesh)
    inputs = {"soil_E": scene.soil_E, "soil_nu": scene.soil_nu, "plate_material": plate_key,
              "plate_E": plate[0] if plate else None, "plate_nu": plate[1] if plate else None,
              "plate_thickness": float(scene.plate_thickness),
              "indenter_radius": indenter_radius,
              "soil_model": (scene.soil_model.params() if scene.soil_model is not None
                             else {"model": "linear-elastic"}),
              "plate_model": plate_model.params() if plate_model is not None else None,
              "plastic_mesh": mesh, "scene_id": scene.scene_id, **settings_of(contact_cfg)}
    if mesh == "path":
        inputs["plastic_mesh_size_contact"] = float(curve.stats["mesh_size_contact"])
    return curve, inputs


def scene_curve(scene: Any, contact_cfg: dict[str, Any], indenter_radius: float,
                plate: tuple[float, float] | None) -> Any:
    """A study scene with a ``soil_model``: its loading curve (:func:`loading_curve`) of
    :func:`scene_path`."""
    return loading_curve(*scene_path(scene, contact_cfg, indenter_radius, plate))


def _factor(A: Any) -> Any:
    """SuperLU of a symmetric quasi-definite Newton matrix (the u-p blocks: SPD displacement
    block, negative definite pressure block; Vanderbei 1995): a minimum-degree ordering of
    ``A + A^T`` with diagonal pivots, the symmetric structure's fill; partial pivoting (the
    COLAMD ordering) when a diagonal pivot fails."""
    try:
        return splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                    options={"SymmetricMode": True})
    except RuntimeError:
        return splu(A, permc_spec="COLAMD")


def _symmetric_order(lu: Any) -> np.ndarray | None:
    """The elimination order of a SuperLU factorization that kept its diagonal pivots (the
    row permutation its column one): the positions in the order they were eliminated;
    None when pivoting moved a row off the diagonal."""
    if not np.array_equal(lu.perm_r, lu.perm_c):
        return None
    return np.argsort(lu.perm_c)


class _OrderedLU:
    """SuperLU of a Newton matrix in a given elimination order (:func:`_symmetric_order`
    of an earlier factorization of the same free set, whose pattern it shares): the
    minimum-degree ordering, a quarter of a factorization of these matrices, is skipped.
    Solves with the unpermuted matrix, as :func:`_factor`'s."""

    def __init__(self, lu: Any, order: np.ndarray) -> None:
        self.lu, self.order, self.nnz = lu, order, lu.nnz

    @classmethod
    def factor(cls, A: Any, order: np.ndarray) -> _OrderedLU | None:
        """The factorization of ``A`` (CSC, already permuted to ``order``) with diagonal
        pivots in its own order; None when a diagonal pivot fails."""
        try:
            return cls(splu(A, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                            options={"SymmetricMode": True}), order)
        except RuntimeError:
            return None

    def solve(self, rhs: np.ndarray, trans: str = "N") -> np.ndarray:
        """The solution of the unpermuted system (``trans`` as SuperLU's)."""
        x = np.empty_like(rhs)
        x[self.order] = self.lu.solve(rhs[self.order], trans=trans)
        return x
