"""Elasto-plastic contact: a rigid frictionless sphere pressed into (and lifted off) a plastic
sample (any model of :mod:`ssw.constitutive`), directly or through an elastic plate, with an
active set on the contact inside Newton's iteration.

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

Plate. An elastic plate on the sample (the thesis's device) is meshed as by the elastic
engine and tied to the sample by the contact config's ``interface``: ``frictionless`` (the
thesis's; the two surfaces share ``u_z`` and slide freely) or ``bonded``. The tie is
bilateral, as the elastic engine's: on unloading the plate follows the dent it pressed (a
plate that springs back off a permanent dent, the ``unilateral`` interface, is refused).
Below yield the curve is the elastic engine's with the same plate (tests).

Contact. The sphere's candidates are the top-surface nodes with ``r < R / 2``; at an
indentation ``delta`` the gap of a node is ``g = g0(r) - delta - u_z`` (``g0`` the exact
spherical gap). Each Newton iteration prescribes ``u_z = g0 - delta`` on the active set and
solves for the rest; at convergence the contact forces are the reactions ``lam = -f_int,z``;
the set gains the nodes with ``g < 0`` and loses those with ``lam < 0`` (a primal-dual active
set, Hintermueller, Ito & Kunisch 2003) until it is stable and the residual is below
``rtol`` times the load scale. An increment that does not converge in ``max_iter``
iterations raises SolverError.

Path. Loading through ``delta`` then, with ``unload``, back in the same steps until the
sphere leaves the surface; the residual indentation is the axis's depth then (contact is
lost; the body stays as it is). Per increment: force, contact radius, the plastic zone
(volume, depth, radius), the plastic work ``sum int sigma_{n+1} : d eps_p dV`` (backward
Euler) and Newton's iterations. First yield: the elastic increments' largest yield ratio
``q / Y`` scales as the Hertz pressure ``p0 ~ F^(1/3)`` (self-similar elastic contact), so
``F_y = F / ratio^3`` of the last elastic increment.

References
----------
Hintermueller, M., Ito, K. & Kunisch, K. (2003). The primal-dual active set strategy as a
semismooth Newton method. *SIAM J. Optim.* 13, 865-888.
Johnson, K. L. (1985). *Contact Mechanics*. Cambridge, sec. 6.1.
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
#: Halvings of a Newton step that does not lower the residual.
LINE_SEARCH = 4
#: Halvings of an increment whose Newton iteration fails, before SolverError.
MAX_CUTS = 5
#: Elastic LUs kept per path (one per free set: the contact's active set).
LU_CACHE = 8
#: Residual tolerance relative to the load scale (the largest nodal internal force).
RTOL = 1e-9


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

    A plate (``mesh.body == 1``, elastic ``plate = (E Pa, nu)``) is tied to the sample by
    ``interface``: its interface nodes are copies of the sample's (:func:`split_interface`)
    that share ``u_z`` (``frictionless``, the thesis's interface) or both components
    (``bonded``) with them; the plate's points are elastic, the sample's follow the model."""

    def __init__(self, mesh: Mesh, E: float, nu: float, radius: float,
                 punch: str | None = None, mixed: bool = True,
                 plate: tuple[float, float] | None = None,
                 interface: str = "frictionless") -> None:
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
        rows = np.repeat(self.edof, 15, axis=1).ravel()
        cols = np.tile(self.edof, (1, 15)).ravel()
        keys, self.slot = np.unique(rows * self.ndof + cols, return_inverse=True)
        self.row_u, self.col_u = keys // self.ndof, keys % self.ndof  # CSR order
        self.nnz = keys.size
        self.pattern: tuple | None = None
        tol = geometric_tolerance(nodes, tri)
        free = fixed_free(nodes, tol, mesh.soil_radius, mesh.soil_depth, mesh.base,
                          mesh.lateral)
        unused = np.setdiff1d(np.arange(2 * n), self.edof_u)
        self.fixed = np.union1d(udof[~free], unused)
        weight = top_surface_weights(nodes, tri, np.arange(ne), mesh.top, tol)
        top = np.flatnonzero(weight > 0)
        top = top[np.argsort(nodes[top, 0])]
        if punch is None:
            self.cand = top[nodes[top, 0] < 0.5 * radius]
        else:  # a rigid flat punch of radius ``radius``: the nodes under its face
            self.cand = top[nodes[top, 0] <= radius + tol]
            if punch == "rough":  # no slip under the face
                self.fixed = np.union1d(self.fixed, udof[self.cand, 0])
        self.cand_r = nodes[self.cand, 0]
        self.cand_dof = udof[self.cand, 1]
        self.g0 = sphere_gap0(self.cand_r, radius) if punch is None else np.zeros(
            self.cand.size)
        self.axis_dof = int(udof[top[0], 1])
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
        self.kuu_el = self.ke[:, :12, :12].copy()
        self._elastic_data: np.ndarray | None = None  # the elastic matrix, once assembled
        self._lus: dict[bytes, Any] = {}
        self.factorizations = self.lu_reused = 0

    def factor(self, data: np.ndarray, free: np.ndarray) -> Any:
        """The LU of the Newton matrix ``data`` (CSR order) on ``free``. The elastic
        matrix's (no plastic element: the unloading and elastic reloading branches) is kept
        per free set, at most :data:`LU_CACHE` of them, and reused: the same factorization
        bit for bit. Counts ``factorizations`` and ``lu_reused``."""
        elastic = data is self._elastic_data
        key = free.tobytes()
        if elastic and key in self._lus:
            self.lu_reused += 1
            return self._lus[key]
        lu = _factor(self.restricted(data, free))
        self.factorizations += 1
        if elastic:
            if len(self._lus) >= LU_CACHE:
                self._lus.pop(next(iter(self._lus)))
            self._lus[key] = lu
        return lu

    def _kuu(self, elems: np.ndarray, Dd: np.ndarray) -> np.ndarray:
        """``int B^T Dd B dV`` (len(elems), 12, 12) of deviatoric tangents Dd."""
        B = self.B[elems]
        WDB = np.matmul(Dd * self.w[elems][:, :, None, None], B)  # (m, nq, 4, 12)
        return np.matmul(np.swapaxes(B, 2, 3), WDB).sum(axis=1)

    def restricted(self, data: np.ndarray, free: np.ndarray) -> Any:
        """The CSC matrix of the transpose of ``A[free][:, free]`` (``A`` in CSR order
        ``data``): splu's ``trans='T'`` solve then solves with ``A``."""
        key = free.tobytes()
        if self.pattern is None or self.pattern[0] != key:
            mask = np.zeros(self.ndof, bool)
            mask[free] = True
            new = np.full(self.ndof, -1)
            new[free] = np.arange(free.size)
            sel = np.flatnonzero(mask[self.row_u] & mask[self.col_u])
            ri, ci = new[self.row_u[sel]], new[self.col_u[sel]]
            indptr = np.concatenate([[0], np.cumsum(np.bincount(ri, minlength=free.size))])
            self.pattern = (key, sel, ci, indptr)
        _, sel, ci, indptr = self.pattern
        return sp.csc_matrix((data[sel], ci, indptr), shape=(free.size, free.size))

    def update(self, model: Any, E: float, nu: float, u: np.ndarray, state: np.ndarray
               ) -> Update:
        """The model's return mapping at the sample's points and the plate's elastic law at
        its points, for the displacements ``u`` from ``state`` (all points)."""
        eps = self.strain(u)
        s = self.sample_pts
        if s.all():
            return model.update(E, nu, eps, state)
        up = model.update(E, nu, eps[s], state[s])
        stress = eps @ self.D_plate
        stress[s] = up.stress
        tangent = np.repeat(self.D_plate[None], eps.shape[0], axis=0)
        tangent[s] = up.tangent
        new = state.copy()
        new[s] = up.state
        plastic = np.zeros(eps.shape[0], bool)
        plastic[s] = up.plastic
        region = np.zeros(eps.shape[0], np.int8)
        region[s] = up.region
        return Update(stress, tangent, new, plastic, region)

    def yield_ratio(self, model: Any, stress: np.ndarray, state: np.ndarray) -> float:
        """The largest yield ratio of the sample's points."""
        s = self.sample_pts
        return float(np.max(model.yield_ratio(stress[s], state[s])))

    def strain(self, u: np.ndarray) -> np.ndarray:
        """(ne * nq, 4) Mandel strains of the displacements ``u`` (the full dof vector)."""
        ue = u[self.edof_u]
        return np.einsum("eqij,ej->eqi", self.B, ue).reshape(-1, 4)

    def pressure_q(self, u: np.ndarray) -> np.ndarray:
        """(ne, nq) mean stress ``p`` at the quadrature points, Pa."""
        pe = u[self.edof[:, 12:]] * self.ps_e
        return pe @ self.N1.T

    def residual_matrix(self, u: np.ndarray, stress: np.ndarray, tangent: np.ndarray,
                        plastic: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """Residual (ndof,) in N (pressure rows scaled by ``ps``), the Newton matrix's
        entries in CSR order (divided by ``scale``; only the elements with a ``plastic``
        point take the model's tangent, the others the elastic one) and the load scale: the
        largest element force before assembly (N), the size of what cancels in the
        residual."""
        ne, nq = self.w.shape
        res, fu = self._residual(u, stress)
        load = max(float(np.max(np.abs(fu))), 1e-300)
        if not plastic.any() and self._elastic_data is not None:
            return res, self._elastic_data, load  # no plastic point: the elastic matrix
        pe_mask = plastic.reshape(ne, nq).any(axis=1)
        self.ke[:, :12, :12] = self.kuu_el
        el = np.flatnonzero(pe_mask)
        if el.size:
            Dd = self.proj @ tangent.reshape(ne, nq, 4, 4)[el] @ self.proj
            self.ke[el, :12, :12] = self._kuu(el, Dd)
        data = np.bincount(self.slot, weights=self.ke.ravel(), minlength=self.nnz) / self.scale
        if not el.size:
            self._elastic_data = data
        return res, data, load

    def residual_only(self, u: np.ndarray, stress: np.ndarray) -> np.ndarray:
        """The residual of :meth:`residual_matrix` alone (ndof,), N."""
        return self._residual(u, stress)[0]

    def _residual(self, u: np.ndarray, stress: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The assembled residual (ndof,) and the elements' displacement forces (ne, 12), N."""
        ne, nq = self.w.shape
        s = (stress @ self.proj).reshape(ne, nq, 4)
        ue, pe = u[self.edof_u], u[self.edof[:, 12:]]
        fu = np.matmul(np.swapaxes(self.B, 2, 3), (s * self.w[:, :, None])[..., None]
                       ).sum(axis=1)[..., 0] + np.matmul(pe[:, None, :], self.Bp)[:, 0]
        fp = np.matmul(self.Bp, ue[..., None])[..., 0] - np.matmul(self.Cp, pe[..., None])[..., 0]
        res = np.zeros(self.ndof)
        np.add.at(res, self.edof, np.concatenate([fu, fp], axis=1))
        return res, fu

    def matvec(self, data: np.ndarray, x: np.ndarray) -> np.ndarray:
        """``A x`` of the entries ``data`` (CSR order)."""
        out = np.zeros(self.ndof)
        np.add.at(out, self.row_u, data * x[self.col_u])
        return out


def solve_path(
    mesh: Mesh, E: float, nu: float, model: Any, radius: float, deltas: np.ndarray,
    unload: bool = False, *, rtol: float = RTOL, max_iter: int = MAX_ITER,
    punch: str | None = None, max_cuts: int = MAX_CUTS,
    plate: tuple[float, float] | None = None, interface: str = "frictionless",
) -> PlasticCurve:
    """Load a rigid sphere of ``radius`` (m) through the indentations ``deltas`` (m,
    increasing) into the soil ``(E Pa, nu)`` of constitutive ``model`` on ``mesh``; with
    ``unload``, lift it back in the same steps until it leaves the surface (module
    docstring). Raises SolverError on an increment that does not converge, and when the
    contact reaches the last candidate node.

    ``punch`` ``smooth`` or ``rough``: a rigid flat punch of radius ``radius`` instead of
    the sphere (frictionless, or without slip under its face; the limit-load check of
    Eason & Shield 1960). An increment whose Newton iteration fails is cut in two, at most
    ``max_cuts`` times (``stats['cutbacks']`` counts them; the path then holds the
    intermediate indentations). A mesh with a plate takes its elastic ``plate`` (E Pa, nu)
    and the plate-sample ``interface`` (``frictionless`` | ``bonded``; ``_Model``)."""
    if not hasattr(model, "update"):
        raise ConfigError("soil_model", model, "a model of ssw.constitutive")
    t0 = time.perf_counter()
    deltas = np.asarray(deltas, float)
    if deltas.ndim != 1 or deltas.size < 1 or np.any(np.diff(deltas) <= 0) or deltas[0] <= 0:
        raise ConfigError("deltas", deltas, "increasing indentations > 0 m")
    if punch not in (None, "smooth", "rough"):
        raise ConfigError("punch", punch, "smooth | rough (or none: the sphere)")
    fe = _Model(mesh, E, nu, radius, punch, mixed=bool(getattr(model, "isochoric", False)),
                plate=plate, interface=interface)
    ne, nq = fe.w.shape
    state = initial_state(ne * nq)
    last = (None, np.zeros(ne * nq, bool))  # the last converged tangent (elastic at first)
    u = np.zeros(fe.ndof)
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
    residual = None
    load_ref = 0.0  # the largest load scale of the path: a floor once the load is gone
    k, d_prev, cuts = 0, 0.0, 0
    h0 = float(deltas[0])  # the first (and uniform) step
    while k < len(path):
        d = path[k]
        target = fe.g0 - d
        tol_g = 1e-9 * max(abs(d), fe.h_min * 1e-6)
        step = abs(d - d_prev)
        u_start, active_start = u.copy(), active.copy()
        prev, was_elastic = np.inf, False
        for it in range(max_iter):
            upd = fe.update(model, E, nu, u, state)
            # the first iteration of an increment takes the last converged tangent (at the
            # committed state the return cannot tell loading from unloading)
            tangent, plastic = (last if it == 0 else (upd.tangent, upd.plastic))
            res, data, load = fe.residual_matrix(u, upd.stress, tangent, plastic)
            lam = -res[fe.cand_dof]
            load_ref = max(load_ref, load)
            tol = rtol * max(load, 1e-6 * load_ref)
            gap = target - u[fe.cand_dof]
            new_active = np.where(active, lam > tol, gap < -tol_g)
            if 0 < it < SET_UPDATES and not np.array_equal(new_active, active):
                # semismooth Newton: the set follows the iterate (Hintermueller et al. 2003)
                active = new_active
            known = np.zeros(fe.ndof, bool)
            known[fe.fixed] = True
            known[fe.cand_dof[active]] = True
            free = np.flatnonzero(~known)
            jump = np.zeros(fe.ndof)
            jump[fe.cand_dof[active]] = target[active] - u[fe.cand_dof[active]]
            err = float(np.max(np.abs(res[free]), initial=0.0))
            if it > 0 and err <= tol and not np.any(jump):
                if np.array_equal(new_active, active):
                    break
                active, prev = new_active, np.inf
                continue
            elastic = err > prev and not was_elastic  # one elastic step, then Newton again
            prev = err
            for _ in range(2):
                if elastic:
                    # Newton stalls or leaps (a nearly singular perfectly plastic tangent):
                    # a step with the elastic tangent, a contraction for the return mapping
                    res, data, load = fe.residual_matrix(u, upd.stress, upd.tangent,
                                                         np.zeros_like(upd.plastic))
                try:
                    lu = fe.factor(data, free)
                except RuntimeError:  # a singular consistent tangent (e.g. a region at
                    if elastic:       # the apex): the elastic tangent's step instead
                        raise SolverError(f"plastic contact: singular Newton matrix at "
                                          f"delta = {d:.4g} m") from None
                    elastic = True
                    continue
                rhs = -res / fe.scale
                if np.any(jump):
                    rhs -= fe.matvec(data, jump)
                du = lu.solve(rhs[free], trans="T")
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
                    if np.max(np.abs(r_t[free]), initial=0.0) < err:
                        break
                    du = 0.5 * du
                else:
                    _, data_el, _ = fe.residual_matrix(u, upd.stress, None,
                                                       np.zeros_like(upd.plastic))
                    lu = fe.factor(data_el, free)
                    du = lu.solve(-res[free] / fe.scale, trans="T")
            was_elastic = elastic
            u[free] += du
            u += jump
        else:
            if step > h0 * 0.5 ** max_cuts * (1 + 1e-9):
                # cut the increment in two: back to the last converged state
                u, active = u_start, active_start
                path.insert(k, 0.5 * (d_prev + d))
                branch.insert(k, branch[k])
                cuts += 1
                continue
            hint = ("; a perfectly plastic model with corners (tresca) may stall there: a "
                    "small hardening (e.g. E/100) restores Newton's convergence"
                    if getattr(model, "hardening", None) == 0.0 else "")
            raise SolverError(
                f"plastic contact: increment {k} (delta = {d:.6g} m) did not converge in "
                f"{max_iter} Newton iterations (residual {err:.3g} N, load scale {load:.3g} N), "
                f"its step cut to {step:.3g} m{hint}")
        d_prev = d
        last = (upd.tangent, upd.plastic)
        dep = upd.state[:, :4] - state[:, :4]
        work += float(np.sum(np.einsum("gi,gi->g", upd.stress, dep) * fe.w.ravel()))
        state = upd.state
        force = float(lam[active].sum())
        ratio = fe.yield_ratio(model, upd.stress, state)
        yielded = state[:, 4] > 0
        if first[0] is None:
            if np.any(upd.plastic):
                if last_elastic is not None:
                    f_el, d_el, r_el = last_elastic
                    first = (f_el / r_el ** 3, d_el / r_el ** 2)
            else:
                last_elastic = (force, d, ratio) if force > 0 else last_elastic
        gap = np.clip(target - u[fe.cand_dof], 0.0, None)
        if punch is None and active.size and active[-1]:
            raise ContactZoneError(f"the contact zone reached the last candidate node (r = "
                                   f"{fe.cand_r[-1]:.4g} m, half the sphere's radius): an "
                                   f"indentation beyond the small-strain contact's reach")
        out["delta"].append(d)
        out["force"].append(force)
        out["a"].append(edge_radius(fe.cand_r, gap, active))
        out["work"].append(work)
        out["vol"].append(float(np.sum(fe.w.ravel()[yielded])))
        out["depth"].append(float(-np.min(fe.zq.ravel()[yielded], initial=0.0)))
        out["rad"].append(float(np.max(fe.rq.ravel()[yielded], initial=0.0)))
        out["it"].append(it)
        out["ratio"].append(ratio)
        if branch[k] == 1 and not active.any():
            residual = float(-u[fe.axis_dof])
            branch = branch[: k + 1]
            break
        k += 1
    # elastic energy stored in the final state: int (s:s / (4 G) + p^2 / (2 K)) dV
    s = upd.stress @ P_DEV
    pq = fe.pressure_q(u).ravel() if fe.mixed else upd.stress @ ONE / 3.0
    stored = float(np.sum((np.einsum("gi,gi->g", s, s) / (4.0 * fe.Gq)
                           + 0.5 * fe.inv_Kq * pq * pq) * fe.w.ravel()))
    stats = {"nodes": fe.n, "elements": ne, "dofs": fe.ndof, "candidates": fe.cand.size,
             "increments": len(out["delta"]), "newton_iterations": int(np.sum(out["it"])),
             "factorizations": fe.factorizations, "lu_reused": fe.lu_reused,
             "cutbacks": cuts,
             "wall_total": time.perf_counter() - t0}
    return PlasticCurve(
        np.array(out["delta"]), np.array(out["force"]), np.array(branch, np.int8),
        np.array(out["a"]), np.array(out["work"]), np.array(out["vol"]),
        np.array(out["depth"]), np.array(out["rad"]), np.array(out["it"]),
        np.array(out["ratio"]), first[0], first[1], residual, stored, stats)


def contact_mesh(radius: float, d_max: float, *, fine: float = 8.0, growth: float = 0.3,
                 domain: float = 40.0, plate_thickness: float = 0.0,
                 plate_radius: float = 0.0) -> Mesh:
    """A mesh scaled to the Hertz contact radius ``a = sqrt(radius d_max)`` at the largest
    indentation ``d_max`` (m): element ``a / fine`` at the contact point, ``growth``, a
    domain of ``domain x a`` (the plastic wall's tables and ``ssw bench contact --plastic``;
    the elastic engine's meshes are graded for indentations down to 1e-9 m, far finer at
    the contact point than a plastic path needs). A plate of ``plate_thickness`` and
    ``plate_radius`` (m) on the sample: the domain then reaches 4 plate radii at least, the
    plate has 2 element layers at least."""
    from ssw.contact.mesh import MeshSettings, build_mesh

    a = float(np.sqrt(radius * d_max))
    t, rp = float(plate_thickness), float(plate_radius)
    if t <= 0:
        return build_mesh(0.0, 0.0, MeshSettings(domain * a, domain * a, a / fine, growth,
                                                 8.0 * a, 1))
    dom = max(domain * a, 4.0 * rp)
    return build_mesh(t, rp, MeshSettings(dom, dom, min(a / fine, t / 2), growth,
                                          max(8.0 * a, 0.05 * dom), 2))


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


def solve_plastic_scene(
    soil: tuple[float, float], model: Any, radius: float, contact_cfg: dict[str, Any],
    unload: bool = False, plate: tuple[float, float] | None = None,
    plate_thickness: float = 0.0,
) -> PlasticCurve:
    """The plastic curve of a sphere of ``radius`` (m) on the sample ``soil`` (E Pa, nu),
    through an elastic ``plate`` (E Pa, nu) of ``plate_thickness`` (m; 0: none) of the
    contact config's ``plate_diameter`` and ``interface``, with the config's mesh, domain
    (a finite block's boundaries included) and increments
    (:func:`ssw.contact.scene.settings_of`, :func:`ssw.contact.scene.indentation_steps`):
    the elastic engine's mesh and steps."""
    from ssw.contact.mesh import build_mesh, mesh_settings
    from ssw.contact.scene import indentation_steps, settings_of

    cfg = settings_of(contact_cfg)
    t = float(plate_thickness)
    if t > 0 and plate is None:
        raise ConfigError("plate", None, "the plate's (E Pa, nu) when plate_thickness > 0")
    mesh = build_mesh(t, 0.5 * float(cfg["plate_diameter"]) if t > 0 else 0.0,
                      mesh_settings(cfg))
    deltas = indentation_steps(float(cfg["delta_max"]), int(cfg["steps"]))
    return solve_path(mesh, float(soil[0]), float(soil[1]), model, radius, deltas, unload,
                      plate=plate if t > 0 else None, interface=str(cfg["interface"]))


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
    return {"first_yield_force": curve.first_yield_force,
            "first_yield_delta": curve.first_yield_delta,
            "residual_indentation": curve.residual_indentation,
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
                  "dissipated_work", "external_work", "stored_energy", "force_max"):
            v = float(f.attrs[k])
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
               plate: tuple[float, float] | None, unload: bool = False
               ) -> tuple[PlasticCurve, dict[str, Any]]:
    """The plastic path of a scene with a ``soil_model`` (:class:`ssw.config.Scene`) and
    its inputs: :func:`solve_plastic_scene` on the contact config's mesh and increments
    (a finite block's settings already applied, :meth:`ssw.sample.Sample.contact_settings`),
    through the scene's plate ``(E Pa, nu)`` (:func:`ssw.contact.scene.scene_plate`) when
    it has one; with ``unload``, lifted back until the sphere leaves."""
    from ssw.contact.scene import settings_of

    plate_key = scene.plate_material if scene.plate_thickness > 0 else "none"
    curve = solve_plastic_scene((scene.soil_E, scene.soil_nu), scene.soil_model,
                                indenter_radius, contact_cfg, unload=unload, plate=plate,
                                plate_thickness=scene.plate_thickness)
    inputs = {"soil_E": scene.soil_E, "soil_nu": scene.soil_nu, "plate_material": plate_key,
              "plate_E": plate[0] if plate else None, "plate_nu": plate[1] if plate else None,
              "plate_thickness": float(scene.plate_thickness),
              "indenter_radius": indenter_radius, "soil_model": scene.soil_model.params(),
              "scene_id": scene.scene_id, **settings_of(contact_cfg)}
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
