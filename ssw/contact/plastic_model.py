"""The discrete problem of the elasto-plastic contact (:mod:`ssw.contact.plastic`): one
mesh's Taylor-Hood u-p element written for a nonlinear deviatoric law, its dof maps and
constant blocks, the elastic far field condensed onto a near zone, the Newton matrix
assembled as the elastic matrix plus the plastic elements' change, and its solves.

Discretization (Simo & Hughes 1998, sec. 4.4; de Souza Neto et al. 2008, sec. 15.4): P2
displacements and a continuous P1 mean stress ``p`` (:mod:`ssw.contact.elements`),

    R_u = sum_e int B^T (dev sigma(eps) + p ONE) dV - f = 0,
    R_p = sum_e int N_p (tr eps - p / K) dV = 0,

``sigma(eps)`` the model's return mapping at the quadrature points and its consistent
tangent ``D``; the Newton matrix is ``[[int B^T P_DEV D B, int B^T ONE N_p],
[int N_p ONE^T B, -int N_p N_p / K]]`` (the displacement form of the same element for
models with plastic volume change: ``R_u = sum_e int B^T sigma(eps) dV``, the whole
tangent).

Cost (exact reductions of the same discrete problem):

* the far field: the elements beyond a near zone about the contact point stay elastic and
  unloaded, so they are condensed once onto the dofs they share with the near zone (their
  Schur complement, ``_Model._condense``; Przemieniecki 1963);
* the Newton steps: GMRES (Saad & Schultz 1986) right-preconditioned by the newest
  factorization of an earlier tangent while that is cheaper than factorizing
  (``_Model.solve``), to the linear residual the Newton test needs;
* the Newton matrix: assembled only when a step needs it, as the elastic matrix plus the
  plastic elements' change (``_Model.matrix``), and factored in the elimination order
  the first factorization of its free set chose (``_OrderedLU``); the elastic
  matrix's factorizations are kept per free set.

References
----------
Przemieniecki, J. S. (1963). Matrix structural analysis of substructures. *AIAA J.* 1,
138-147.
Saad, Y. & Schultz, M. H. (1986). GMRES: a generalized minimal residual algorithm for
solving nonsymmetric linear systems. *SIAM J. Sci. Stat. Comput.* 7, 856-869.
Simo, J. C. & Hughes, T. J. R. (1998). *Computational Inelasticity*. Springer.
de Souza Neto, E. A., Peric, D. & Owen, D. R. J. (2008). *Computational Methods for
Plasticity*. Wiley.
Vanderbei, R. J. (1995). Symmetric quasidefinite matrices. *SIAM J. Optim.* 5, 100-113.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from ssw.constitutive.base import Update
from ssw.constitutive.tensors import ONE, P_DEV, SQRT2, bulk_shear, elastic_tangent
from ssw.contact import lu as sparse_lu
from ssw.contact.assembly import (
    element_sizes,
    fixed_free,
    geometric_tolerance,
    pow2,
    split_interface,
    top_surface_weights,
)
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
from ssw.errors import ConfigError

#: Candidates of a condensed path: the top-surface nodes within this share of the near
#: zone's radius (the rest of it: the ring of elements that meets the far field).
NEAR_CANDIDATES = 0.9
#: Elastic LUs kept per path (one per free set: the contact's active set).
LU_CACHE = 8
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
#: A consistent tangent whose largest entry is below this share of the elastic tangent's
#: vanishes (``_Model.matrix``): Drucker-Prager's apex, perfectly plastic (its return
#: fixes the stress, ``ssw.constitutive.drucker_prager``).
VANISHING = 1e-9
#: The share of the elastic tangent a point whose tangent vanishes takes in the Newton
#: matrix. With a zero tangent a zone of points at the apex (the clay under the plate's dent
#: as the sphere lifts: the bilateral tie pulls it to the cone's tension apex) leaves the
#: Newton matrix nearly singular there and the iteration cycles between the apex and the
#: cone at 1e-6 - 1e-4 of the load scale, whatever the step (a table path of ``ssw tof
#: --hits 5 --soil-material compacted_clay --soil-model drucker-prager``: 100-160 points at
#: the apex); with 0.01 it converges (4 stalls within STALL_RTOL, 2 cutbacks, 3.3 s against
#: a failure after 12 s). The converged state is the same: the residual is the exact one.
APEX_STIFFNESS = 0.01
#: Relative residual of a solve meant to be exact (an elastic span's rate, the elastic
#: states of the first-yield search), a thousandth of the Newton test's share of the load
#: (:data:`RTOL <ssw.contact.plastic_path.RTOL>` 1e-8): GMRES preconditioned by the
#: factorization of a free set a few contact dofs away (a low-rank change) reaches it in
#: 7 iterations on average on the study's elastic part (a span's curve moves by 1e-9 of
#: its force from the exact LU's).
EXACT_RTOL = 1e-11


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
        self.nodes, self.tri = nodes, tri
        body = mesh.body.astype(np.int64)
        if has_plate:
            E_el = np.where(body == 1, float(plate[0]), float(E))
            nu_el = np.where(body == 1, float(plate[1]), float(nu))
        else:
            E_el, nu_el = np.full(len(tri), float(E)), np.full(len(tri), float(nu))
        G_e, inv_K_e = (np.asarray(x, float) for x in lame(E_el, nu_el))
        vert, pid, h = self._elements(body, G_e, inv_K_e, mixed)
        Kp = 1.0 / float(inv_K_e[body == 1][0]) if has_plate else 0.0
        Gp = float(G_e[body == 1][0]) if has_plate else 0.0
        #: the plate's and the sample's elastic matrices (Mandel), Pa
        self.D_plate = 2.0 * Gp * P_DEV + Kp * np.outer(ONE, ONE)
        self.D_sample = elastic_tangent(*bulk_shear(E, nu))
        self.plate = (float(plate[0]), float(plate[1])) if has_plate else None
        self.plate_model = plate_model if has_plate else None
        udof = self._dofs(mesh, pairs, vert, pid, interface, radius, punch, near)
        soil_n = pairs[:, 0]
        #: u_z of the plate-sample interface on the axis (the top without a plate)
        self.interface_axis_dof = (int(udof[soil_n[np.argmin(nodes[soil_n, 0])], 1])
                                   if has_plate else self.axis_dof)
        self.h_min = float(np.min(h))
        ne, nq = self.w.shape
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
        self._sparsity()
        self.patterns: dict[bytes, tuple] = {}  # of restricted(): the newest few
        self._elastic_data: np.ndarray | None = None  # the elastic matrix, once assembled
        self._lus: dict[bytes, Any] = {}
        #: a fill-reducing order per free set (its first factorization's): later ones
        #: of the same free set skip the ordering
        self._orders: dict[bytes, np.ndarray] = {}
        self._pre: tuple | None = None  # the newest factorization: (lu, free, data)
        self._stale = self._direct = False
        self.factorizations = self.lu_reused = self.krylov = 0

    def _elements(self, body: np.ndarray, G_e: np.ndarray, inv_K_e: np.ndarray,
                  mixed: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The elements' quadrature (points ``rq``, ``zq``, weights ``w`` with ``2 pi r``),
        strain rows ``B``, the scaled pressure unknowns and their blocks ``Bp``, ``Cp``
        (shear moduli ``G_e`` Pa and inverse bulk moduli ``inv_K_e`` 1/Pa per element);
        returns the vertices carrying a pressure, their index per node and the element
        sizes (m)."""
        nodes, tri = self.nodes, self.tri
        n = len(nodes)
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
        # Mandel strain rows (e_rr, e_zz, e_tt, sqrt(2) e_rz) of (ur_0..5, uz_0..5)
        B = np.zeros((len(tri), nq, 4, 12))
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
        return vert, pid, h

    def _dofs(self, mesh: Mesh, pairs: np.ndarray, vert: np.ndarray, pid: np.ndarray,
              interface: str, radius: float, punch: str | None, near: float | None
              ) -> np.ndarray:
        """The dof maps, the fixed dofs and the contact's candidates (the top-surface nodes
        within half the sphere's ``radius`` (m) and the near zone ``near``, or under a
        punch's face); returns the nodes' ``(u_r, u_z)`` dofs (n, 2)."""
        nodes, tri = self.nodes, self.tri
        n, ne = len(nodes), len(tri)
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
        return udof

    def _sparsity(self) -> None:
        """The Newton matrix's pattern (CSR order) of the elements and the condensed far
        field, and each entry's slot."""
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
        that the cost follows the plastic zone. A point whose tangent vanishes (below
        :data:`VANISHING` of its elastic one: Drucker-Prager's apex, perfectly plastic, a
        stress fixed whatever the strain) takes :data:`APEX_STIFFNESS` of its elastic
        tangent (a modified Newton step there; the residual keeps the exact stress)."""
        ne, nq = self.w.shape
        el = np.flatnonzero(plastic.reshape(ne, nq).any(axis=1))
        data = self.elastic_matrix()
        if not el.size:
            return data
        T = tangent.reshape(ne, nq, 4, 4)[el]
        De = np.where(self.sample_pts.reshape(ne, nq)[el][..., None, None], self.D_sample,
                      self.D_plate)
        vanish = np.max(np.abs(T), axis=(2, 3)) < VANISHING * np.max(np.abs(De), axis=(2, 3))
        if vanish.any():  # a stress fixed whatever the strain: a share of the elastic one
            T = np.where(vanish[..., None, None], T + APEX_STIFFNESS * De, T)
        Dd = self.proj @ T @ self.proj
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
              atol: float = 0.0, rtol: float = KRYLOV_RTOL) -> np.ndarray:
        """``x`` with ``A[free][:, free] x = rhs`` (``A`` the Newton matrix ``data``, CSR
        order): the elastic matrix's kept LU when there is one for ``free``; else GMRES
        right-preconditioned by the newest factorization (of an earlier tangent, possibly on
        another free set: the dofs it lacks take their diagonal) to the relative residual
        ``rtol`` (default :data:`KRYLOV_RTOL`; :data:`EXACT_RTOL` for a solution to
        round-off) or the absolute residual ``atol`` (the 2-norm, in ``rhs``'s units),
        whichever is reached first, within the iterations a factorization is worth
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
            diag = np.where(diag != 0.0, diag, 1.0)  # a dof without stiffness (a region
            outside = ~inside                           # at an apex): left as it is

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

        y, info = gmres(AM, rhs, rtol=rtol, atol=atol, restart=allowed, maxiter=1,
                        callback=tick, callback_type="pr_norm")
        x = apply(y)
        self.krylov += count[0]
        bnorm = float(np.linalg.norm(rhs))
        if info != 0 or not np.linalg.norm(rhs - A @ x) <= 10 * max(rtol * bnorm, atol):
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

    def yield_ratios(self, model: Any, stress: np.ndarray, state: np.ndarray) -> np.ndarray:
        """(ne * nq,) the yield ratio of every point: the sample's model at the sample's
        points, the plate's model at the plate's (0 for an elastic plate)."""
        s = self.sample_pts
        out = np.zeros(stress.shape[0])
        out[s] = model.yield_ratio(stress[s], state[s])
        if self.plate_model is not None:
            out[~s] = self.plate_model.yield_ratio(stress[~s], state[~s])
        return out

    def elastic_stress(self, E: float, nu: float, u: np.ndarray,
                       state: np.ndarray | None = None) -> np.ndarray:
        """(ne * nq, 4) Mandel stresses (Pa) of the displacements ``u`` by the elastic
        laws of the sample (``E`` Pa, ``nu``) and the plate, less the plastic strain of
        ``state`` (``state[:, :4]``, every model's; None: none): the trial stresses of an
        elastic step from ``state``."""
        eps = self.strain(u)
        if state is not None:
            eps = eps - state[:, :4]
        K, G = bulk_shear(E, nu)
        stress = eps @ elastic_tangent(K, G)
        pp = ~self.sample_pts
        if pp.any():
            stress[pp] = eps[pp] @ self.D_plate
        return stress

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



def _factor(A: Any) -> Any:
    """SuperLU of a symmetric quasi-definite Newton matrix (the u-p blocks: SPD displacement
    block, negative definite pressure block; Vanderbei 1995): a minimum-degree ordering of
    ``A + A^T`` with diagonal pivots, the symmetric structure's fill; partial pivoting (the
    COLAMD ordering) when a diagonal pivot fails (:mod:`ssw.contact.lu`)."""
    return sparse_lu.diagonal_lu(A, "MMD_AT_PLUS_A") or sparse_lu.pivoted_lu(A)


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
        factors = sparse_lu.diagonal_lu(A)
        return None if factors is None else cls(factors, order)

    def solve(self, rhs: np.ndarray, trans: str = "N") -> np.ndarray:
        """The solution of the unpermuted system (``trans`` as SuperLU's)."""
        x = np.empty_like(rhs)
        x[self.order] = self.lu.solve(rhs[self.order], trans=trans)
        return x
