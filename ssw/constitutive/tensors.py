"""Axisymmetric stress and strain in Mandel notation, their invariants, and the consistent
tangent of an isotropic return mapping written in the invariants (p, q).

Vectors. A symmetric tensor of the axisymmetric (r, z) section has the components rr, zz,
tt (hoop) and rz; it is stored as the Mandel 4-vector ``(a_rr, a_zz, a_tt, sqrt(2) a_rz)``,
so that the double contraction is the dot product (``sigma : eps = sigma . eps``) and the
fourth-order tensors (elasticity, projectors, tangents) are symmetric 4 x 4 matrices
(Mandel 1965; de Souza Neto, Peric & Owen 2008, app. D). ``ONE`` is the identity, ``P_DEV``
the deviatoric projector ``I - ONE ONE^T / 3``.

Invariants. ``p = tr(sigma) / 3`` (mean stress, tension positive), ``s = P_DEV sigma``,
``q = sqrt(3/2) |s|`` (von Mises equivalent stress), ``n = s / |s|`` (the unit deviatoric
direction; 0 where ``s = 0``), so ``sigma = p ONE + sqrt(2/3) q n``.

Tangent of a p-q return mapping. Every model of :mod:`ssw.constitutive` is isotropic and
its return keeps the deviatoric direction of the elastic trial (a radial return in the
deviatoric plane): the result is ``sigma = p ONE + sqrt(2/3) q n_tr`` with ``(p, q)``
functions of the trial invariants ``(p_tr, q_tr)`` (and the state). With
``d p_tr / d eps = K ONE``, ``d q_tr / d eps = sqrt(6) G n_tr`` and
``d n_tr / d eps = (2 G / |s_tr|) (P_DEV - n n^T)``, the consistent tangent is

    D = ONE (J_pp K ONE + J_pq sqrt(6) G n)^T + sqrt(2/3) n (J_qp K ONE + J_qq sqrt(6) G n)^T
        + 2 G (q / q_tr) (P_DEV - n n^T),

``J = d(p, q) / d(p_tr, q_tr)`` (Simo & Taylor 1985 for von Mises; de Souza Neto et al.
2008, sec. 7.4 and 8.3, for the general form). With ``J = I`` it is the elastic
``K ONE ONE^T + 2 G P_DEV``.

References
----------
de Souza Neto, E. A., Peric, D. & Owen, D. R. J. (2008). *Computational Methods for
Plasticity*. Wiley.
Simo, J. C. & Taylor, R. L. (1985). Consistent tangent operators for rate-independent
elastoplasticity. *Comput. Methods Appl. Mech. Eng.* 48, 101-118.
"""

from __future__ import annotations

import numpy as np

from ssw.errors import ConfigError

SQRT2 = float(np.sqrt(2.0))
SQRT_2_3 = float(np.sqrt(2.0 / 3.0))
SQRT_3_2 = float(np.sqrt(1.5))
SQRT6 = float(np.sqrt(6.0))
#: Identity (Mandel vector).
ONE = np.array([1.0, 1.0, 1.0, 0.0])
#: Deviatoric projector (Mandel matrix).
P_DEV = np.eye(4) - np.outer(ONE, ONE) / 3.0


def bulk_shear(E: float, nu: float) -> tuple[float, float]:
    """Bulk and shear moduli (Pa) of Young's modulus ``E`` (Pa) and Poisson's ratio ``nu``
    in (-1, 0.5): ``K = E / (3 (1 - 2 nu))``, ``G = E / (2 (1 + nu))``.

    Parameters
    ----------
    E : float
        Young's modulus (Pa), > 0.
    nu : float
        Poisson's ratio, in (-1, 0.5).

    Returns
    -------
    tuple of float
        ``(K, G)`` (Pa).

    Raises
    ------
    ConfigError
        If ``E`` is not > 0 or ``nu`` lies outside (-1, 0.5).
    """
    E, nu = float(E), float(nu)
    if not E > 0:
        raise ConfigError("soil_E", E, "a Young's modulus > 0 Pa")
    if not -1.0 < nu < 0.5:
        raise ConfigError("soil_nu", nu, "a Poisson's ratio in (-1, 0.5) for a plastic model "
                          "(0.5: use 0.499, the elastic volume change then stays finite)")
    return E / (3.0 * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))


def elastic_tangent(K: float, G: float) -> np.ndarray:
    """Isotropic elasticity ``K ONE ONE^T + 2 G P_DEV`` (4, 4), Pa.

    Parameters
    ----------
    K : float
        Bulk modulus (Pa).
    G : float
        Shear modulus (Pa).

    Returns
    -------
    numpy.ndarray
        Elasticity matrix (Mandel, Pa), (4, 4).
    """
    return K * np.outer(ONE, ONE) + 2.0 * G * P_DEV


def trial(E: float, nu: float, strain: np.ndarray, plastic_strain: np.ndarray
          ) -> tuple[float, float, np.ndarray, np.ndarray, np.ndarray]:
    """The elastic trial of a strain (n, 4) from the plastic strain (n, 4):
    ``(K, G, p_tr (n,), q_tr (n,), n_tr (n, 4))``.

    Parameters
    ----------
    E : float
        Young's modulus (Pa), > 0.
    nu : float
        Poisson's ratio, in (-1, 0.5).
    strain : numpy.ndarray
        Total strains (Mandel), (n, 4).
    plastic_strain : numpy.ndarray
        Plastic strains (Mandel), (n, 4).

    Returns
    -------
    tuple
        ``(K, G, p_tr, q_tr, n_tr)``: moduli (Pa), trial invariants (Pa), (n,), unit
        deviatoric direction, (n, 4).

    Raises
    ------
    ConfigError
        If ``E`` is not > 0 or ``nu`` lies outside (-1, 0.5).
    """
    K, G = bulk_shear(E, nu)
    ee = np.asarray(strain, float) - np.asarray(plastic_strain, float)
    p_tr = K * (ee @ ONE)
    q_tr, n_tr = deviator(2.0 * G * (ee @ P_DEV))
    return K, G, p_tr, q_tr, n_tr


def deviator(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``q = sqrt(3/2) |s|`` (n,) and the unit direction ``n = s / |s|`` (n, 4), 0 where
    ``s = 0``, of deviatoric vectors ``s`` (n, 4).

    Parameters
    ----------
    s : numpy.ndarray
        Deviatoric vectors (Mandel), (n, 4).

    Returns
    -------
    q : numpy.ndarray
        Equivalent value ``sqrt(3/2) |s|`` (the unit of ``s``), (n,).
    n : numpy.ndarray
        Unit directions, (n, 4).
    """
    norm = np.sqrt(np.einsum("ni,ni->n", s, s))
    with np.errstate(invalid="ignore", divide="ignore"):
        n = np.where(norm[:, None] > 0, s / norm[:, None], 0.0)
    return SQRT_3_2 * norm, n


def invariants(stress: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean stress ``p`` (n,) and von Mises stress ``q`` (n,) of stresses (n, 4), Pa.

    Parameters
    ----------
    stress : numpy.ndarray
        Stresses (Mandel, Pa), (n, 4).

    Returns
    -------
    p : numpy.ndarray
        Mean stress (Pa, tension positive), (n,).
    q : numpy.ndarray
        Von Mises stress (Pa), (n,).
    """
    stress = np.asarray(stress, float)
    q, _ = deviator(stress @ P_DEV)
    return stress @ ONE / 3.0, q


def stress_of(p: np.ndarray, q: np.ndarray, n: np.ndarray) -> np.ndarray:
    """``sigma = p ONE + sqrt(2/3) q n`` (n, 4).

    Parameters
    ----------
    p : numpy.ndarray
        Mean stresses (Pa), (n,).
    q : numpy.ndarray
        Von Mises stresses (Pa), (n,).
    n : numpy.ndarray
        Unit deviatoric directions, (n, 4).

    Returns
    -------
    numpy.ndarray
        Stresses (Mandel, Pa), (n, 4).
    """
    return p[:, None] * ONE + SQRT_2_3 * q[:, None] * n


def pq_tangent(K: float, G: float, n: np.ndarray, J: np.ndarray, ratio: np.ndarray
               ) -> np.ndarray:
    """Consistent tangent (n, 4, 4), Pa, of a p-q return (module docstring).

    Parameters
    ----------
    K : float
        Bulk modulus, Pa.
    G : float
        Shear modulus, Pa.
    n : numpy.ndarray
        (n, 4) unit deviatoric direction of the trial.
    J : numpy.ndarray
        (n, 2, 2) ``[[dp/dp_tr, dp/dq_tr], [dq/dp_tr, dq/dq_tr]]``.
    ratio : numpy.ndarray
        (n,) ``q / q_tr`` (the shrink of the deviator; 1 where elastic).

    Returns
    -------
    numpy.ndarray
        Consistent tangent (Pa), (n, 4, 4).
    """
    # where the return left the trial alone (J = I, ratio = 1) the formula is the elastic
    # tangent K ONE ONE^T + 2 G P_DEV (sqrt(2/3) sqrt(6) = 2): evaluate it elsewhere only
    D = np.repeat(elastic_tangent(K, G)[None], n.shape[0], axis=0)
    pl = np.flatnonzero((ratio != 1.0) | (J[:, 0, 0] != 1.0) | (J[:, 0, 1] != 0.0)
                        | (J[:, 1, 0] != 0.0) | (J[:, 1, 1] != 1.0))
    if pl.size:
        n, J, r = n[pl], J[pl], ratio[pl]
        dp = J[:, 0, 0, None] * K * ONE + J[:, 0, 1, None] * SQRT6 * G * n  # d p / d eps
        dq = J[:, 1, 0, None] * K * ONE + J[:, 1, 1, None] * SQRT6 * G * n  # d q / d eps
        nn = n[:, :, None] * n[:, None, :]
        D[pl] = (ONE[None, :, None] * dp[:, None, :] + SQRT_2_3 * n[:, :, None] * dq[:, None, :]
                 + 2.0 * G * r[:, None, None] * (P_DEV[None] - nn))
    return D


def equivalent_plastic_work(stress: np.ndarray, dplastic: np.ndarray) -> np.ndarray:
    """Plastic work density ``sigma : d eps_p`` (n,), J/m^3.

    Parameters
    ----------
    stress : numpy.ndarray
        Stresses (Mandel, Pa), (n, 4).
    dplastic : numpy.ndarray
        Plastic strain increments (Mandel), (n, 4).

    Returns
    -------
    numpy.ndarray
        Plastic work density (J/m^3), (n,).
    """
    return np.einsum("ni,ni->n", stress, dplastic)
