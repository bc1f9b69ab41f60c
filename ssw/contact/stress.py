"""Stresses of a contact state: the plate's and the soil's peak von Mises stress.

The substructured engine (:mod:`ssw.contact.operators`) keeps of each body only its
stiffness condensed onto the retained dofs (the contact candidates and the plate-soil
interface). A state of the contact, the exact LCP solution at an indentation ``delta`` of
the rigid sphere (:mod:`ssw.contact.parametric`), fixes the contact forces ``lam`` and with
them the retained displacements ``u_B``: the scene's dense system ``K u = G^T lam``
assembled as :func:`ssw.contact.coupling.scene_lcp` does. Each body's interior follows
from its own equilibrium with ``u_B`` imposed (static condensation read backwards,
Przemieniecki 1963),

    K_II u_I = -K_IB u_B,

with the body's u-p matrix at unit E (the displacement field does not depend on the
body's modulus once ``u_B`` is given). ``K_II`` is factored once per mesh, body and
Poisson's ratio (:class:`BodyField`, kept in memory) and serves every state at once
(one multi-column solve).

Stress. The von Mises stress depends only on the deviatoric strain,
``sigma_vM = sqrt(3/2 s:s) = G sqrt(6 e:e)``, ``s = 2 G e``, ``e = dev(eps)`` with the
engineering shear halved (``e_rz = gamma_rz / 2`` counted twice), ``G = E / (2 (1 + nu))``;
the pressure unknown of the u-p element is not needed. On a straight-sided P2 triangle the
displacement gradient is linear and ``sigma_vM`` a norm of it, so its largest value over
the element sits at a vertex: the strains are evaluated at each element's three vertices
(from inside the element; pulled in by :data:`VERTEX_PULL` of the element, so that the
hoop strain ``u_r / r`` is defined on the axis, where it tends to ``du_r/dr``). The peak of
a body is the largest of these values, with its location.

Elastic bead. The FEM's indenter is rigid; the chain's bead is steel. At the same force a
rigid sphere of the bead's radius presses harder on a stiff plate than the bead does; the
stresses are computed under the rigid sphere of the Hertz-equivalent radius
(:func:`equivalent_radius`), which gives the bead's own pressure on the top body.

Checked against independent solutions (tests/test_design_stress.py): without a plate the
soil's peak is Johnson's Hertz first-yield point (``0.62 p0`` at ``z = 0.48 a`` for
``nu = 0.3``; Johnson 1985, sec. 6.1: the peak of the closed-form axis field), also under
an elastic bead (Hertz with the combined modulus); with a plate of the soil's own material
bonded to it (a homogeneous half-space cut by the interface) the plate's peak is the same
Hertz point and the soil's the closed-form field at the interface depth.

References
----------
Przemieniecki, J. S. (1963). Matrix structural analysis of substructures. AIAA J. 1(1),
138-147. Johnson, K. L. (1985). *Contact Mechanics*, CUP.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from ssw.contact.operators import (
    BodyOperator,
    Geometry,
    Layout,
    OperatorStore,
    coupled_stiffness,
    default_store,
    geometry_of,
    scene_lcp,
    take_factor,
)
from ssw.errors import ConfigError, SolverError

#: Barycentric share by which a vertex's evaluation point is pulled towards the element's
#: other two vertices (keeps ``r > 0`` on the axis; the strain changes by ~1e-9 of its
#: gradient across the element).
VERTEX_PULL = 1.0e-9
#: Body fields kept in memory (each holds a sparse LU of a body: tens of MB).
FIELDS_KEPT = 4


@dataclass(frozen=True)
class BodyPeak:
    """Peak von Mises stress of one body at each state. ``peak`` (n,) Pa; ``r``, ``z``
    (n,) m where it occurs (z from the plate-soil interface, up).

    Parameters
    ----------
    peak : numpy.ndarray
        Peak von Mises stress (Pa), (n,).
    r : numpy.ndarray
        Radius where it occurs (m), (n,).
    z : numpy.ndarray
        Height where it occurs, from the plate-soil interface, up (m), (n,).
    """

    peak: np.ndarray
    r: np.ndarray
    z: np.ndarray


@dataclass(frozen=True)
class ContactStress:
    """Stresses of contact states: ``delta`` (n,) m (rigid-sphere indentation), ``force``
    (n,) N on the sphere, ``plate`` (None without one) and ``soil`` peaks. ``fields``
    (when asked): per body, ``(r, z, von_mises)`` at every evaluation point, arrays
    (n_points,) m, m and (n_points, n) Pa.

    Parameters
    ----------
    delta : numpy.ndarray
        Rigid-sphere indentations (m), (n,).
    force : numpy.ndarray
        Forces on the sphere (N), (n,).
    plate : BodyPeak or None
        The plate's peaks, or None.
    soil : BodyPeak
        The soil's peaks.
    fields : dict or None
        Per body, ``(r, z, von_mises)`` (m, m, Pa) at every point, or None.
    """

    delta: np.ndarray
    force: np.ndarray
    plate: BodyPeak | None
    soil: BodyPeak
    fields: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None


class BodyField:
    """One body of a mesh at unit E: its interior displacement from the retained one, and
    the von Mises stress of that field at every element vertex.

    Parameters
    ----------
    nodes : numpy.ndarray
        (n, 2) every node of the model, m.
    tri : numpy.ndarray
        (ne, 6) the body's elements.
    free : numpy.ndarray
        (n, 2) bool, the free displacement components.
    b_nodes : numpy.ndarray
        (nb,) the retained dofs' nodes, in the order of the body's condensed operator.
    b_comps : numpy.ndarray
        (nb,) the retained dofs' components (0 = u_r, 1 = u_z), in that order.
    nu : float
        The body's Poisson's ratio.
    prepared : tuple or None
        ``(body matrix, LeadingBlock)`` of this body from its condensation
        (:func:`ssw.contact.operators.take_factor`): the same matrix, and the interior
        solve is one triangular solve with the unit upper factor of its LU
        (:class:`ssw.contact.substructure.LeadingBlock`; no second assembly or
        factorization). None: assembled, and ``K_II`` factored, here.
    """

    def __init__(self, nodes: np.ndarray, tri: np.ndarray, free: np.ndarray,
                 b_nodes: np.ndarray, b_comps: np.ndarray, nu: float,
                 prepared: tuple[Any, Any] | None = None) -> None:
        from ssw.contact.substructure import body_matrix, min_degree_order

        if prepared is None:
            bm = body_matrix(nodes, tri, nu, free, b_nodes, b_comps, min_degree_order)
        else:
            bm = prepared[0]
        K, n_int, ndof, udof, lnodes, ltri = bm.K, bm.n_int, bm.ndof, bm.udof, bm.nodes, bm.tri
        self.n_int, self.ndof = n_int, ndof
        if prepared is None:
            lu, KIB = _factor(K[:n_int, :n_int].tocsc()), K[:n_int, n_int:].tocsc()
            self._interior = lambda u_B: -lu.solve(np.asarray(KIB @ u_B))
        else:
            self._interior = prepared[1].interior
        self.udof = udof
        self.nodes = lnodes
        self.tri = ltri
        self.nu = float(nu)
        self._B, self.points = _vertex_strain_operators(lnodes, ltri)

    def displacements(self, u_B: np.ndarray) -> np.ndarray:
        """Nodal ``(u_r, u_z)`` (n_nodes, 2, n_states) m of the body for retained
        displacements ``u_B`` (n_B, n_states) m.

        Parameters
        ----------
        u_B : numpy.ndarray
            Retained displacements (m), (n_B, n_states).

        Returns
        -------
        numpy.ndarray
            Nodal displacements (m), (n_nodes, 2, n_states).
        """
        u_B = np.asarray(u_B, float).reshape(self.ndof - self.n_int, -1)
        x = np.empty((self.ndof, u_B.shape[1]))
        x[self.n_int:] = u_B
        x[: self.n_int] = self._interior(u_B)
        u = np.zeros((self.udof.shape[0], 2, u_B.shape[1]))
        for c in (0, 1):
            has = self.udof[:, c] >= 0
            u[has, c] = x[self.udof[has, c]]
        return u

    def von_mises(self, u_B: np.ndarray, E: np.ndarray) -> np.ndarray:
        """von Mises stress (n_points, n_states) Pa at ``points`` for retained
        displacements ``u_B`` (n_B, n_states) m and the body's modulus ``E`` (n_states,) Pa
        of each state.

        Parameters
        ----------
        u_B : numpy.ndarray
            Retained displacements (m), (n_B, n_states).
        E : numpy.ndarray
            Body's Young's modulus (Pa), (n_states,).

        Returns
        -------
        numpy.ndarray
            Von Mises stress (Pa), (n_points, n_states).
        """
        u = self.displacements(u_B)
        ue = np.concatenate([u[self.tri, 0], u[self.tri, 1]], axis=1)  # (ne, 12, n)
        # (ne, 3, 4, n): one batched product of the (12 x 12) operators (numpy's matmul
        # loop, 10-15x einsum's generic one at these shapes)
        ne = ue.shape[0]
        eps = np.matmul(self._B.reshape(ne, 12, 12), ue).reshape(ne, 3, 4, -1)
        tr = (eps[:, :, 0] + eps[:, :, 1] + eps[:, :, 2]) / 3.0
        dev2 = ((eps[:, :, 0] - tr) ** 2 + (eps[:, :, 1] - tr) ** 2 + (eps[:, :, 2] - tr) ** 2
                + 0.5 * eps[:, :, 3] ** 2)
        G = np.asarray(E, float) / (2.0 * (1.0 + self.nu))
        return (np.sqrt(6.0 * dev2) * G).reshape(-1, u_B.shape[1] if u_B.ndim > 1 else 1)


def _factor(KII: Any) -> Any:
    """Sparse LU of ``K_II``: pivot-free in the body's minimum-degree order (as the
    condensation factors it) when its backward error is small, else threshold-pivoted
    (:func:`ssw.contact.lu.checked_lu`)."""
    from ssw.contact.lu import checked_lu

    return checked_lu(KII)


def _vertex_strain_operators(nodes: np.ndarray, tri: np.ndarray
                             ) -> tuple[np.ndarray, np.ndarray]:
    """Strain operators at the elements' vertices: ``B`` (ne, 3, 4, 12) mapping the
    element's ``(u_r[0..5], u_z[0..5])`` to ``(e_rr, e_zz, e_tt, gamma_rz)``, and the
    points' ``(r, z)`` (ne * 3, 2) m."""
    from ssw.contact.elements import p2_shape, physical_gradients

    a = VERTEX_PULL
    xi = np.array([[a, a], [1.0 - 2.0 * a, a], [a, 1.0 - 2.0 * a]])  # near vertices 0, 1, 2
    n2, g2 = p2_shape(xi)
    xy = nodes[tri]
    dn, _ = physical_gradients(xy, g2)  # (ne, 3, 6, 2)
    pts = np.einsum("qa,eax->eqx", n2, xy)  # (ne, 3, 2)
    ne = len(tri)
    B = np.zeros((ne, 3, 4, 12))
    B[:, :, 0, :6] = dn[..., 0]
    B[:, :, 1, 6:] = dn[..., 1]
    B[:, :, 2, :6] = n2[None] / pts[:, :, 0:1]
    B[:, :, 3, :6] = dn[..., 1]
    B[:, :, 3, 6:] = dn[..., 0]
    return B, pts.reshape(-1, 2)


_FIELDS: OrderedDict[tuple[str, str, float], BodyField] = OrderedDict()


def body_field(store: OperatorStore, geom: Geometry, which: str, nu: float) -> BodyField:
    """The :class:`BodyField` of the ``plate`` or the ``soil`` of ``geom`` at ``nu``
    (built from the geometry's mesh on first use, then kept: :data:`FIELDS_KEPT`).

    Parameters
    ----------
    store : OperatorStore
        The operator store.
    geom : Geometry
        The scene's geometry (m).
    which : str
        ``plate`` or ``soil``.
    nu : float
        Poisson's ratio.

    Returns
    -------
    BodyField
        The field.

    Raises
    ------
    ConfigError
        If the geometry has an elastic subgrade.
    """
    key = (geom.key(), which, float(nu))
    if key in _FIELDS:
        _FIELDS.move_to_end(key)
        return _FIELDS[key]
    model = store._model(geom)  # the mesh the operators were condensed on (deterministic)
    if model.mesh.subgrade is not None:
        raise ConfigError("sample.base", "elastic",
                          "a rigid base or the half-space for the stress field (no subgrade)")
    b_nodes, b_comps = retained_dofs(model, which)
    tri = model.tri[model.body == (1 if which == "plate" else 0)]
    fld = BodyField(model.nodes, tri, model.free, b_nodes, b_comps, nu,
                    take_factor(geom, which, nu))
    _FIELDS[key] = fld
    while len(_FIELDS) > FIELDS_KEPT:
        _FIELDS.popitem(last=False)
    return fld


def retained_dofs(model: Any, which: str) -> tuple[np.ndarray, np.ndarray]:
    """The retained (node, component) of a body, in its condensed operator's order
    (``ssw.contact.operators._condense``): the plate's candidates then its interface
    dofs; the soil's interface dofs, or its candidates without a plate.

    Parameters
    ----------
    model : Any
        The condensed geometry's model.
    which : str
        ``plate`` or ``soil``.

    Returns
    -------
    nodes : numpy.ndarray
        Node indices.
    comps : numpy.ndarray
        Components (0: r, 1: z).
    """
    if which == "plate":
        return (np.concatenate([model.cand, model.iface_nodes[:, 1]]),
                np.concatenate([np.ones(len(model.cand), int), model.iface_comp]))
    if np.any(model.body == 1):
        return model.iface_nodes[:, 0], model.iface_comp
    return model.cand, np.ones(len(model.cand), int)


def retained_displacements(
    layout: Layout, plate: BodyOperator | None, soil: BodyOperator, soil_E: float,
    plate_E: float | None, interface: str, lam: np.ndarray,
) -> tuple[np.ndarray | None, np.ndarray]:
    """Retained displacements (m) of the plate (None without one) and of the soil under
    the constraint forces ``lam`` (N) of the scene's LCP: ``K u = G^T lam`` with ``K`` and
    ``G`` assembled as :func:`ssw.contact.coupling.scene_lcp` does (a sphere candidate's
    force pushes its ``u_z`` down; a pair of the unilateral interface pulls its two nodes
    together). ``lam`` (m,) gives (n_dofs,) displacements; (k, m), states of one scene,
    gives (n_dofs, k) from one factorization.

    Parameters
    ----------
    layout : Layout
        The retained dofs.
    plate : BodyOperator or None
        The plate's operator, or None.
    soil : BodyOperator
        The soil's operator.
    soil_E : float
        Soil's Young's modulus (Pa).
    plate_E : float or None
        Plate's Young's modulus (Pa).
    interface : str
        The plate-soil interface.
    lam : numpy.ndarray
        Constraint forces (N), (m,) or (k, m).

    Returns
    -------
    u_plate : numpy.ndarray or None
        Plate's retained displacements (m).
    u_soil : numpy.ndarray
        Soil's retained displacements (m).
    """
    nc = layout.r.size
    lam = np.asarray(lam, float)
    one = lam.ndim == 1
    L = (lam[None] if one else lam).T  # (m, k)
    if plate is None:
        K = soil_E * soil.S
        us = _spd_solve(K, -L[:nc])
        return None, us[:, 0] if one else us
    K, p_map, s_map, off = coupled_stiffness(plate.S, soil.S, plate_E, soil_E, layout, nc,
                                             interface == "unilateral")
    f = np.zeros((K.shape[0], L.shape[1]))
    f[:nc] = -L[:nc]
    if off.size:
        li = L[nc:]
        np.add.at(f, nc + off, li)
        np.add.at(f, s_map[off], -li)
    u = _spd_solve(K, f)
    if one:
        return u[p_map, 0], u[s_map, 0]
    return u[p_map], u[s_map]


def _spd_solve(K: np.ndarray, f: np.ndarray) -> np.ndarray:
    try:
        return cho_solve(cho_factor(0.5 * (K + K.T), lower=True, check_finite=False), f,
                         check_finite=False)
    except np.linalg.LinAlgError as exc:
        raise SolverError(f"the condensed scene stiffness is not positive definite: {exc}"
                          ) from exc


def equivalent_radius(radius: float, top: tuple[float, float], bead: tuple[float, float]
                      ) -> float:
    """Radius (m) of the rigid sphere that presses the same Hertz pressure on a body
    ``top = (E, nu)`` as an elastic bead ``bead = (E, nu)`` of ``radius`` at the same force.

    Hertz: ``a^3 = 3 F R / (4 E*)`` and ``p(r) = p0 sqrt(1 - r^2/a^2)`` with
    ``1/E* = 1/E_top* + 1/E_bead*`` (``E_i* = E_i / (1 - nu_i^2)``); a rigid sphere of radius
    ``R'`` on the top body alone gives the same ``a`` (and so the same pressure) at the same
    force when ``R' / E_top* = R / E*``:

        R' = R (1 + E_top* / E_bead*)

    (Johnson 1985, sec. 4.2). Exact for a half-space of the top material; for a plate on a
    soil it keeps the local contact pressure of the elastic bead (the rigid sphere of the
    bead's own radius overstates it by ``(E_top*/E*)^(2/3)``: 1.6 for a steel plate under a
    steel bead).

    Parameters
    ----------
    radius : float
        Bead radius (m).
    top : tuple of float
        The top body's ``(E, nu)`` (Pa, -).
    bead : tuple of float
        The bead's ``(E, nu)`` (Pa, -).

    Returns
    -------
    float
        Equivalent rigid radius (m).
    """
    e_top = top[0] / (1.0 - top[1] ** 2)
    e_bead = bead[0] / (1.0 - bead[1] ** 2)
    return float(radius * (1.0 + e_top / e_bead))


#: Gap tolerance of the LCP solved at one indentation, relative to it (a few ulp of it,
#: as :data:`ssw.contact.scene.LCP_TOL` per increment).
STATE_TOL = 1e-12
def _state_at_force(lcp: Any, force: np.ndarray, guess: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The contact states at which the sphere carries ``force`` (N, (k,)): indentations (k,)
    m, constraint forces (k, m) N and active sets (k, m).

    The sphere's force ``f(delta)`` is continuous, piecewise affine and increasing
    (:mod:`ssw.contact.parametric`); on the piece of an active set ``A`` its slope is
    ``-1 . (W_AA^-1 q1_A)`` over the sphere's constraints. Newton's step from a state,
    ``delta + (F - f) / slope``, lands on ``F`` exactly when it stays on the state's piece,
    which the LCP solved there (:func:`ssw.contact.contact_lcp.solve_lcp`, warm-started
    from the previous active set) confirms by returning the same active set; otherwise it
    lands on another piece and steps again. A bracket ``f(lo) < F <= f(hi)`` (``hi``
    doubled from ``guess`` until it holds ``F``) safeguards the steps (bisection when a
    step leaves it): :func:`ssw.roots.newton_bracketed`. The same state as the path traced
    from 0 and inverted on its pieces (:func:`ssw.contact.parametric.trace`), to round-off,
    in a few LCP solves instead of one per breakpoint.
    """
    from ssw.contact.contact_lcp import solve_lcp
    from ssw.contact.lapack import cho_solve, cholesky
    from ssw.roots import newton_bracketed

    ms = lcp.n_sphere
    W, q0, q1 = lcp.W, lcp.q0, lcp.q1
    force = np.atleast_1d(np.asarray(force, float))
    cache: dict = {}

    def state(d: float, act: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float]:
        g0 = q0 + d * q1
        lam, act, _ = solve_lcp(W, g0, act, STATE_TOL * d, cache)
        idx = np.flatnonzero(act)
        if idx.size == 0:
            return lam, act, 0.0, 0.0
        cf = cholesky(W[idx[:, None], idx], lower=False, clean=False)
        lam1 = -cho_solve(cf, q1[idx], lower=False)
        return lam, act, float(lam[:ms].sum()), float(lam1[idx < ms].sum())

    def fun(d: np.ndarray, states: list) -> tuple[np.ndarray, np.ndarray, list]:
        # one LCP per element, warm-started from its active set (states: (lam, act))
        out = [state(float(x), st[1]) for x, st in zip(d, states, strict=True)]
        return (np.array([o[2] for o in out]), np.array([o[3] for o in out]),
                [(o[0], o[1]) for o in out])

    # warm start: Hertz's contact radius (a^2 = R delta, half the geometric overlap's
    # r^2 = 2 R delta) and every touching pair of an unilateral interface
    hi = float(guess)
    act0 = (q0 + 0.5 * hi * q1 < 0) | ((q1 == 0) & (q0 == 0))
    try:
        root = newton_bracketed(fun, force, 0.0, hi, [(None, act0)] * force.size, grow=True,
                                same_piece=lambda a, b: np.array_equal(a[1], b[1]))
    except SolverError as exc:
        raise SolverError(f"the indentation of a force in {force.tolist()[:3]} N was not "
                          f"found ({exc})") from exc
    return (root.x, np.array([st[0] for st in root.state]),
            np.array([st[1] for st in root.state]))


def contact_stresses(
    soil_E: Any, soil_nu: float, plate: tuple[float, float] | None, plate_thickness: float,
    radius: float, delta: Any, contact: dict[str, Any] | None = None, *,
    store: OperatorStore | None = None, fields: bool = False,
    bead: tuple[float, float] | None = None, force: Any = None,
) -> ContactStress:
    """Peak von Mises stresses of the plate and of the soil at contact states.

    Parameters
    ----------
    soil_E : array_like
        (n,) the soil modulus of each state, Pa (one soil Poisson's ratio).
    soil_nu : float
        The soil's Poisson's ratio.
    plate : tuple of float or None
        ``(E, nu)`` of the plate, Pa and -, or None (``plate_thickness`` 0).
    plate_thickness : float
        The plate's thickness, m.
    radius : float
        The rigid sphere's radius, m.
    delta : array_like
        (n,) the sphere's indentation at each state, m (broadcast with ``soil_E``).
    contact : dict or None
        The ``contact`` settings (mesh, zone, interface); defaults
        :data:`ssw.contact.scene.DEFAULTS`.
    store : ssw.contact.operators.OperatorStore or None
        The operators (default: the process's,
        :func:`ssw.contact.operators.default_store`).
    fields : bool
        Also return every evaluation point's stress (the result's ``fields``).
    bead : tuple of float or None
        ``(E, nu)`` of an elastic bead, Pa and -, or None (a rigid sphere). With a bead,
        each state is the rigid sphere's at ``delta`` (as the chain's fem wall has it: the
        bead's compliance moved into the indentation), its force ``F``; the stresses are
        those of the rigid sphere of :func:`equivalent_radius` carrying the same ``F``
        (the elastic bead's Hertz pressure on the top body). ``delta`` of the result is
        then that sphere's indentation.
    force : array_like or None
        (n,) N, the rigid sphere's force at each ``delta`` when the caller knows it (the
        chain's fem wall at its peak indentation): with ``bead``, the rigid sphere's path is
        then not traced again.

    Returns
    -------
    ContactStress
        The peaks (Pa, m) of the plate and the soil at each state.
    """
    from ssw.contact.scene import settings_of

    E, d = np.broadcast_arrays(np.atleast_1d(np.asarray(soil_E, float)),
                               np.atleast_1d(np.asarray(delta, float)))
    if np.any(~(d > 0)) or np.any(~(E > 0)):
        raise ConfigError("delta, soil_E", (d.tolist(), E.tolist()),
                          "indentations > 0 m and moduli > 0 Pa")
    cfg = settings_of(contact or {})
    interface = cfg["interface"]
    has_plate = plate_thickness > 0
    if has_plate and plate is None:
        raise ConfigError("plate", plate, "(E, nu) of the plate when plate_thickness > 0")
    store = store if store is not None else default_store()
    geom = geometry_of(cfg, plate_thickness, radius, float(np.max(d)), interface)
    layout = store.layout(geom)
    soil_op = store.body(geom, "soil", soil_nu)
    plate_op = store.body(geom, "plate", plate[1]) if has_plate else None
    n = E.size
    known = None if force is None or bead is None else np.broadcast_to(
        np.asarray(force, float), (n,))
    force = np.empty(n)
    uP: np.ndarray | None = None
    uS: np.ndarray | None = None
    d = d.copy()
    plate_E = plate[0] if has_plate else None
    # the states of one modulus share their scene: one LCP, one path, one factorization
    moduli, which = np.unique(E, return_inverse=True)
    for u, Eu in enumerate(moduli):
        ks = np.flatnonzero(which == u)
        top = plate if has_plate else (float(Eu), soil_nu)  # the body the sphere presses
        r_eq = None if bead is None else equivalent_radius(radius, top, bead)
        d[ks], lam, active, ms = _scene_states(
            (layout, plate_op, soil_op), float(Eu), plate_E, interface, radius, d[ks],
            None if known is None else known[ks], r_eq)
        if np.any(active[:, ms - 1]):
            k = int(ks[np.argmax(d[ks])])
            raise SolverError(f"the contact zone reached the last candidate (r = "
                              f"{layout.r[-1]:.4g} m) at the state {k}: soil E {E[k]:.4g} Pa, "
                              f"indentation {d[k]:.4g} m")
        force[ks] = lam[:, :ms].sum(axis=1)
        up, us = retained_displacements(layout, plate_op, soil_op, float(Eu), plate_E,
                                        interface, lam)
        if uS is None:
            uS = np.empty((us.shape[0], n))
            uP = np.empty((up.shape[0], n)) if up is not None else None
        uS[:, ks] = us
        if up is not None:
            uP[:, ks] = up
    out_fields: dict[str, Any] | None = {} if fields else None
    soil = _body_peak(store, geom, "soil", soil_nu, uS, E, out_fields)
    plate_peak = (_body_peak(store, geom, "plate", plate[1], uP, np.full(n, plate[0]),
                             out_fields) if has_plate else None)
    return ContactStress(d, force, plate_peak, soil, out_fields)


def _scene_states(ops: tuple[Layout, BodyOperator | None, BodyOperator], soil_E: float,
                  plate_E: float | None, interface: str, radius: float, d: np.ndarray,
                  known: np.ndarray | None, r_eq: float | None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The contact states of one scene (one soil modulus) at the rigid sphere's
    indentations ``d`` (m): its path traced (or its forces ``known``, N); with ``r_eq`` (m,
    :func:`equivalent_radius`) the states of that sphere carrying the rigid sphere's forces.
    ``ops`` the geometry's layout and the plate's (or None) and soil's operators. Returns
    the states' indentations (m), the candidates' forces ``lam`` (N), their active sets and
    the number of sphere candidates."""
    from ssw.contact.parametric import trace

    layout, plate_op, soil_op = ops
    if known is None:
        lcp = scene_lcp(layout, plate_op, soil_op, soil_E, plate_E, interface, radius)
        path, _ = trace(lcp.W, lcp.q0, lcp.q1, float(d.max()))
        lam = path.forces(d)
        if r_eq is None:
            return d, lam, path.active, lcp.n_sphere
        known = lam[:, :lcp.n_sphere].sum(axis=1)
    lcp = scene_lcp(layout, plate_op, soil_op, soil_E, plate_E, interface, float(r_eq))
    d, lam, active = _state_at_force(lcp, known, float(d.max()))
    return d, lam, active, lcp.n_sphere


def _body_peak(store: OperatorStore, geom: Geometry, which: str, nu: float, u: np.ndarray,
               modulus: np.ndarray, out_fields: dict[str, Any] | None) -> BodyPeak:
    """The peak von Mises stress (Pa) of the ``plate`` or the ``soil`` at each state, and
    where (m), from its retained displacements ``u`` (m) at the states' moduli (Pa); every
    evaluation point's stress into ``out_fields`` when given."""
    fld = body_field(store, geom, which, nu)
    vm = fld.von_mises(u, modulus)
    j = np.argmax(vm, axis=0)
    pts = fld.points
    if out_fields is not None:
        out_fields[which] = (pts[:, 0], pts[:, 1], vm)
    return BodyPeak(vm[j, np.arange(vm.shape[1])], pts[j, 0], pts[j, 1])
