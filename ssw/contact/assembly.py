"""Degrees of freedom, interfaces, boundary conditions and the global sparse u-p matrix.

The plate-soil interface nodes are duplicated for the plate; the interface law then only
decides which displacement components the two copies share:

* ``bonded``: both (the plate is glued to the soil);
* ``frictionless``: ``u_z`` only (sliding without separation, the thesis's interface);
* ``unilateral``: none, except at the axis (the pair under the load); separation and
  contact are then constraints of the contact problem (:mod:`ssw.contact.contact_lcp`).

The pressure is always discontinuous across the interface (two materials). Boundary
conditions: ``u_r = 0`` on the axis ``r = 0`` (symmetry) and on the lateral boundary
(rollers), ``u = 0`` on the bottom.

Dofs are numbered node by node in a nested-dissection order of the node graph, a node's
displacements before its pressure, so that an LU factorization in this ("natural") order
meets no zero pivot in the saddle-point system even at ``nu = 0.5``.

Scaling. The LU detects a zero pivot by an *absolute* threshold (PETSc's
``-pc_factor_zeropivot``, 100 machine epsilons = 2.2e-14), so the matrix is assembled
nondimensional, with every pivot of order one or larger. A displacement pivot is a
stiffness ``~ G r`` (N/m; ``r`` the radius of the node, at least the local element size
``h``), but with the pressure unknown ``p / G`` a pressure pivot (the Schur complement
``-C - B A^-1 B^T``) is ``~ G r h^2``, ``~ G h^3`` at the contact point: for the contact
meshes of 1.6e-7 m and 1.6e-8 m (indentations of 1e-7 m and 1e-9 m, soil of 50 MPa) that is
~1e-13 and ~1e-16, at or below the threshold, and the factorization stopped with a "zero
pivot" although the matrix is regular (with the threshold off, both curves are within
0.11 % of Hertz). Hence (:func:`pressure_scale`) the pressure unknown
of a vertex is ``p h_i / G`` (``h_i`` the smallest element size at the vertex), which makes
``B ~ G r`` like ``A``; and the whole matrix is divided by ``scale ~ G_min h_min`` (the
softest body's shear modulus times the smallest element size), so that the smallest pivots
are O(1) and the threshold keeps its meaning of "zero relative to the problem". Both factors
are powers of two: the LU (no pivoting) then gives exactly, bit for bit, the unscaled
factorization's numbers, scaled.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.contact.elements import element_matrices, lame, triangle_jacobian
from ssw.contact.mesh import Mesh
from ssw.errors import ConfigError

INTERFACES = ("bonded", "frictionless", "unilateral")
#: Geometric tolerance (a node lies on a line) relative to the smallest element size: far
#: above the round-off of gmsh's coordinates (1e-16 m on a 1 m domain), far below the
#: distance of any other node (half an element).
GEOM_TOL_REL = 1e-6


def geometric_tolerance(nodes: np.ndarray, tri: np.ndarray) -> float:
    """Distance (m) below which a node counts as lying on a boundary line:
    :data:`GEOM_TOL_REL` times the smallest element size of the mesh.

    Parameters
    ----------
    nodes : numpy.ndarray
        Node coordinates (r, z) (m), (n, 2).
    tri : numpy.ndarray
        Quadratic triangles (node indices, gmsh order), (ne, 6).

    Returns
    -------
    float
        Tolerance (m).
    """
    return GEOM_TOL_REL * float(np.min(element_sizes(nodes, tri)))


@dataclass(frozen=True)
class System:
    """The assembled problem: COO triplets and the dof maps. SI units.

    ``udof`` (n, 2): global index of (u_r, u_z) per node, -1 where fixed; ``pdof`` (n,):
    pressure index (-1 at midside nodes); ``nodes`` (n, 2) m after duplicating the plate's
    interface nodes; ``tri`` (ne, 6); ``iface`` (m, 2): (soil node, plate node) pairs.
    The stiffness is ``scale * A`` with ``A`` the assembled (nondimensional) matrix of the
    triplets and ``scale`` in N/m; pressure unknowns are ``p h_i / G`` (see the module
    docstring), so the displacement part of a solution ``K^-1 f`` is in m, and ``x^T K x``
    is the energy whatever the pressure scaling.

    Parameters
    ----------
    rows : numpy.ndarray
        Row indices of the triplets.
    cols : numpy.ndarray
        Column indices of the triplets.
    vals : numpy.ndarray
        Values of the triplets (nondimensional).
    ndof : int
        Number of dofs.
    udof : numpy.ndarray
        Index of (u_r, u_z) per node, (n, 2); -1 where fixed.
    pdof : numpy.ndarray
        Pressure index per node, (n,); -1 at midside nodes.
    nodes : numpy.ndarray
        Node coordinates (m), (n, 2).
    tri : numpy.ndarray
        Quadratic triangles, (ne, 6).
    body : numpy.ndarray
        Body of each element (0 soil, 1 plate).
    iface : numpy.ndarray
        (soil node, plate node) pairs, (m, 2).
    scale : float
        Stiffness scale (N/m).
    """

    rows: np.ndarray
    cols: np.ndarray
    vals: np.ndarray
    ndof: int
    udof: np.ndarray
    pdof: np.ndarray
    nodes: np.ndarray
    tri: np.ndarray
    body: np.ndarray
    iface: np.ndarray
    scale: float = 1.0


def split_interface(mesh: Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Duplicate the interface nodes of the plate. Returns (nodes, tri, pairs (m, 2)).

    Parameters
    ----------
    mesh : Mesh
        The plate-on-soil mesh (m).

    Returns
    -------
    nodes : numpy.ndarray
        Node coordinates with the plate's interface copies appended (m).
    tri : numpy.ndarray
        Triangles, the plate's on the copies.
    pairs : numpy.ndarray
        (soil node, plate copy) pairs, (m, 2).
    """
    if not np.any(mesh.body == 1):
        return mesh.nodes, mesh.tri, np.zeros((0, 2), dtype=np.int64)
    tol = geometric_tolerance(mesh.nodes, mesh.tri)
    plate_nodes = np.unique(mesh.tri[mesh.body == 1])
    soil_nodes = np.unique(mesh.tri[mesh.body == 0])
    shared = np.intersect1d(plate_nodes, soil_nodes)
    shared = shared[np.abs(mesh.nodes[shared, 1]) < tol]
    n = len(mesh.nodes)
    copy = np.arange(n)
    copy[shared] = n + np.arange(len(shared))
    tri = mesh.tri.copy()
    tri[mesh.body == 1] = copy[tri[mesh.body == 1]]
    nodes = np.vstack([mesh.nodes, mesh.nodes[shared]])
    return nodes, tri, np.stack([shared, copy[shared]], axis=1)


def number_dofs(
    nodes: np.ndarray, tri: np.ndarray, pairs: np.ndarray, interface: str, order: np.ndarray,
    soil_radius: float, soil_depth: float, base: str = "bonded", lateral: str = "mould",
) -> tuple[np.ndarray, np.ndarray, int]:
    """Global dof indices: ``udof`` (n, 2), ``pdof`` (n,), ``ndof``. -1 marks no dof.

    ``order`` is the elimination order of the nodes (a permutation of ``range(n)``).

    Parameters
    ----------
    nodes : numpy.ndarray
        Node coordinates (r, z) (m), (n, 2).
    tri : numpy.ndarray
        Quadratic triangles (node indices, gmsh order), (ne, 6).
    pairs : numpy.ndarray
        Interface (soil, plate) node pairs, (m, 2).
    interface : str
        The plate-soil interface (``INTERFACES``).
    order : numpy.ndarray
        Node elimination order, a permutation of ``range(n)``.
    soil_radius : float
        Radius of the soil domain (m).
    soil_depth : float
        Depth of the soil domain (m).
    base : str
        Bottom condition: ``bonded`` or ``sliding``.
    lateral : str
        Lateral condition: ``mould`` or ``free``.

    Returns
    -------
    udof : numpy.ndarray
        Displacement dofs, (n, 2).
    pdof : numpy.ndarray
        Pressure dofs, (n,).
    ndof : int
        Number of dofs.

    Raises
    ------
    ConfigError
        If the interface, base or lateral condition is unknown.
    """
    if interface not in INTERFACES:
        raise ConfigError("contact.interface", interface, " | ".join(INTERFACES))
    n = len(nodes)
    tol = geometric_tolerance(nodes, tri)
    r = nodes[:, 0]
    free = fixed_free(nodes, tol, soil_radius, soil_depth, base, lateral)
    master = np.tile(np.arange(n)[:, None], (1, 2))  # node whose dof each component uses
    soil, plate = pairs[:, 0], pairs[:, 1]
    if interface == "bonded":
        master[plate] = soil[:, None]
    elif interface == "frictionless":
        master[plate, 1] = soil
    else:
        on_axis = r[plate] < tol
        master[plate[on_axis], 1] = soil[on_axis]
    own = free & (master == np.arange(n)[:, None])
    vertex = np.zeros(n, dtype=bool)
    vertex[tri[:, :3]] = True
    count = own.sum(axis=1) + vertex
    start = np.zeros(n, dtype=np.int64)
    start[order] = np.concatenate([[0], np.cumsum(count[order])[:-1]])
    udof = np.where(own[:, 0], start, -1)
    udof = np.stack([udof, np.where(own[:, 1], start + own[:, 0], -1)], axis=1)
    udof[~free] = -1
    udof = np.where(free, udof[master, np.arange(2)[None, :]], -1)
    pdof = np.where(vertex, start + own.sum(axis=1), -1)
    return udof, pdof, int(count.sum())


def fixed_free(nodes: np.ndarray, tol: float, soil_radius: float,
               soil_depth: float, base: str = "bonded", lateral: str = "mould") -> np.ndarray:
    """(n, 2) bool, the displacement components that are free: ``u_r = 0`` on the axis
    (symmetry); on the lateral boundary ``u_r = 0`` (``mould``: rollers, a rigid
    frictionless wall; the half-space box) or nothing (``free``); on the bottom ``u = 0``
    (``bonded``; the half-space box) or ``u_z = 0`` (``sliding``: a rigid frictionless
    base).

    Parameters
    ----------
    nodes : numpy.ndarray
        Node coordinates (r, z) (m), (n, 2).
    tol : float
        Geometric tolerance (m).
    soil_radius : float
        Radius of the soil domain (m).
    soil_depth : float
        Depth of the soil domain (m).
    base : str
        Bottom condition: ``bonded`` or ``sliding``.
    lateral : str
        Lateral condition: ``mould`` or ``free``.

    Returns
    -------
    numpy.ndarray
        Free components, (n, 2) bool.

    Raises
    ------
    ConfigError
        If ``base`` or ``lateral`` is unknown.
    """
    r, z = nodes[:, 0], nodes[:, 1]
    free = np.ones((len(nodes), 2), dtype=bool)
    free[r < tol, 0] = False  # symmetry axis
    if lateral == "mould":
        free[r > soil_radius - tol, 0] = False  # rollers
    elif lateral != "free":
        raise ConfigError("sample.lateral", lateral, "mould | free")
    bottom = z < -soil_depth + tol
    if base == "bonded":
        free[bottom] = False
    elif base == "sliding":
        free[bottom, 1] = False
    else:
        raise ConfigError("sample.base", base, "bonded | sliding")
    return free


def node_graph(tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """COO (rows, cols) of the node adjacency graph (nodes sharing an element).

    Parameters
    ----------
    tri : numpy.ndarray
        Elements (node indices), (ne, k).

    Returns
    -------
    rows : numpy.ndarray
        Row indices.
    cols : numpy.ndarray
        Column indices.
    """
    rr = np.repeat(tri, tri.shape[1], axis=1).ravel()
    cc = np.tile(tri, (1, tri.shape[1])).ravel()
    return rr, cc


def elimination_order(tri: np.ndarray, pairs: np.ndarray, n: int, order_nodes) -> np.ndarray:
    """Node elimination order: ``order_nodes`` on the graph where the two copies of an
    interface node are one vertex (they may share dofs), each copy right after its twin.

    Parameters
    ----------
    tri : numpy.ndarray
        Quadratic triangles (node indices, gmsh order), (ne, 6).
    pairs : numpy.ndarray
        Interface (soil, plate copy) node pairs, (m, 2).
    n : int
        Number of nodes.
    order_nodes : callable
        ``order_nodes(rows, cols, n)``: a fill-reducing permutation of a graph.

    Returns
    -------
    numpy.ndarray
        The node order, (n,).
    """
    rep = np.arange(n)
    rep[pairs[:, 1]] = pairs[:, 0]
    perm = order_nodes(*node_graph(rep[tri]), n)
    pos = np.empty(n)
    pos[perm] = np.arange(n)
    return np.argsort(pos[rep] + 0.5 * (rep != np.arange(n)), kind="stable")


def pow2(x: np.ndarray) -> np.ndarray:
    """The power of two nearest to ``x`` (> 0) on a log scale: scaling by it is exact.

    Parameters
    ----------
    x : numpy.ndarray
        Positive values.

    Returns
    -------
    numpy.ndarray
        Powers of two, the shape of ``x``.
    """
    return np.exp2(np.round(np.log2(x)))


def element_sizes(nodes: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(ne,) size of every element, m: ``sqrt(2 area)`` of its vertex triangle.

    Parameters
    ----------
    nodes : numpy.ndarray
        Node coordinates (r, z) (m), (n, 2).
    tri : numpy.ndarray
        Quadratic triangles (node indices, gmsh order), (ne, 6).

    Returns
    -------
    numpy.ndarray
        Element sizes (m), (ne,).
    """
    return np.sqrt(np.abs(triangle_jacobian(nodes[tri[:, :3]])[1]))


def pressure_scale(nodes: np.ndarray, tri: np.ndarray, G: np.ndarray) -> np.ndarray:
    """(ne, 3) ``p_scale`` of the element vertices: ``G / h_i`` rounded to ``G`` times a
    power of two, ``h_i`` the smallest size of the elements at vertex ``i`` (a pressure
    vertex belongs to one body, so all its elements agree).

    Parameters
    ----------
    nodes : numpy.ndarray
        Node coordinates (r, z) (m), (n, 2).
    tri : numpy.ndarray
        Quadratic triangles (node indices, gmsh order), (ne, 6).
    G : numpy.ndarray
        Shear modulus of each element (Pa), (ne,).

    Returns
    -------
    numpy.ndarray
        Pressure scales (Pa/m), (ne, 3).
    """
    h = element_sizes(nodes, tri)
    h_node = np.full(len(nodes), np.inf)
    np.minimum.at(h_node, tri[:, :3], h[:, None])
    return G[:, None] * pow2(1.0 / h_node[tri[:, :3]])


def assemble(
    mesh: Mesh, E: tuple[float, float], nu: tuple[float, float], interface: str,
    order_nodes, fixed_faces: float = 1.0,
) -> System:
    """Assemble the mixed u-p stiffness of soil (body 0) and plate (body 1).

    Parameters
    ----------
    mesh : ssw.contact.mesh.Mesh
        The section mesh.
    E : tuple of float
        ``(soil, plate)`` Young's moduli, Pa.
    nu : tuple of float
        ``(soil, plate)`` Poisson's ratios.
    interface : str
        ``bonded`` | ``frictionless`` | ``unilateral``.
    order_nodes : callable
        ``(rows, cols, n) -> permutation`` (nested dissection).
    fixed_faces : float
        Where the rollers and the fixed bottom lie, as a multiple of the mesh's soil
        radius and depth (1: on its faces; 2: beyond them, a free truncation boundary as
        the dynamic wall's absorbing one).

    Returns
    -------
    System
        The assembled problem.
    """
    nodes, tri, pairs = split_interface(mesh)
    n = len(nodes)
    order = elimination_order(tri, pairs, n, order_nodes)
    udof, pdof, ndof = number_dofs(
        nodes, tri, pairs, interface, order, fixed_faces * mesh.soil_radius,
        fixed_faces * mesh.soil_depth, mesh.base, mesh.lateral
    )
    body = mesh.body.astype(np.int64)
    E_el, nu_el = np.asarray(E, float)[body], np.asarray(nu, float)[body]
    if mesh.subgrade is not None:  # a lift on a subgrade: the soil's lower region
        E_el = np.where(mesh.subgrade, E[0] * mesh.subgrade_ratio, E_el)
        nu_el = np.where(mesh.subgrade, mesh.subgrade_nu, nu_el)
    G, inv_K = lame(E_el, nu_el)
    ke = element_matrices(nodes[tri], G, inv_K, pressure_scale(nodes, tri, G))
    scale = float(pow2(np.min(G) * np.min(element_sizes(nodes, tri))))
    edof = np.concatenate([udof[tri, 0], udof[tri, 1], pdof[tri[:, :3]]], axis=1)
    rows = np.repeat(edof, 15, axis=1).ravel()
    cols = np.tile(edof, (1, 15)).ravel()
    vals = ke.ravel() / scale
    keep = (rows >= 0) & (cols >= 0)
    return System(rows[keep], cols[keep], vals[keep], ndof, udof, pdof, nodes, tri, body,
                  pairs, scale)


def top_surface_weights(mesh_nodes: np.ndarray, tri: np.ndarray, top_elems: np.ndarray,
                        top: float, tol: float) -> np.ndarray:
    """``int N_j 2 pi r ds`` (m^2) over the top surface for every node (0 off the surface).

    Parameters
    ----------
    mesh_nodes : numpy.ndarray
        Node coordinates (r, z) (m), (n, 2).
    tri : numpy.ndarray
        Quadratic triangles (node indices, gmsh order), (ne, 6).
    top_elems : numpy.ndarray
        Indices of the elements of the top body.
    top : float
        Height of the top surface (m).
    tol : float
        Geometric tolerance (m).

    Returns
    -------
    numpy.ndarray
        Surface weights (m^2), (n,).
    """
    w = np.zeros(len(mesh_nodes))
    t6 = tri[top_elems]
    for a, b, m in ((0, 1, 3), (1, 2, 4), (2, 0, 5)):
        e = t6[:, [a, b, m]]
        on = np.all(np.abs(mesh_nodes[e, 1] - top) < tol, axis=1)
        e = e[on]
        ra, rb = mesh_nodes[e[:, 0], 0], mesh_nodes[e[:, 1], 0]
        length = np.abs(rb - ra)
        s, gw = np.polynomial.legendre.leggauss(4)
        s, gw = 0.5 * (s + 1.0), 0.5 * gw
        n = np.stack([(1 - s) * (1 - 2 * s), s * (2 * s - 1), 4 * s * (1 - s)], axis=1)
        r = ra[:, None] * (1 - s) + rb[:, None] * s  # (ne, nq)
        contrib = np.einsum("q,eq,qi->ei", gw, 2 * np.pi * r * length[:, None], n)
        np.add.at(w, e, contrib)
    return w
