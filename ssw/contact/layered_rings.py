"""Influence coefficients of ring loads on a layered half-space (the oracle's matrix).

A ring ``j`` is an annulus ``b_(j-1) <= r < b_j`` under uniform unit pressure; its
influence coefficient ``C_ij`` (m/Pa) is the surface deflection it causes at the
collocation radius ``r_i``. With the Hankel transform of the ring's pressure,
``p_bar_j(xi) = [b_j J1(xi b_j) - b_(j-1) J1(xi b_(j-1))] / xi``, and the kernel ratio
``A(xi)`` of :mod:`ssw.contact.layered_kernel`,

    ``C_ij = c_1 int_0^inf A(xi) p_bar_j(xi) J0(xi r_i) dxi``,  ``c_1 = 2 (1 - nu_1^2) / E_1``.

The integrand decays only like ``xi^(-2)`` and oscillates, so the large-``xi`` asymptote
``A = 1`` (the top material as a half-space) is subtracted and added back in closed form:
``C = C_hs + C_corr`` with

* ``C_hs``: uniform pressure on a disc of radius ``b`` on a half-space (Love 1929; Johnson
  1985, eqs. 3.38-3.39, ``k`` the elliptic modulus, ``K``, ``E`` complete elliptic integrals):
  ``u_z = (4 (1 - nu^2) / (pi E)) b E(r/b)`` for ``r <= b`` and
  ``(4 (1 - nu^2) / (pi E)) r [E(b/r) - (1 - b^2/r^2) K(b/r)]`` for ``r >= b``; a ring is
  the difference of two discs;
* ``C_corr = c_1 int_0^xi_max (A - 1) p_bar_j J0(xi r_i) dxi``, whose integrand decays like
  ``(xi h_1)^2 e^(-2 xi h_1)``: it is cut at ``xi_max = t_max / h_1`` (``t_max = 15``:
  ``e^-30``) and integrated by composite Gauss-Legendre (8 points a panel) on panels that
  double in ``xi`` (resolving the kernel's scales: the layer, the plate's bending length,
  the depth) and are no wider than ``1.5 pi / r_max`` (resolving the Bessel
  oscillations). Against ~30x the nodes (32 points, panels growing by 1.25 and
  half as wide, ``t_max = 30``) the contact forces agree to <= 2e-12 (``ssw bench
  layered``).

References
----------
Love, A. E. H. (1929). Phil. Trans. R. Soc. A 228, 377-420. Johnson, K. L. (1985).
*Contact Mechanics*, CUP, sec. 3.4. Sneddon, I. N. (1951). *Fourier Transforms*.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ssw.contact.layered_kernel import Stack, compliance_ratio
from ssw.errors import ConfigError


@dataclass(frozen=True)
class Quadrature:
    """Hankel quadrature of the correction integral.

    ``order`` Gauss-Legendre points per panel; panels grow geometrically by ``growth``
    from ``xi_low`` (relative to the stack's longest length scale) and are no wider than
    ``width`` (in units of ``pi / r_max``); the integral stops at ``xi_max = t_max / h_1``.

    Parameters
    ----------
    order : int
        Gauss-Legendre points per panel.
    growth : float
        Geometric growth of the panels.
    width : float
        Largest panel width in units of ``pi / r_max``.
    t_max : float
        Upper limit ``xi_max h_1``.
    xi_low : float
        Start of the geometric panels, relative to the stack's longest length.
    """

    order: int = 8
    growth: float = 2.0
    width: float = 1.5
    t_max: float = 15.0
    xi_low: float = 1e-4

    def __post_init__(self) -> None:
        checks = {"order": self.order >= 2, "growth": self.growth > 1.0,
                  "width": self.width > 0, "t_max": self.t_max > 0,
                  "xi_low": 0 < self.xi_low < 1}
        for name, ok in checks.items():
            if not ok:
                raise ConfigError(f"quadrature.{name}", getattr(self, name),
                                  "order >= 2, growth > 1, width > 0, t_max > 0, "
                                  "0 < xi_low < 1")


def graded_edges(r_max: float, ratio: float, width_min: float) -> NDArray[np.float64]:
    """Ring edges (m) from 0 to at least ``r_max``: each ring ``max(width_min, ratio * b)``
    wide, ``b`` its inner radius (uniform near the axis, geometric beyond
    ``width_min / ratio``), so a contact of radius ``a >= width_min / ratio`` has rings of
    relative width ``ratio`` at its edge.

    Parameters
    ----------
    r_max : float
        Radius to cover (m), > 0.
    ratio : float
        Relative ring width, in (0, 1).
    width_min : float
        Smallest ring width (m), in (0, r_max).

    Returns
    -------
    numpy.ndarray
        Ring edges (m), from 0.

    Raises
    ------
    ConfigError
        If an argument is out of range.
    """
    if not (r_max > 0 and 0 < ratio < 1 and 0 < width_min < r_max):
        raise ConfigError("rings", (r_max, ratio, width_min),
                          "r_max > 0, 0 < ratio < 1, 0 < width_min < r_max")
    b_switch = width_min / ratio
    n_uniform = int(np.ceil(min(b_switch, r_max) / width_min))
    edges = width_min * np.arange(n_uniform + 1)
    if edges[-1] < r_max:
        n_geo = int(np.ceil(np.log(r_max / edges[-1]) / np.log1p(ratio)))
        edges = np.concatenate([edges, edges[-1] * (1 + ratio) ** np.arange(1, n_geo + 1)])
    return edges


def disc_deflection(r: NDArray, b: NDArray, E: float, nu: float) -> NDArray[np.float64]:
    """Surface deflection (m) of a half-space (E Pa, nu) at radius ``r`` (m) under unit
    pressure (1 Pa) on a disc of radius ``b`` (m); broadcasts (Johnson 1985, eq. 3.38-3.39).

    Parameters
    ----------
    r : numpy.ndarray
        Radii (m).
    b : numpy.ndarray
        Disc radii (m).
    E : float
        Young's modulus (Pa).
    nu : float
        Poisson's ratio.

    Returns
    -------
    numpy.ndarray
        Deflection per unit pressure (m/Pa), the broadcast shape.

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, Cambridge University Press, eqs. (3.38)-(3.39).
    """
    from scipy.special import ellipe, ellipk

    r, b = np.broadcast_arrays(np.asarray(r, float), np.asarray(b, float))
    inside = r <= b
    safe_b = np.where(b > 0, b, 1.0)
    safe_r = np.where(r > 0, r, 1.0)
    m_in = np.where(inside, (r / safe_b) ** 2, 0.0)
    m_out = np.where(inside, 0.0, (b / safe_r) ** 2)
    w_in = b * ellipe(m_in)
    w_out = r * (ellipe(m_out) - (1.0 - m_out) * ellipk(m_out))
    return 4.0 * (1.0 - nu * nu) / (np.pi * E) * np.where(inside, w_in, w_out)


def halfspace_influence(points: NDArray, edges: NDArray, E: float,
                        nu: float) -> NDArray[np.float64]:
    """``C_hs`` (m/Pa), shape (n_points, n_rings): rings of ``edges`` on a half-space.

    Parameters
    ----------
    points : numpy.ndarray
        Collocation radii (m), (n_points,).
    edges : numpy.ndarray
        Ring edges (m), (n_rings + 1,).
    E : float
        Young's modulus (Pa).
    nu : float
        Poisson's ratio.

    Returns
    -------
    numpy.ndarray
        Influence coefficients (m/Pa), (n_points, n_rings).
    """
    disc = disc_deflection(points[:, None], edges[None, :], E, nu)
    return disc[:, 1:] - disc[:, :-1]


def hankel_nodes(stack: Stack, r_max: float,
                 quad: Quadrature) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Nodes ``xi`` (1/m) and weights of the correction integral over ``[0, xi_max]``.

    Parameters
    ----------
    stack : Stack
        The layered body.
    r_max : float
        Radius of the candidate zone (m).
    quad : Quadrature
        The quadrature settings.

    Returns
    -------
    xi : numpy.ndarray
        Nodes (1/m).
    w : numpy.ndarray
        Weights (1/m).

    Raises
    ------
    ConfigError
        If the lower limit is not below the upper one.
    """
    h1 = stack.layers[0].thickness
    E1 = stack.top[0]
    below = [lay.E for lay in stack.layers[1:]] + [stack.base_E]
    bending = max((E1 / E) ** (1.0 / 3.0) for E in below)  # plate bending length / h_1
    scale = max(stack.depth, r_max, h1 * bending)  # the longest length of the problem
    xi_lo, xi_max = quad.xi_low / scale, quad.t_max / h1
    if xi_lo >= xi_max:
        raise ConfigError("quadrature.xi_low", quad.xi_low, "a lower limit below t_max / h_1")
    n_geo = int(np.ceil(np.log(xi_max / xi_lo) / np.log(quad.growth)))
    breaks = np.concatenate([[0.0], np.geomspace(xi_lo, xi_max, n_geo + 1)])
    width = quad.width * np.pi / r_max
    parts = [np.linspace(a, b, int(np.ceil((b - a) / width)) + 1)[:-1]
             for a, b in itertools.pairwise(breaks)]
    breaks = np.concatenate([*parts, [xi_max]])
    x, w = np.polynomial.legendre.leggauss(quad.order)
    half = 0.5 * np.diff(breaks)
    mid = 0.5 * (breaks[1:] + breaks[:-1])
    xi = (mid[:, None] + half[:, None] * x[None, :]).ravel()
    wt = (half[:, None] * w[None, :]).ravel()
    return xi, wt


def influence_matrix(stack: Stack, points: NDArray, edges: NDArray,
                     quad: Quadrature | None = None) -> tuple[NDArray[np.float64], int]:
    """Influence coefficients ``C`` (m/Pa), shape (n_points, n_rings), and the number of
    Hankel nodes used (0 for a homogeneous half-space).

    ``points`` (m): collocation radii; ``edges`` (m, increasing from 0): ring edges.

    Parameters
    ----------
    stack : Stack
        The layered body.
    points : numpy.ndarray
        Collocation radii (m).
    edges : numpy.ndarray
        Ring edges (m), increasing from 0.
    quad : Quadrature or None
        The quadrature settings; None: the defaults.

    Returns
    -------
    C : numpy.ndarray
        Influence coefficients (m/Pa), (n_points, n_rings).
    n_xi : int
        Number of Hankel nodes.

    Raises
    ------
    ConfigError
        If the edges do not increase from 0.
    """
    from scipy.special import j0, j1

    points = np.asarray(points, float)
    edges = np.asarray(edges, float)
    if edges[0] != 0.0 or np.any(np.diff(edges) <= 0):
        raise ConfigError("edges", "not increasing from 0", "ring edges 0 = b_0 < b_1 < ...")
    E1, nu1 = stack.top
    C = halfspace_influence(points, edges, E1, nu1)
    if not stack.layers:
        return C, 0
    quad = quad or Quadrature()
    r_max = max(float(points.max()), float(edges[-1]))
    xi, wt = hankel_nodes(stack, r_max, quad)
    weight = wt * (compliance_ratio(stack, xi) - 1.0) * stack.top_compliance
    bJ1 = edges[None, :] * j1(xi[:, None] * edges[None, :])  # (n_xi, n_edges)
    pbar = (bJ1[:, 1:] - bJ1[:, :-1]) / xi[:, None]  # (n_xi, n_rings)
    C += (j0(points[:, None] * xi[None, :]) * weight[None, :]) @ pbar
    return C, xi.size
