"""Axisymmetric elastodynamic operators of plate and soil: stiffness, mass, absorbing boundary.

The equations of motion of the discretized plate and soil are

    M u'' + C u' + (K + K_b) u = G^T lam,

with ``K`` the mixed u-p (Taylor-Hood P2-P1) stiffness of :mod:`ssw.contact.assembly`
(same mesh, dof numbering, scaling and interfaces), ``M`` the consistent mass of the
displacement dofs (the pressure dofs carry none)

    M_ab = int rho N_a N_b 2 pi r dr dz   (each displacement component),

integrated exactly (degree-5 rule, Dunavant 1985: ``N_a N_b r`` has degree 5), and, for the
``absorbing`` boundary, Lysmer-Kuhlemeyer dashpots (Lysmer & Kuhlemeyer 1969) in parallel
with static springs on the lateral (``r = L``) and bottom (``z = -L``) faces:

    t_n = -(rho c_p u_n' + alpha_n G / R u_n),   t_t = -(rho c_s u_t' + alpha_t G / R u_t),

``R`` the distance of the boundary point from the load point (the origin), ``c_p``, ``c_s``
the soil's wave speeds (``c_p`` capped for nearly incompressible soils,
:attr:`Material.c_p_boundary`); ``alpha_n = 4/3``, ``alpha_t = 2/3`` are the viscous-spring
boundary's coefficients of Liu et al. (2006) [recalled; their static effect is measured by
the rigid-punch static stiffness of ``ssw bench dynamic``]. The dashpots absorb plane P
and S waves at normal incidence exactly; the springs carry the static load (the chain's
weight) that dashpots alone could not. The ``fixed`` boundary is the quasi-static FEM's
(rollers on ``r = L``, fixed bottom): the same operator as ``ssw contact`` with mass added.

References
----------
Lysmer, J. & Kuhlemeyer, R. L. (1969). Finite dynamic model for infinite media. J. Eng.
Mech. Div. ASCE 95(EM4), 859-877.
Miller, G. F. & Pursey, H. (1955). On the partition of energy between elastic waves in a
semi-infinite solid. Proc. R. Soc. A 233, 55-69.
Liu, J., Du, Y., Du, X., Wang, Z. & Wu, J. (2006). 3D viscous-spring artificial boundary in
time domain. Earthquake Eng. Eng. Vib. 5(1), 93-102.
Dunavant, D. A. (1985). High degree efficient symmetrical Gaussian quadrature rules for the
triangle. Int. J. Numer. Meth. Eng. 21, 1129-1148.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.contact.assembly import System, assemble
from ssw.contact.elements import p2_shape, triangle_jacobian
from ssw.contact.mesh import Mesh
from ssw.errors import ConfigError

BOUNDARIES = ("absorbing", "fixed")
#: Viscous-spring boundary coefficients (Liu et al. 2006): normal and tangential springs
#: ``alpha G / R``.
ALPHA_N, ALPHA_T = 4.0 / 3.0, 2.0 / 3.0
#: Largest c_p / c_s the boundary uses (nu = 0.467; :attr:`Material.c_p_boundary`).
C_P_CAP = 4.0

#: Dunavant (1985) degree-5, 7-point rule on the reference triangle (weights sum to 1/2).
_A1, _B1 = 0.470142064105115, 0.059715871789770
_A2, _B2 = 0.101286507323456, 0.797426985353087
MASS_POINTS = np.array([
    [1.0 / 3.0, 1.0 / 3.0],
    [_A1, _A1], [_B1, _A1], [_A1, _B1],
    [_A2, _A2], [_B2, _A2], [_A2, _B2],
])
MASS_WEIGHTS = 0.5 * np.array([0.225] + [0.132394152788506] * 3 + [0.125939180544827] * 3)


@dataclass(frozen=True)
class Material:
    """An isotropic elastic solid: E (Pa), nu (-), density (kg/m^3).

    Parameters
    ----------
    E : float
        Young's modulus (Pa).
    nu : float
        Poisson's ratio.
    density : float
        Density (kg/m^3).
    """

    E: float
    nu: float
    density: float

    @property
    def G(self) -> float:
        """Shear modulus (Pa)."""
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def c_s(self) -> float:
        """Shear wave speed ``sqrt(G / rho)`` (m/s)."""
        return float(np.sqrt(self.G / self.density))

    @property
    def c_p(self) -> float:
        """Compression wave speed ``c_s sqrt(2 (1 - nu) / (1 - 2 nu))`` (m/s; inf at 0.5)."""
        if self.nu >= 0.5:
            return float("inf")
        return self.c_s * float(np.sqrt(2.0 * (1.0 - self.nu) / (1.0 - 2.0 * self.nu)))

    @property
    def c_p_boundary(self) -> float:
        """The compression speed the boundary and the domain size use (m/s):
        ``min(c_p, C_P_CAP c_s)``. A nearly incompressible soil's P wave is (infinitely)
        fast but carries little of a surface source's energy (Miller & Pursey 1955: the
        Rayleigh and S waves carry the rest), so its dashpot and its round trip are capped
        at that of nu = 0.467; the static springs still hold the boundary."""
        return min(self.c_p, C_P_CAP * self.c_s)


@dataclass(frozen=True)
class DynamicSystem:
    """The assembled dynamic problem. SI units.

    ``static`` holds the stiffness (COO triplets of ``K / scale`` and the dof maps, see
    :class:`ssw.contact.assembly.System`); ``M``, ``C`` and ``Kb`` are scipy CSR matrices
    (kg, N s/m, N/m) on the same dofs (zero rows at pressure dofs). ``soil`` and ``plate``
    are the materials; ``boundary`` names the truncation boundary.

    Parameters
    ----------
    static : System
        The stiffness (COO triplets of ``K / scale``) and the dof maps.
    M : scipy.sparse.csr_matrix
        Mass matrix (kg).
    C : scipy.sparse.csr_matrix
        Dashpot matrix of the boundary (N s/m).
    Kb : scipy.sparse.csr_matrix
        Spring matrix of the boundary (N/m).
    soil : Material
        The soil.
    plate : Material or None
        The plate, or None.
    boundary : str
        The truncation boundary: ``absorbing`` or ``fixed``.
    mesh : Mesh
        The mesh (m).
    """

    static: System
    M: Any
    C: Any
    Kb: Any
    soil: Material
    plate: Material | None
    boundary: str
    mesh: Mesh

    @property
    def ndof(self) -> int:
        """Number of free degrees of freedom."""
        return self.static.ndof

    @property
    def scale(self) -> float:
        """Stiffness scale of the static operators (N/m)."""
        return self.static.scale

    def stiffness_triplets(self, mass_factor: float = 0.0, damping_factor: float = 0.0
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """COO triplets of ``(K + Kb + mass_factor M + damping_factor C) / scale``.

        Parameters
        ----------
        mass_factor : float
            Factor of ``M`` (1/s^2).
        damping_factor : float
            Factor of ``C`` (1/s).

        Returns
        -------
        rows : numpy.ndarray
            Row indices.
        cols : numpy.ndarray
            Column indices.
        vals : numpy.ndarray
            Values (dimensionless, scaled).
        """
        extra = (self.Kb + mass_factor * self.M + damping_factor * self.C).tocoo()
        s = self.static
        return (np.concatenate([s.rows, extra.row]), np.concatenate([s.cols, extra.col]),
                np.concatenate([s.vals, extra.data / s.scale]))

    @functools.cached_property
    def K(self) -> Any:
        """``K + Kb`` as a scipy CSR matrix (N/m; pressure columns in scaled units)."""
        from scipy.sparse import coo_matrix

        s = self.static
        k = coo_matrix((s.vals * s.scale, (s.rows, s.cols)), shape=(s.ndof, s.ndof))
        return (k.tocsr() + self.Kb).tocsr()

    def energy(self, u: np.ndarray, v: np.ndarray) -> tuple[float, float]:
        """Kinetic ``v M v / 2`` and strain ``u (K + Kb) u / 2`` energies (J).

        Parameters
        ----------
        u : numpy.ndarray
            Displacements (m), (ndof,).
        v : numpy.ndarray
            Velocities (m/s), (ndof,).

        Returns
        -------
        kinetic : float
            Kinetic energy (J).
        strain : float
            Strain energy (J).
        """
        return (0.5 * float(np.einsum("i,i->", v, self.M @ v)),
                0.5 * float(np.einsum("i,i->", u, self.K @ u)))


def without_mass(system: DynamicSystem, dofs: np.ndarray) -> DynamicSystem:
    """The system with the rows and columns of ``M`` at ``dofs`` removed (zeroed).

    The mass redistribution of Khenous, Laborde & Renard (2008) for dynamic contact: with
    the contact dofs massless, a node entering contact does not impact (no velocity jump
    to propagate), the trapezoidal rule stays stable and its energy balance exact, and
    the contact stress is a smooth function of time. The mass removed, that of the
    contact candidates' surface layer (elements of ``~0.1 r`` at radius ``r``), is
    ``O(h)`` of the participating mass and vanishes with mesh refinement.

    Parameters
    ----------
    system : DynamicSystem
        The operators.
    dofs : numpy.ndarray
        The contact dofs.

    Returns
    -------
    DynamicSystem
        The system with those rows and columns of ``M`` zeroed.

    References
    ----------
    Khenous, H. B., Laborde, P. & Renard, Y. (2008). Mass redistribution method for
    finite element contact problems in elastodynamics. Eur. J. Mech. A/Solids 27, 918-932.
    """
    from dataclasses import replace

    from scipy.sparse import diags

    keep = np.ones(system.ndof)
    keep[np.asarray(dofs, np.int64)] = 0.0
    D = diags(keep)
    return replace(system, M=(D @ system.M @ D).tocsr())


def mass_matrices(xy: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """(ne, 6, 6) scalar P2 mass ``int rho N_a N_b 2 pi r dA`` of straight-sided triangles.

    Parameters
    ----------
    xy : numpy.ndarray
        (ne, 6, 2) node coordinates (r, z), m.
    rho : numpy.ndarray
        (ne,) density, kg/m^3.

    Returns
    -------
    numpy.ndarray
        Element mass matrices (kg), (ne, 6, 6).
    """
    n, _ = p2_shape(MASS_POINTS)
    det = triangle_jacobian(xy)[1]
    r = np.einsum("qa,ea->eq", n, xy[:, :, 0])
    w = 2.0 * np.pi * r * MASS_WEIGHTS[None, :] * np.abs(det)[:, None] * rho[:, None]
    return np.einsum("qa,qb,eq->eab", n, n, w)


def _edges(tri: np.ndarray) -> np.ndarray:
    """(3 ne, 3) P2 edges (vertex, vertex, midside) of every element."""
    return np.concatenate([tri[:, [0, 1, 3]], tri[:, [1, 2, 4]], tri[:, [2, 0, 5]]])


def boundary_matrices(
    nodes: np.ndarray, tri: np.ndarray, body: np.ndarray, udof: np.ndarray, ndof: int,
    L_r: float, L_z: float, soil: Material,
) -> tuple[Any, Any]:
    """Dashpot ``C`` (N s/m) and spring ``Kb`` (N/m) matrices of the absorbing boundary.

    Consistent boundary matrices ``int N_a N_b k 2 pi r ds`` over the soil's faces
    ``r = L_r`` and ``z = -L_z`` (4-point Gauss along each quadratic edge), normal and
    tangential components as in the module docstring.

    Parameters
    ----------
    nodes : numpy.ndarray
        Node coordinates (r, z) (m), (n_nodes, 2).
    tri : numpy.ndarray
        Quadratic triangles, (n_el, 6).
    body : numpy.ndarray
        Body of each element (0: soil).
    udof : numpy.ndarray
        Dof number of each node's components (negative: fixed), (n_nodes, 2).
    ndof : int
        Number of dofs.
    L_r : float
        Radius of the domain (m).
    L_z : float
        Depth of the domain (m).
    soil : Material
        The soil (Pa, -, kg/m^3).

    Returns
    -------
    C : scipy.sparse.csr_matrix
        Dashpot matrix (N s/m).
    Kb : scipy.sparse.csr_matrix
        Spring matrix (N/m).

    References
    ----------
    Lysmer, J. and Kuhlemeyer, R. L. (1969). Finite dynamic model for infinite media.
    *J. Eng. Mech. Div.* 95(EM4), 859-877.
    """
    from scipy.sparse import coo_matrix

    tol = 1e-9 * max(L_r, L_z)
    e = _edges(tri[body == 0])
    p = nodes[e]  # (n, 3, 2)
    lateral = np.all(np.abs(p[:, :, 0] - L_r) < tol, axis=1)
    bottom = np.all(np.abs(p[:, :, 1] + L_z) < tol, axis=1)
    s, gw = np.polynomial.legendre.leggauss(4)
    s, gw = 0.5 * (s + 1.0), 0.5 * gw
    shape = np.stack([(1 - s) * (1 - 2 * s), s * (2 * s - 1), 4 * s * (1 - s)], axis=1)
    rows, cols, cv, kv = [], [], [], []
    G, rho = soil.G, soil.density
    for sel, normal in ((lateral, 0), (bottom, 1)):
        es = e[sel]
        if len(es) == 0:
            continue
        a, b = nodes[es[:, 0]], nodes[es[:, 1]]
        length = np.hypot(*(b - a).T)
        x = a[:, None, :] * (1 - s)[None, :, None] + b[:, None, :] * s[None, :, None]
        R = np.hypot(x[..., 0], x[..., 1])
        w = gw[None, :] * 2.0 * np.pi * x[..., 0] * length[:, None]  # (n, q)
        for comp in (0, 1):
            is_n = comp == normal
            c = rho * (soil.c_p_boundary if is_n else soil.c_s)
            alpha = ALPHA_N if is_n else ALPHA_T
            mc = np.einsum("qa,qb,eq->eab", shape, shape, w * c)
            mk = np.einsum("qa,qb,eq->eab", shape, shape, w * alpha * G / R)
            d = udof[es, comp]
            rows.append(np.repeat(d, 3, axis=1).ravel())
            cols.append(np.tile(d, (1, 3)).ravel())
            cv.append(mc.ravel())
            kv.append(mk.ravel())
    if not rows:
        z = coo_matrix((ndof, ndof)).tocsr()
        return z, z
    r_, c_ = np.concatenate(rows), np.concatenate(cols)
    keep = (r_ >= 0) & (c_ >= 0)
    C = coo_matrix((np.concatenate(cv)[keep], (r_[keep], c_[keep])), shape=(ndof, ndof))
    K = coo_matrix((np.concatenate(kv)[keep], (r_[keep], c_[keep])), shape=(ndof, ndof))
    return C.tocsr(), K.tocsr()


def assemble_dynamic(
    mesh: Mesh, soil: Material, plate: Material | None, interface: str, boundary: str,
    order_nodes,
) -> DynamicSystem:
    """Assemble stiffness, mass and boundary operators of soil (body 0) and plate (body 1).

    Parameters
    ----------
    mesh : ssw.contact.mesh.Mesh
        The section mesh (:func:`ssw.contact.mesh.build_mesh`).
    soil : Material
        The soil's material.
    plate : Material or None
        The plate's material (None without a plate).
    interface : str
        ``bonded`` | ``frictionless`` (the plate-soil interface; ``unilateral`` would
        need the interface's separation in every step's LCP: not supported).
    boundary : str
        ``absorbing`` (free faces with dashpots and springs) | ``fixed`` (rollers and a
        fixed bottom, as the quasi-static FEM).
    order_nodes : callable
        ``(rows, cols, n) -> permutation`` (nested dissection).

    Returns
    -------
    DynamicSystem
        The assembled operators.
    """
    if boundary not in BOUNDARIES:
        raise ConfigError("dynamics.boundary", boundary, " | ".join(BOUNDARIES))
    if interface not in ("bonded", "frictionless"):
        raise ConfigError("plate.interface", interface,
                          "bonded | frictionless for the dynamic wall")
    pl = plate if plate is not None else soil
    # a free truncation boundary: number the dofs as if the fixed faces lay twice as far
    static = assemble(mesh, (soil.E, pl.E), (soil.nu, pl.nu), interface, order_nodes,
                      fixed_faces=1.0 if boundary == "fixed" else 2.0)
    nodes, tri, udof, ndof = static.nodes, static.tri, static.udof, static.ndof
    rho = np.array([soil.density, pl.density])[static.body]

    from scipy.sparse import coo_matrix

    me = mass_matrices(nodes[tri], rho)
    mr, mc, mv = [], [], []
    for comp in (0, 1):
        d = udof[tri, comp]
        mr.append(np.repeat(d, 6, axis=1).ravel())
        mc.append(np.tile(d, (1, 6)).ravel())
        mv.append(me.ravel())
    mr_, mc_, mv_ = np.concatenate(mr), np.concatenate(mc), np.concatenate(mv)
    ok = (mr_ >= 0) & (mc_ >= 0)
    M = coo_matrix((mv_[ok], (mr_[ok], mc_[ok])), shape=(ndof, ndof)).tocsr()
    if boundary == "absorbing":
        C, Kb = boundary_matrices(nodes, tri, mesh.body, udof, ndof, mesh.soil_radius,
                                  mesh.soil_depth, soil)
    else:
        C = Kb = coo_matrix((ndof, ndof)).tocsr()
    return DynamicSystem(static, M, C, Kb, soil, plate, boundary, mesh)
