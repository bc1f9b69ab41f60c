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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.contact.elements import element_matrices, lame
from ssw.contact.mesh import Mesh
from ssw.errors import ConfigError

INTERFACES = ("bonded", "frictionless", "unilateral")


@dataclass(frozen=True)
class System:
    """The assembled problem: COO triplets and the dof maps. SI units.

    ``udof`` (n, 2): global index of (u_r, u_z) per node, -1 where fixed; ``pdof`` (n,):
    pressure index (-1 at midside nodes); ``nodes`` (n, 2) m after duplicating the plate's
    interface nodes; ``tri`` (ne, 6); ``iface`` (m, 2): (soil node, plate node) pairs.
    Pressure unknowns are ``p / G`` with the shear modulus G of their body.
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


def split_interface(mesh: Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Duplicate the interface nodes of the plate. Returns (nodes, tri, pairs (m, 2))."""
    if not np.any(mesh.body == 1):
        return mesh.nodes, mesh.tri, np.zeros((0, 2), dtype=np.int64)
    tol = 1e-9 * mesh.soil_radius
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
    soil_radius: float, soil_depth: float,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Global dof indices: ``udof`` (n, 2), ``pdof`` (n,), ``ndof``. -1 marks no dof.

    ``order`` is the elimination order of the nodes (a permutation of ``range(n)``).
    """
    if interface not in INTERFACES:
        raise ConfigError("contact.interface", interface, " | ".join(INTERFACES))
    n = len(nodes)
    tol = 1e-9 * soil_radius
    r, z = nodes[:, 0], nodes[:, 1]
    free = np.ones((n, 2), dtype=bool)
    free[r < tol, 0] = False  # symmetry axis
    free[r > soil_radius - tol, 0] = False  # rollers
    free[z < -soil_depth + tol] = False  # fixed bottom
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


def node_graph(tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """COO (rows, cols) of the node adjacency graph (nodes sharing an element)."""
    rr = np.repeat(tri, tri.shape[1], axis=1).ravel()
    cc = np.tile(tri, (1, tri.shape[1])).ravel()
    return rr, cc


def elimination_order(tri: np.ndarray, pairs: np.ndarray, n: int, order_nodes) -> np.ndarray:
    """Node elimination order: ``order_nodes`` on the graph where the two copies of an
    interface node are one vertex (they may share dofs), each copy right after its twin."""
    rep = np.arange(n)
    rep[pairs[:, 1]] = pairs[:, 0]
    perm = order_nodes(*node_graph(rep[tri]), n)
    pos = np.empty(n)
    pos[perm] = np.arange(n)
    return np.argsort(pos[rep] + 0.5 * (rep != np.arange(n)), kind="stable")


def assemble(
    mesh: Mesh, E: tuple[float, float], nu: tuple[float, float], interface: str,
    order_nodes,
) -> System:
    """Assemble the mixed u-p stiffness of soil (body 0) and plate (body 1).

    Parameters
    ----------
    mesh : the section mesh.
    E, nu : (soil, plate) Young's moduli (Pa) and Poisson's ratios.
    interface : ``bonded`` | ``frictionless`` | ``unilateral``.
    order_nodes : callable ``(rows, cols, n) -> permutation`` (nested dissection).
    """
    nodes, tri, pairs = split_interface(mesh)
    n = len(nodes)
    order = elimination_order(tri, pairs, n, order_nodes)
    udof, pdof, ndof = number_dofs(
        nodes, tri, pairs, interface, order, mesh.soil_radius, mesh.soil_depth
    )
    body = mesh.body.astype(np.int64)
    G, inv_K = lame(np.asarray(E)[body], np.asarray(nu)[body])
    ke = element_matrices(nodes[tri], G, inv_K, G)
    edof = np.concatenate([udof[tri, 0], udof[tri, 1], pdof[tri[:, :3]]], axis=1)
    rows = np.repeat(edof, 15, axis=1).ravel()
    cols = np.tile(edof, (1, 15)).ravel()
    vals = ke.ravel()
    keep = (rows >= 0) & (cols >= 0)
    return System(rows[keep], cols[keep], vals[keep], ndof, udof, pdof, nodes, tri, body,
                  pairs)
