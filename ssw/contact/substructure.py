"""Substructuring: one body's u-p stiffness condensed onto the displacements it shares.

For a body (the plate, or the soil) with stiffness ``K`` split into internal dofs ``I``
(displacements and pressures) and retained dofs ``B`` (the displacements the body shares
with the sphere or with the other body), the condensed stiffness is the Schur complement

    S = K_BB - K_BI K_II^-1 K_IB     (N/m),

exactly the stiffness the rest of the model sees (Przemieniecki 1963; the static
condensation of substructures). It is the trailing block of an LU factorization that
eliminates ``I`` first: with ``B`` numbered last, ``K = L U`` gives ``S = L_BB U_BB``, so
one sparse factorization yields ``S`` without a solve per retained dof.

Ordering and pivots. ``K`` is the indefinite saddle-point matrix of the Taylor-Hood element
(:mod:`ssw.contact.elements`). It is factored by SuperLU (scipy) without pivoting in the
given order: the nodes in a minimum-degree order of the node graph (:func:`min_degree_order`;
on the thesis's meshes 8 % less fill than PETSc's nested dissection, and no PETSc needed),
each node's displacements before its pressure; the pressures of nodes without a free
displacement (the fixed bottom) after every other internal dof, where the eliminated
displacements around them have made their pivots nonzero (at ``nu = 0.5`` the pressure's
own diagonal is zero); then ``B``. A pivot-free LU of an indefinite matrix may still be
unstable, so every factorization is checked by its backward error
``||K x - L U x||_inf / (||K||_inf ||x||_inf)`` on a random ``x``; above
:data:`ssw.contact.lu.BACKWARD_ERROR_TOL` the Schur complement is recomputed from a pivoted
(threshold 1) SuperLU factorization of ``K_II`` and one solve per retained dof (slower,
always stable); the factorizations and the check are :mod:`ssw.contact.lu`'s.

Units. The matrix is assembled nondimensional (:mod:`ssw.contact.assembly`) at unit Young's
modulus: the stiffness of a body of modulus ``E`` is ``E`` times it (every block of the u-p
matrix scales with ``E`` at fixed ``nu``), so ``S`` is returned in N/m per Pa (m).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ssw.contact.assembly import element_sizes, pow2, pressure_scale
from ssw.contact.elements import element_matrices, lame
from ssw.errors import SolverError


@dataclass(frozen=True)
class Condensation:
    """A body's condensed stiffness. ``S`` (nb, nb) m (N/m per Pa of the body's E) on the
    retained dofs in the order given; ``dofs`` the body's matrix size; ``backward_error``
    of the factorization; ``pivoted``: the pivoted fallback was used; ``wall_*`` s.

    Parameters
    ----------
    S : numpy.ndarray
        Condensed stiffness (m, N/m per Pa of E), (nb, nb).
    dofs : int
        The body's matrix size.
    nnz_factor : int
        Nonzeros of the factors.
    backward_error : float
        Backward error of the factorization.
    pivoted : bool
        Whether the pivoted fallback was used.
    wall_assemble : float
        Assembly time (s).
    wall_factor : float
        Factorization time (s).
    body : BodyMatrix or None
        The body's matrix, or None.
    factor : Any
        The factorization, or None.
    """

    S: np.ndarray
    dofs: int
    nnz_factor: int
    backward_error: float
    pivoted: bool
    wall_assemble: float
    wall_factor: float
    body: BodyMatrix | None = field(default=None, repr=False, compare=False)
    factor: Any = field(default=None, repr=False, compare=False)


def min_degree_order(rows: np.ndarray, cols: np.ndarray, n: int) -> np.ndarray:
    """Elimination order (position -> node) of a graph given as COO: SuperLU's multiple
    minimum degree on ``A^T + A`` (Liu 1985) of a diagonally dominant matrix with the
    graph's pattern.

    SuperLU computes its column order from the pattern alone, before the numeric phase;
    scipy exposes it only through a factorization. The incomplete one (``spilu``) with
    every off-diagonal entry dropped (``drop_tol`` 1e30, ``fill_factor`` 1) returns the same
    order as the complete one at a fraction of its cost: 0.006-0.010 s against 0.016-0.032 s
    on the thesis's plates and soils (4-7 k nodes; the orders equal, element for element).

    Parameters
    ----------
    rows : numpy.ndarray
        (m,) the graph's edges' first nodes (duplicates and self-loops allowed).
    cols : numpy.ndarray
        (m,) their second nodes.
    n : int
        The number of nodes.

    Returns
    -------
    numpy.ndarray
        (n,) the nodes in elimination order.
    """
    import scipy.sparse as sp
    from scipy.sparse.linalg import spilu

    G = sp.csc_array((np.full(len(rows), 0.01), (rows, cols)), shape=(n, n))
    G.sum_duplicates()
    G = (G + sp.diags_array(np.asarray(abs(G).sum(axis=1)).ravel() + 1.0)).tocsc()
    lu = spilu(G, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, drop_tol=1e30,
               fill_factor=1, options={"SymmetricMode": True})
    return np.argsort(lu.perm_c)


def body_dofs(
    tri: np.ndarray, free: np.ndarray, b_nodes: np.ndarray, b_comps: np.ndarray,
    order: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Dof numbering of one body: ``(udof (n, 2), pdof (n,), ndof, n_internal)``, -1 where
    none.

    ``free`` (n, 2) marks the displacement components that are not fixed; ``b_nodes``,
    ``b_comps`` the retained dofs in their order (they come last); ``order`` the node
    elimination order (nodes of the body only). Internal dofs follow ``order``, a node's
    u_r, u_z, p in turn, except the pressures of nodes without a free displacement, which
    come after every other internal dof.

    Parameters
    ----------
    tri : numpy.ndarray
        Quadratic triangles (node indices, gmsh order), (ne, 6).
    free : numpy.ndarray
        Free displacement components, (n, 2) bool.
    b_nodes : numpy.ndarray
        Nodes of the retained dofs.
    b_comps : numpy.ndarray
        Components of the retained dofs.
    order : numpy.ndarray
        Node elimination order.

    Returns
    -------
    udof : numpy.ndarray
        Displacement dofs, (n, 2).
    pdof : numpy.ndarray
        Pressure dofs, (n,).
    ndof : int
        Number of dofs.
    n_internal : int
        Number of internal dofs.
    """
    n = free.shape[0]
    vertex = np.zeros(n, dtype=bool)
    vertex[tri[:, :3]] = True
    retained = np.zeros((n, 2), dtype=bool)
    retained[b_nodes, b_comps] = True
    if np.any(~free[b_nodes, b_comps]):
        raise SolverError("a retained dof of the substructure is fixed")
    own = free & ~retained
    late = vertex & ~free.any(axis=1)
    early_p = vertex & ~late
    pos = np.empty(n, dtype=np.int64)
    pos[order] = np.arange(order.size)
    # sort keys: (position of the node, component) for early dofs; late pressures after
    key_nodes = np.repeat(np.arange(n)[:, None], 3, axis=1)
    keys = pos[key_nodes] * 3 + np.arange(3)[None, :]
    mask = np.column_stack([own, early_p])
    keys = np.where(mask, keys, -1)
    n_early = int(mask.sum())
    udof = np.full((n, 2), -1, dtype=np.int64)
    pdof = np.full(n, -1, dtype=np.int64)
    flat = np.flatnonzero(mask.ravel())
    rank = np.empty(flat.size, dtype=np.int64)
    rank[np.argsort(keys.ravel()[flat], kind="stable")] = np.arange(flat.size)
    numbers = np.full(3 * n, -1, dtype=np.int64)
    numbers[flat] = rank
    numbers = numbers.reshape(n, 3)
    udof[own] = numbers[:, :2][own]
    pdof[early_p] = numbers[early_p, 2]
    late_nodes = np.flatnonzero(late)
    late_nodes = late_nodes[np.argsort(pos[late_nodes], kind="stable")]
    pdof[late_nodes] = n_early + np.arange(late_nodes.size)
    n_internal = n_early + late_nodes.size
    udof[b_nodes, b_comps] = n_internal + np.arange(b_nodes.size)
    return udof, pdof, n_internal + b_nodes.size, n_internal


def schur_complement(K: Any, n_int: int) -> tuple[np.ndarray, float, int, bool]:
    """``S = K_BB - K_BI K_II^-1 K_IB`` of a sparse square ``K`` (any scipy sparse format)
    whose last rows and columns, from ``n_int`` on, are ``B``.

    Returns ``(S, backward_error, nnz of the factors, pivoted)``: the trailing block of a
    pivot-free LU in the given order when its backward error is at most
    :data:`ssw.contact.lu.BACKWARD_ERROR_TOL` (module docstring), else from a pivoted LU of
    ``K_II`` and one solve per column of ``K_IB``.

    Parameters
    ----------
    K : scipy.sparse matrix
        The square stiffness.
    n_int : int
        Number of internal dofs (they come first).

    Returns
    -------
    tuple
        ``(S, backward_error, nnz, pivoted)``.
    """
    return schur_factor(K, n_int)[:4]


def schur_factor(K: Any, n_int: int) -> tuple[np.ndarray, float, int, bool, Any]:
    """:func:`schur_complement` and the factorization it came from.

    Parameters
    ----------
    K : scipy.sparse matrix
        Square, the retained dofs ``B`` last (from ``n_int`` on).
    n_int : int
        The number of internal dofs.

    Returns
    -------
    tuple
        ``(S, backward_error, nnz, pivoted, lu)``: those of :func:`schur_complement` and
        ``lu`` the pivot-free SuperLU factorization of the whole ``K`` (its leading blocks
        ``L_II``, ``U_II`` factor ``K_II``: the body's interior solves reuse them,
        :mod:`ssw.contact.stress`), or None when the pivoted fallback was used.
    """
    from ssw.contact import lu as ssw_lu

    K = K.tocsc()
    n = K.shape[0]
    lu = ssw_lu.diagonal_lu(K)
    ident = np.arange(n)
    if (lu is not None and np.array_equal(lu.perm_r, ident)
            and np.array_equal(lu.perm_c, ident)):
        x = ssw_lu.probe(n)
        berr = ssw_lu.backward_error(K, x, K @ x - lu.L @ (lu.U @ x))
        if berr <= ssw_lu.BACKWARD_ERROR_TOL:
            # the trailing blocks: columns first (CSC), then their rows, then dense
            L22 = lu.L[:, n_int:][n_int:].toarray()
            U22 = lu.U[:, n_int:][n_int:].toarray()
            return L22 @ U22, berr, int(lu.L.nnz + lu.U.nnz), False, lu
    # stable fallback: threshold-pivoted LU of K_II, one solve per retained dof
    KII = K[:n_int, :n_int].tocsc()
    lu = ssw_lu.pivoted_lu(KII)
    KIB = K[:n_int, n_int:].toarray()
    X = lu.solve(KIB)
    berr = ssw_lu.backward_error(KII, X, KII @ X - KIB, KIB)
    S = K[n_int:, n_int:].toarray() - K[n_int:, :n_int] @ X
    return np.asarray(S), berr, int(lu.L.nnz + lu.U.nnz), True, None


class LeadingBlock:
    """The interior displacements of a body from its retained ones, with the pivot-free LU of
    its whole matrix (identity row and column permutations): ``K = L U``, interior dofs
    first.

    ``x_I = -K_II^-1 K_IB u_B``, and ``K_IB = L_II U_IB`` (the blocks of ``L U``), so ``x_I =
    -U_II^-1 U_IB u_B``: one upper triangular solve, no solve with ``L``. With ``U = D V``
    (``D`` the diagonal of ``U``, ``V`` unit upper triangular, both taken once here),
    ``x_I = -V_II^-1 V_IB u_B``, the interior rows of ``V x = [-V_IB u_B; 0]``, whose
    retained rows are exactly 0. Solved by scipy's ``spsolve_triangular`` with
    ``unit_diagonal``: given ``V``, it skips its per-call scaling of the matrix by its
    diagonal and the conversion to CSC (1 mm PLA plate, 19 k dofs, 1.6 M nonzeros of ``U``,
    7 states: 0.012 s to prepare ``V`` and 0.012 s a solve, against 0.012 s and 0.045 s for
    ``U`` in CSR passed as it is; measured with ``time.perf_counter``, best of 3).

    Parameters
    ----------
    lu : scipy.sparse.linalg.SuperLU
        The pivot-free factorization of the whole matrix (``perm_r``, ``perm_c`` the
        identity; :func:`ssw.contact.substructure.schur_factor` checks it).
    n : int
        The number of interior dofs (the leading block's size).
    """

    def __init__(self, lu: Any, n: int) -> None:
        import scipy.sparse as sp

        U = sp.csc_array(lu.U)
        d = U.diagonal()
        # V = D^-1 U: each entry divided by the diagonal of its row; its row indices (sorted,
        # as SuperLU gives them) checked once here, not on every solve
        V = sp.csc_array((U.data / d[U.indices], U.indices, U.indptr), shape=U.shape)
        V.sort_indices()
        self.V, self.V_IB = V, V[:, n:][:n]
        self.n = n

    def interior(self, u_B: np.ndarray) -> np.ndarray:
        """``x_I = -K_II^-1 K_IB u_B``.

        Parameters
        ----------
        u_B : numpy.ndarray
            (n_B,) or (n_B, k) retained displacements.

        Returns
        -------
        numpy.ndarray
            (n,) or (n, k), the interior displacements.
        """
        from scipy.sparse.linalg import spsolve_triangular

        rhs = np.zeros((self.V.shape[0], *u_B.shape[1:]))
        rhs[: self.n] = -np.asarray(self.V_IB @ u_B)
        return spsolve_triangular(self.V, rhs, lower=False, unit_diagonal=True,
                                  overwrite_b=True)[: self.n]


@dataclass(frozen=True)
class BodyMatrix:
    """A body's u-p stiffness at unit E, interior dofs first (``K[:n_int, :n_int]`` is
    ``K_II``), divided by ``scale`` (nondimensional); ``udof`` (n_local, 2) its displacement
    dofs (-1: fixed), ``nodes``/``tri`` the body's own (local) mesh.

    Parameters
    ----------
    K : scipy.sparse matrix
        The u-p stiffness at unit E over ``scale``, interior dofs first.
    n_int : int
        Number of interior dofs.
    ndof : int
        Number of dofs.
    scale : float
        Its scale (N/m per Pa).
    udof : numpy.ndarray
        Displacement dofs, (n_local, 2); -1: fixed.
    nodes : numpy.ndarray
        The body's node coordinates (m).
    tri : numpy.ndarray
        The body's triangles (local indices).
    """

    K: Any
    n_int: int
    ndof: int
    scale: float
    udof: np.ndarray
    nodes: np.ndarray
    tri: np.ndarray


def body_matrix(
    nodes: np.ndarray, tri: np.ndarray, nu: Any, free: np.ndarray,
    b_nodes: np.ndarray, b_comps: np.ndarray, order_nodes, E: Any = 1.0,
) -> BodyMatrix:
    """The u-p stiffness (unit E) of the body meshed by ``tri`` with the retained dofs
    ``(b_nodes, b_comps)`` last (arguments as :func:`condense_body`); ``E`` and ``nu`` may
    vary by element (a lift on a subgrade: E relative to the lift's).

    Parameters
    ----------
    nodes : numpy.ndarray
        Node coordinates (r, z) (m), (n, 2).
    tri : numpy.ndarray
        Quadratic triangles (node indices, gmsh order), (ne, 6).
    nu : array_like
        Poisson's ratio, scalar or per element.
    free : numpy.ndarray
        Free displacement components, (n, 2) bool.
    b_nodes : numpy.ndarray
        Nodes of the retained dofs.
    b_comps : numpy.ndarray
        Components of the retained dofs.
    order_nodes : callable
        ``order_nodes(rows, cols, n)``: a fill-reducing permutation.
    E : array_like
        Young's modulus relative to the body's, scalar or per element.

    Returns
    -------
    BodyMatrix
        The u-p stiffness and its dof numbering.
    """
    import scipy.sparse as sp

    from ssw.contact.assembly import node_graph

    used = np.unique(tri)
    local = np.full(nodes.shape[0], -1, dtype=np.int64)
    local[used] = np.arange(used.size)
    ltri, lnodes = local[tri], nodes[used]
    lb = local[b_nodes]
    if np.any(lb < 0):
        raise SolverError("a retained node does not belong to the body")
    order = order_nodes(*node_graph(ltri), used.size)
    udof, pdof, ndof, n_int = body_dofs(ltri, free[used], lb, np.asarray(b_comps), order)
    G, inv_K = lame(np.broadcast_to(np.asarray(E, float), (len(ltri),)),
                    np.broadcast_to(np.asarray(nu, float), (len(ltri),)))
    ke = element_matrices(lnodes[ltri], G, inv_K, pressure_scale(lnodes, ltri, G))
    scale = float(pow2(np.min(G) * np.min(element_sizes(lnodes, ltri))))
    edof = np.concatenate([udof[ltri, 0], udof[ltri, 1], pdof[ltri[:, :3]]], axis=1)
    rows = np.repeat(edof, 15, axis=1).ravel()
    cols = np.tile(edof, (1, 15)).ravel()
    keep = (rows >= 0) & (cols >= 0)
    K = sp.csc_array((ke.ravel()[keep] / scale, (rows[keep], cols[keep])), shape=(ndof, ndof))
    K.sum_duplicates()
    return BodyMatrix(K, int(n_int), int(ndof), scale, udof, lnodes, ltri)


def condense_body(
    nodes: np.ndarray, tri: np.ndarray, nu: Any, free: np.ndarray,
    b_nodes: np.ndarray, b_comps: np.ndarray, order_nodes, E: Any = 1.0,
) -> Condensation:
    """Condensed stiffness (unit E) of the body meshed by ``tri`` onto the retained dofs.

    Parameters
    ----------
    nodes : numpy.ndarray
        (n, 2) every node of the model, m (only those of ``tri`` are used).
    tri : numpy.ndarray
        (ne, 6) the body's quadratic triangles.
    nu : float or numpy.ndarray
        The body's Poisson's ratio, (-1, 0.5].
    free : numpy.ndarray
        (n, 2) bool, displacement components that are not fixed (rollers, axis, bottom).
    b_nodes : numpy.ndarray
        (nb,) the retained dofs' nodes, in order.
    b_comps : numpy.ndarray
        (nb,) the retained dofs' components (0 = u_r, 1 = u_z), in that order.
    order_nodes : callable
        ``(rows, cols, n) -> permutation`` (nested dissection).
    E : float or numpy.ndarray
        The body's Young's modulus, Pa (1: the unit-E operator).

    Returns
    -------
    Condensation
        The condensed stiffness and how it was made.
    """
    t0 = time.perf_counter()
    bm = body_matrix(nodes, tri, nu, free, b_nodes, b_comps, order_nodes, E)
    K, n_int, ndof, scale = bm.K, bm.n_int, bm.ndof, bm.scale
    t1 = time.perf_counter()
    S, berr, nnz, pivoted, lu = schur_factor(K, n_int)
    t2 = time.perf_counter()
    S = 0.5 * (S + S.T) * scale
    if S.shape != (b_nodes.size,) * 2 or not np.all(np.isfinite(S)):
        raise SolverError("the condensed stiffness of a substructure is not finite")
    return Condensation(S, int(ndof), nnz, berr, pivoted, t1 - t0, t2 - t1, bm, lu)
