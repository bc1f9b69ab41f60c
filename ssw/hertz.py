"""Hertz contact laws: sphere on half-space, sphere on sphere, and the exact sphere.

Equations (Johnson 1985, *Contact Mechanics*, ch. 4; Popov 2010, ch. 5; Sneddon 1965):

* effective modulus ``1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2`` (a rigid body: ``E = inf``);
* effective radius ``1/R* = 1/R1 + 1/R2`` (a flat: ``R = inf``);
* force ``F = 4/3 E* sqrt(R*) delta^(3/2)``; contact radius ``a = sqrt(R* delta)``;
* peak pressure ``p0 = 3 F / (2 pi a^2) = 2 E* a / (pi R*)``;
* stored energy ``U = (2/5) A delta^(5/2)``; the indentation at which ``U`` exceeds the work
  of a constant load ``P`` by ``W``, ``(2/5) A delta^(5/2) - P delta = W`` (an energy bound of
  the indentation an impact reaches);
* impact duration of two bodies of reduced mass ``m`` meeting at speed ``v`` under
  ``F = A delta^(3/2)``: ``t_c = 2.9432 (5 m / (4 A))^(2/5) v^(-1/5)`` (Johnson 1985, eq. 11.24);
* exact (non-paraboloidal) rigid sphere on an elastic half-space (Sneddon 1965):
  ``delta = (a/2) ln((R+a)/(R-a))``, ``F = (E*/2) [(a^2 + R^2) ln((R+a)/(R-a)) - 2 a R]``.

All functions take and return SI units and broadcast over numpy arrays.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ssw.errors import ConfigError
from ssw.roots import find_root


def _check_positive(name: str, value: ArrayLike) -> NDArray[np.float64]:
    arr = np.asarray(value, dtype=float)
    if not np.all(arr > 0):
        raise ConfigError(name, value, "must be > 0")
    return arr


def _check_nu(name: str, nu: ArrayLike) -> NDArray[np.float64]:
    arr = np.asarray(nu, dtype=float)
    if not np.all((arr > -1.0) & (arr <= 0.5)):
        raise ConfigError(name, nu, "Poisson's ratio must lie in (-1, 0.5]")
    return arr


def effective_modulus(
    E1: ArrayLike, nu1: ArrayLike, E2: ArrayLike = np.inf, nu2: ArrayLike = 0.0
) -> NDArray[np.float64]:
    """Contact modulus E* (Pa): ``1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2``; ``E2=inf`` is rigid.

    Parameters
    ----------
    E1 : array_like
        Young's modulus of the first body (Pa), > 0.
    nu1 : array_like
        Poisson's ratio of the first body, in (-1, 0.5].
    E2 : array_like
        Young's modulus of the second body (Pa), > 0; ``inf`` (the default) is rigid.
    nu2 : array_like
        Poisson's ratio of the second body, in (-1, 0.5].

    Returns
    -------
    ndarray
        Contact modulus ``E*`` (Pa).

    Raises
    ------
    ConfigError
        If a modulus is not > 0 or a Poisson's ratio lies outside (-1, 0.5].

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 4, section 4.2.
    """
    E1a, E2a = _check_positive("E1", E1), _check_positive("E2", E2)
    n1, n2 = _check_nu("nu1", nu1), _check_nu("nu2", nu2)
    return 1.0 / ((1.0 - n1**2) / E1a + (1.0 - n2**2) / E2a)


def effective_radius(R1: ArrayLike, R2: ArrayLike = np.inf) -> NDArray[np.float64]:
    """Effective radius R* (m): ``1/R* = 1/R1 + 1/R2``; ``R2=inf`` is a flat.

    Parameters
    ----------
    R1 : array_like
        Radius of curvature of the first body (m), > 0.
    R2 : array_like
        Radius of curvature of the second body (m), > 0; ``inf`` (the default) is a flat.

    Returns
    -------
    ndarray
        Effective radius ``R*`` (m).

    Raises
    ------
    ConfigError
        If a radius is not > 0.

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 4.
    """
    return 1.0 / (1.0 / _check_positive("R1", R1) + 1.0 / _check_positive("R2", R2))


def hertz_coefficient(E_star: ArrayLike, R_star: ArrayLike) -> NDArray[np.float64]:
    """``A`` of ``F = A delta^(3/2)``: ``A = 4/3 E* sqrt(R*)`` (N m^-3/2).

    Parameters
    ----------
    E_star : array_like
        Contact modulus ``E*`` (Pa).
    R_star : array_like
        Effective radius ``R*`` (m).

    Returns
    -------
    ndarray
        Coefficient ``A`` (N m^-3/2).

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 4, section 4.2.
    """
    return 4.0 / 3.0 * np.asarray(E_star, float) * np.sqrt(np.asarray(R_star, float))


def sphere_sphere_coefficient(E: ArrayLike, nu: ArrayLike, R: ArrayLike) -> NDArray[np.float64]:
    """``A`` for two identical spheres of radius R: ``A = E sqrt(2R) / (3 (1 - nu^2))``.

    Parameters
    ----------
    E : array_like
        Young's modulus of both spheres (Pa), > 0.
    nu : array_like
        Poisson's ratio of both spheres, in (-1, 0.5].
    R : array_like
        Radius of both spheres (m), > 0.

    Returns
    -------
    ndarray
        Coefficient ``A`` (N m^-3/2).

    Raises
    ------
    ConfigError
        If ``E`` or ``R`` is not > 0 or ``nu`` lies outside (-1, 0.5].

    References
    ----------
    Nesterenko, V. F. (2001). *Dynamics of Heterogeneous Materials*, ch. 1;
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 4.
    """
    return hertz_coefficient(effective_modulus(E, nu, E, nu), effective_radius(R, R))


def force(delta: ArrayLike, E_star: ArrayLike, R_star: ArrayLike) -> NDArray[np.float64]:
    """Hertz force (N) at approach ``delta`` (m); zero for ``delta <= 0`` (no tension).

    ``F = 4/3 E* sqrt(R*) delta^(3/2)``.

    Parameters
    ----------
    delta : array_like
        Approach (m); values <= 0 give no force.
    E_star : array_like
        Contact modulus ``E*`` (Pa).
    R_star : array_like
        Effective radius ``R*`` (m).

    Returns
    -------
    ndarray
        Contact force (N), >= 0.

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 4, section 4.2.
    """
    d = np.clip(np.asarray(delta, float), 0.0, None)
    return hertz_coefficient(E_star, R_star) * d**1.5


def indentation(F: ArrayLike, E_star: ArrayLike, R_star: ArrayLike) -> NDArray[np.float64]:
    """Approach ``delta`` (m) under force ``F`` (N), the inverse of :func:`force`.

    ``delta = (F / A)^(2/3)``, ``A = 4/3 E* sqrt(R*)``.

    Parameters
    ----------
    F : array_like
        Contact force (N); values <= 0 give no approach.
    E_star : array_like
        Contact modulus ``E*`` (Pa).
    R_star : array_like
        Effective radius ``R*`` (m).

    Returns
    -------
    ndarray
        Approach (m), >= 0.

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 4, section 4.2.
    """
    f = np.clip(np.asarray(F, float), 0.0, None)
    return (f / hertz_coefficient(E_star, R_star)) ** (2.0 / 3.0)


def contact_radius(delta: ArrayLike, R_star: ArrayLike) -> NDArray[np.float64]:
    """Contact radius ``a = sqrt(R* delta)`` (m).

    Parameters
    ----------
    delta : array_like
        Approach (m); values <= 0 give a zero radius.
    R_star : array_like
        Effective radius ``R*`` (m).

    Returns
    -------
    ndarray
        Contact radius ``a`` (m).

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 4, section 4.2.
    """
    return np.sqrt(np.clip(np.asarray(delta, float), 0.0, None) * np.asarray(R_star, float))


def peak_pressure(delta: ArrayLike, E_star: ArrayLike, R_star: ArrayLike) -> NDArray[np.float64]:
    """Peak contact pressure ``p0 = 2 E* a / (pi R*)`` (Pa).

    Parameters
    ----------
    delta : array_like
        Approach (m).
    E_star : array_like
        Contact modulus ``E*`` (Pa).
    R_star : array_like
        Effective radius ``R*`` (m).

    Returns
    -------
    ndarray
        Peak pressure ``p0`` (Pa) at the centre of the contact.

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 4, section 4.2.
    """
    return 2.0 * np.asarray(E_star, float) * contact_radius(delta, R_star) / (
        np.pi * np.asarray(R_star, float)
    )


def pressure_profile(
    r: ArrayLike, delta: ArrayLike, E_star: ArrayLike, R_star: ArrayLike
) -> NDArray[np.float64]:
    """Hertz pressure ``p(r) = p0 sqrt(1 - r^2/a^2)`` for ``r < a``, else 0 (Pa).

    Parameters
    ----------
    r : array_like
        Radial distance from the contact's centre (m).
    delta : array_like
        Approach (m).
    E_star : array_like
        Contact modulus ``E*`` (Pa).
    R_star : array_like
        Effective radius ``R*`` (m).

    Returns
    -------
    ndarray
        Contact pressure (Pa), the broadcast shape of the inputs.

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 4, section 4.2.
    """
    a = contact_radius(delta, R_star)
    p0 = peak_pressure(delta, E_star, R_star)
    s = 1.0 - (np.asarray(r, float) / np.where(a > 0, a, np.inf)) ** 2
    return p0 * np.sqrt(np.clip(s, 0.0, None))


def energy_indentation(A: ArrayLike, energy: ArrayLike, load: ArrayLike = 0.0
                       ) -> NDArray[np.float64]:
    """Indentation (m) at which ``F = A delta^(3/2)`` stores ``energy`` more than the work of
    a constant ``load``: the positive root of

        ``(2/5) A delta^(5/2) - P delta = W``,

    the bound energy conservation sets on the indentation of an impact that brings ``W``
    while ``P`` presses on (Johnson 1985, ch. 11). Without a load it is
    ``(5 W / (2 A))^(2/5)``; with one, the root of the convex left side (negative, then
    increasing beyond its minimum) by :func:`ssw.roots.find_root` on the bracket
    ``[max((5 W / (2 A))^(2/5), (5 P / (2 A))^(2/3)), max((5 W / A)^(2/5), (5 P / A)^(2/3))]``
    (at the lower end the left side is ``-P delta`` or ``-W``, <= 0: the bracket starts
    1e-9 below it; at the upper one ``(1/5) A delta^(5/2)`` covers ``W`` and ``P delta``
    each); without an energy the root is ``(5 P / (2 A))^(2/3)``. The upper end of the
    final bracket is returned: the contact stores at least ``W + P delta`` there, so the
    value bounds the reach from above, as its users need (a range that must hold the
    energy, an upper bound of a peak).

    Parameters
    ----------
    A : array_like
        Hertz coefficient (N m^-3/2), > 0.
    energy : array_like
        ``W``, J, >= 0.
    load : array_like
        ``P``, N, >= 0.

    Returns
    -------
    ndarray
        Indentation (m), the broadcast shape of the inputs.
    """
    Aa = _check_positive("A", A)
    W, P = np.broadcast_arrays(np.asarray(energy, float), np.asarray(load, float))
    if np.any(~(W >= 0)) or np.any(~(P >= 0)):
        raise ConfigError("energy", (energy, load), "energies and loads >= 0 (J, N)")
    Aa, W, P = np.broadcast_arrays(Aa, W, P)
    lo = (2.5 * W / Aa) ** 0.4
    if not np.any(P > 0):
        return lo
    # a hair below the lower end: there the left side is negative by far more than its
    # round-off (its slope is at least 1.5 W / delta, or 1.5 P)
    lo = (1.0 - 1e-9) * np.maximum(lo, (2.5 * P / Aa) ** (2.0 / 3.0))
    hi = np.maximum((5.0 * W / Aa) ** 0.4, (5.0 * P / Aa) ** (2.0 / 3.0))
    root = find_root(lambda d: 0.4 * Aa * d**2.5 - P * d - W, lo, hi)
    return root.hi


def contact_time(m_eff: ArrayLike, A: ArrayLike, v: ArrayLike) -> NDArray[np.float64]:
    """Hertz impact duration ``t_c = 2.9432 (5 m / (4 A))^(2/5) v^(-1/5)`` (s).

    ``m_eff`` is the reduced mass (kg), ``A`` the coefficient of ``F = A delta^(3/2)`` and
    ``v`` the approach speed (m/s). Johnson (1985), eq. (11.24).

    Parameters
    ----------
    m_eff : array_like
        Reduced mass of the two bodies (kg).
    A : array_like
        Coefficient of ``F = A delta^(3/2)`` (N m^-3/2).
    v : array_like
        Approach speed at first contact (m/s), > 0.

    Returns
    -------
    ndarray
        Contact duration ``t_c`` (s).

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, eq. (11.24).
    """
    m, a, vv = (np.asarray(x, float) for x in (m_eff, A, v))
    return HERTZ_TC * (5.0 * m / (4.0 * a)) ** 0.4 * vv ** (-0.2)


def sneddon_sphere(
    a: ArrayLike, E_star: ArrayLike, R: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Exact rigid sphere on a half-space (Sneddon 1965): ``(delta, F)`` at contact radius a.

    ``delta = (a/2) ln((R+a)/(R-a))``; ``F = (E*/2) [(a^2+R^2) ln((R+a)/(R-a)) - 2 a R]``.

    Parameters
    ----------
    a : array_like
        Contact radius (m), < ``R``.
    E_star : array_like
        Contact modulus ``E*`` of the half-space (Pa).
    R : array_like
        Radius of the rigid sphere (m).

    Returns
    -------
    delta : ndarray
        Approach (m).
    F : ndarray
        Contact force (N).

    Raises
    ------
    ConfigError
        If a contact radius is not smaller than the sphere's radius.

    References
    ----------
    Sneddon, I. N. (1965). The relation between load and penetration in the axisymmetric
    Boussinesq problem for a punch of arbitrary profile. *Int. J. Eng. Sci.* 3, 47-57.
    """
    aa, RR, Es = np.broadcast_arrays(*(np.asarray(v, float) for v in (a, R, E_star)))
    if np.any(aa >= RR):
        raise ConfigError("a", a, "contact radius must be smaller than the sphere radius")
    x = aa / RR
    # ln((R+a)/(R-a)) = 2 atanh(x); F = E* R^2 [(atanh(x) - x) + x^2 atanh(x)], where
    # atanh(x) - x = sum_k x^(2k+1)/(2k+1), k >= 1, is summed as a series for small x to
    # avoid cancellation (12 terms: truncation < x^27 < 1e-26 for x < 0.1).
    k = np.arange(1, 13)
    series = np.sum(x[..., None] ** (2 * k + 1) / (2 * k + 1), axis=-1)
    at_minus_x = np.where(x < 0.1, series, np.arctanh(x) - x)
    return aa * np.arctanh(x), Es * RR**2 * (at_minus_x + x**2 * np.arctanh(x))


def _impact_time_coefficient() -> float:
    """2 * integral_0^1 dx / sqrt(1 - x^(5/2)) (Johnson 1985, eq. 11.24): 2.9432."""
    from math import gamma

    # integral_0^1 (1 - x^(5/2))^(-1/2) dx = (2/5) B(2/5, 1/2), B(a, b) = G(a) G(b) / G(a+b)
    return 2.0 * 0.4 * gamma(0.4) * gamma(0.5) / gamma(0.9)


#: Johnson (1985) eq. 11.24 constant, computed: 2 * (2/5) B(2/5, 1/2) = 2.9432.
HERTZ_TC: float = _impact_time_coefficient()
