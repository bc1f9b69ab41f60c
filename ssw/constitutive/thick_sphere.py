"""A thick hollow sphere under inner pressure, solved with a constitutive model's return
mapping: the radial (1-D) finite-element check of the models against Hill's solution.

The sphere ``a <= r <= b`` deforms radially, ``u(r)``: the strains are ``e_rr = du/dr`` and
``e_tt = e_pp = u / r``, stored in the axisymmetric Mandel vector of
:mod:`ssw.constitutive.tensors` as ``(e_rr, e_tt, e_tt, 0)`` (the model is isotropic, so
which slot holds which tangential direction does not matter). Quadratic elements, 3 Gauss
points, the volume ``4 pi r^2 dr``; the inner radius is driven (``u(a)`` prescribed), the
outer face is free; each increment is solved by Newton's method with the model's consistent
tangent, and the inner pressure is the reaction, ``p = f_int(a) / (4 pi a^2)``.

Hill (1950, ch. V.2) for a perfectly plastic von Mises (= Tresca here) sphere: yield starts
at the inner face at ``p = (2Y/3)(1 - a^3/b^3)``; with the plastic zone reaching ``c``,
``p = 2Y ln(c/a) + (2Y/3)(1 - c^3/b^3)``; collapse at ``p = 2Y ln(b/a)``.

References
----------
Hill, R. (1950). *The Mathematical Theory of Plasticity*. Oxford, ch. V.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.constitutive.base import initial_state
from ssw.errors import SolverError

_GP, _GW = np.polynomial.legendre.leggauss(3)


@dataclass(frozen=True)
class SpherePath:
    """The result of a driven path: per increment the inner displacement ``u_a`` (m), the
    inner pressure ``p`` (Pa), the largest yield ratio; and per increment and Gauss point
    (``r_gauss``, m) whether it yielded (``plastic``), and the Newton iterations used.

    Parameters
    ----------
    u_a : numpy.ndarray
        Inner displacement per increment (m).
    p : numpy.ndarray
        Inner pressure per increment (Pa).
    yield_ratio : numpy.ndarray
        Largest yield ratio per increment.
    r_gauss : numpy.ndarray
        Gauss point radii (m).
    plastic : numpy.ndarray
        Whether each Gauss point yielded, per increment.
    iterations : numpy.ndarray
        Newton iterations per increment.
    """

    u_a: np.ndarray
    p: np.ndarray
    yield_ratio: np.ndarray
    r_gauss: np.ndarray
    plastic: np.ndarray
    iterations: np.ndarray


def hill_pressure(c: np.ndarray, a: float, b: float, Y: float) -> np.ndarray:
    """Inner pressure (Pa) of Hill's elastic-plastic sphere with the plastic front at ``c``
    (``a <= c <= b``): ``2Y ln(c/a) + (2Y/3)(1 - c^3/b^3)``.

    Parameters
    ----------
    c : numpy.ndarray
        Radius of the plastic front (m).
    a : float
        Inner radius (m).
    b : float
        Outer radius (m).
    Y : float
        Yield stress (Pa).

    Returns
    -------
    numpy.ndarray
        Inner pressure (Pa), the shape of ``c``.

    References
    ----------
    Hill, R. (1950). *The Mathematical Theory of Plasticity*, Oxford, ch. V.
    """
    c = np.asarray(c, float)
    return 2.0 * Y * np.log(c / a) + (2.0 * Y / 3.0) * (1.0 - (c / b) ** 3)


def solve_sphere(model, E: float, nu: float, a: float, b: float, u_a: np.ndarray,
                 elements: int = 200, tol: float = 1e-10, max_iter: int = 30) -> SpherePath:
    """Drive the inner radius through ``u_a`` (m, increments) and return the path.

    Raises SolverError when an increment's Newton iteration does not converge (residual
    below ``tol`` times the reaction's scale within ``max_iter`` iterations).

    Parameters
    ----------
    model : Any
        The constitutive model (:mod:`ssw.constitutive`).
    E : float
        Young's modulus (Pa), > 0.
    nu : float
        Poisson's ratio, in (-1, 0.5).
    a : float
        Inner radius (m).
    b : float
        Outer radius (m).
    u_a : numpy.ndarray
        Inner radial displacements (m), one per increment, in order.
    elements : int
        Number of radial elements.
    tol : float
        Relative tolerance of the Newton residual.
    max_iter : int
        Most Newton iterations per increment.

    Returns
    -------
    SpherePath
        The path: pressures (Pa), yield ratios, Gauss radii (m), plastic flags and iterations.

    Raises
    ------
    SolverError
        If an increment's Newton iteration does not converge.
    """
    ne = int(elements)
    xv = np.linspace(a, b, ne + 1)
    nodes = np.empty(2 * ne + 1)
    nodes[0::2], nodes[1::2] = xv, 0.5 * (xv[:-1] + xv[1:])
    conn = np.stack([2 * np.arange(ne), 2 * np.arange(ne) + 1, 2 * np.arange(ne) + 2], 1)
    s = 0.5 * (_GP + 1.0)
    N = np.stack([2 * (s - 0.5) * (s - 1), -4 * s * (s - 1), 2 * s * (s - 0.5)], 1)  # (3q, 3)
    dN = np.stack([4 * s - 3, -8 * s + 4, 4 * s - 1], 1)
    h = xv[1:] - xv[:-1]
    r = xv[:-1, None] + s[None, :] * h[:, None]  # (ne, nq)
    w = (4.0 * np.pi * r ** 2 * 0.5 * _GW[None, :] * h[:, None]).ravel()
    B = np.zeros((ne, 3, 4, 3))
    B[:, :, 0, :] = dN[None] / h[:, None, None]
    B[:, :, 1, :] = N[None] / r[:, :, None]
    B[:, :, 2, :] = N[None] / r[:, :, None]
    B = B.reshape(ne * 3, 4, 3)
    dofs = np.repeat(conn, 3, axis=0)  # (ne*nq, 3)
    ndof = nodes.size
    state = initial_state(ne * 3)
    u = np.zeros(ndof)
    out_p, out_y, out_pl, out_it = [], [], [], []
    scale = None
    for ua in np.asarray(u_a, float):
        u[0] = ua
        for it in range(max_iter):
            strain = np.einsum("gij,gj->gi", B, u[dofs])
            upd = model.update(E, nu, strain, state)
            fe = np.einsum("gij,gi,g->gj", B, upd.stress, w)
            f = np.zeros(ndof)
            np.add.at(f, dofs, fe)
            if scale is None:
                scale = E * a * a
            res = np.abs(f[1:]).max()
            if res <= tol * scale * max(abs(ua) / a, 1e-30) and it > 0:
                break
            ke = np.einsum("gki,gkl,glj,g->gij", B, upd.tangent, B, w)
            Kd = np.zeros((ndof, ndof))
            np.add.at(Kd, (dofs[:, :, None], dofs[:, None, :]), ke)
            du = np.linalg.solve(Kd[1:, 1:], -f[1:])  # banded, small: dense is fine
            u[1:] += du
        else:
            raise SolverError(f"thick sphere: Newton did not converge at u_a = {ua:.4g} m "
                              f"(residual {res:.3g} N)")
        state = upd.state
        out_p.append(f[0] / (4.0 * np.pi * a * a))
        out_y.append(float(np.max(model.yield_ratio(upd.stress, state))))
        out_pl.append(upd.plastic.copy())
        out_it.append(it)
    return SpherePath(np.asarray(u_a, float), np.array(out_p), np.array(out_y), r.ravel(),
                      np.array(out_pl), np.array(out_it))
