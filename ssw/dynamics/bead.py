"""The bead's own elastic compliance on the contact candidates (a half-space, as in Hertz).

The FEM models the indenter as rigid; the chain's bead is steel. As Hertz theory does for
both bodies, the bead's surface near the contact deforms like an elastic half-space of
compliance ``c_b = (1 - nu_b^2) / E_b`` under the contact pressure. The nodal contact force
``lam_j`` of candidate ``j`` (radius ``r_j``) is spread uniformly over its tributary
annulus ``[b_j, b_(j+1)]`` (midpoints between candidates; ``b_0 = 0``), and the bead's
surface displacement at ``r_i`` is the closed-form one of a uniformly loaded disk,
differenced over the annulus (Johnson 1985, sec. 3.4, eq. 3.38; Timoshenko & Goodier):

    w(r; a) = 4 c_b p / pi * a E(r^2/a^2)                          (r <= a)
    w(r; a) = 4 c_b p / pi * r [E(a^2/r^2) - (1 - a^2/r^2) K(a^2/r^2)]   (r > a)

(``K``, ``E`` complete elliptic integrals of parameter ``m``), averaged over the annulus of
candidate ``i`` (the displacement work-conjugate to ``lam_i``; Gauss-Legendre in ``r``), so
that the matrix is symmetric (Betti's reciprocity) up to the quadrature's round-off, which
is symmetrized away. The compliances add to the
condensed FEM compliance in the contact LCP, ``g = g0 + (W_fem + W_bead) lam``: the bead's
deformation is a state function of the contact forces (its energy ``lam W_bead lam / 2``),
so the energy balance of a dynamic run stays exact. For a Hertzian pressure this is Hertz's
``1/E* = c_w + c_b``; for a plate's pressure it is the same half-space model of the bead,
where :func:`ssw.chain.wall_base.compliance_scale` rescales the indentation instead.

References
----------
Johnson, K. L. (1985). Contact Mechanics. Cambridge University Press.
"""

from __future__ import annotations

import numpy as np

#: Gauss points per annulus for the averaged displacement.
QUAD_POINTS = 8


def _disk(r: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``pi w / (4 c_b p)`` at radius ``r`` under a uniform pressure on a disk of radius ``a``."""
    from scipy.special import ellipe, ellipk

    r, a = np.broadcast_arrays(np.asarray(r, float), np.asarray(a, float))
    out = np.zeros(r.shape)
    inside = (r <= a) & (a > 0)
    out[inside] = a[inside] * ellipe((r[inside] / a[inside]) ** 2)
    outside = (r > a) & (a > 0)
    m = (a[outside] / r[outside]) ** 2
    out[outside] = r[outside] * (ellipe(m) - (1.0 - m) * ellipk(m))
    return out


def tributary_edges(r: np.ndarray) -> np.ndarray:
    """(m + 1,) annulus edges of candidates at radii ``r`` (sorted, ``r[0] >= 0``), m.

    Parameters
    ----------
    r : numpy.ndarray
        Candidate radii (m), sorted, ``r[0] >= 0``, (m,).

    Returns
    -------
    numpy.ndarray
        Annulus edges (m), (m + 1,), from 0.
    """
    r = np.asarray(r, float)
    mid = 0.5 * (r[1:] + r[:-1])
    last = r[-1] + 0.5 * (r[-1] - r[-2]) if r.size > 1 else 2.0 * r[-1]
    return np.concatenate([[0.0], mid, [last]])


def bead_compliance(r: np.ndarray, E_b: float, nu_b: float) -> np.ndarray:
    """(m, m) compliance (m/N): surface displacement of the bead at ``r_i`` per unit nodal
    force at candidate ``j`` (module docstring).

    Parameters
    ----------
    r : numpy.ndarray
        (m,) candidate radii, sorted, m.
    E_b : float
        The bead's Young's modulus, Pa.
    nu_b : float
        The bead's Poisson's ratio.

    Returns
    -------
    numpy.ndarray
        Symmetric compliance (m/N), (m, m).
    """
    c_b = (1.0 - nu_b**2) / E_b
    b = tributary_edges(r)
    area = np.pi * (b[1:] ** 2 - b[:-1] ** 2)
    s, gw = np.polynomial.legendre.leggauss(QUAD_POINTS)
    s, gw = 0.5 * (s + 1.0), 0.5 * gw
    rq = b[:-1, None] + (b[1:] - b[:-1])[:, None] * s[None, :]  # (m, q)
    wq = 2.0 * np.pi * rq * (b[1:] - b[:-1])[:, None] * gw[None, :] / area[:, None]
    rr = rq[:, :, None]
    w = _disk(rr, b[None, None, 1:]) - _disk(rr, b[None, None, :-1])  # (m_i, q, m_j)
    W = 4.0 * c_b / np.pi * np.einsum("iq,iqj->ij", wq, w) / area[None, :]
    return 0.5 * (W + W.T)
