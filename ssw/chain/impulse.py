"""The contact forces a step applies: smooth through a contact's opening and closing.

Velocity Verlet's positions obey ``u_(n+1) - 2 u_n + u_(n-1) = dt^2 a(u_n)`` (Störmer's
form; Hairer, Lubich & Wanner 2006, sec. I.1.4), while the exact motion obeys

    u(t + dt) - 2 u(t) + u(t - dt) = dt^2 <a>,  <a> = int_{-dt}^{dt} (dt - |s|) a(t + s) ds / dt^2,

the acceleration averaged with the hat weight of the two half-steps around ``t``. Taking
``a(u_n)`` for ``<a>`` errs by ``O(dt^2)`` where the force is smooth in time, an error that
is a smooth function of the run's parameters. The Hertz law ``A [d]_+^(3/2)`` and the
dashpot's switch at ``d = 0`` are not smooth where a contact opens or closes: there the
error depends on where the event falls between two steps (``O(dt^(5/2))``, oscillating
with that phase). The phase moves as a parameter moves the waves, so TOFs were noisy in
their parameters (~1e-6 relative between moduli 0.1 % apart, ``ssw bench smooth``) and
exact derivatives of the discrete TOF wiggled with it.

Here a bead-bead contact whose overlap ``d`` lies within ``-|delta| < d < FAR |delta|`` of an
event (``delta = d' dt``, ``d'`` its rate at the new time, predicted as the dashpot's) exerts
``A |delta|^(3/2) phi(d / |delta|)``, with

    phi(x) = psi(x) - q(x),   psi(x) = [(x + 1)_+^(7/2) - 2 x_+^(7/2) + (x - 1)_+^(7/2)] / (35/4):

``|delta|^(3/2) psi`` is the law's hat average along the linear motion ``d + s d'``
(``|s| <= dt``; the second difference of its double antiderivative), exact through the event,
and ``q`` removes its smooth part: ``q`` is the sextic that leaves ``x = -1`` with value
and three derivatives 0 and meets the smooth part ``psi(x) - x^(3/2)`` (``= x^(-1/2) / 16
+ x^(-5/2) / 640 + ...`` for large ``x``: an ``O(dt^2)`` term of the average, which the
scheme's own error already has) at ``x = FAR`` to second derivative. So ``phi`` joins the
law ``x^(3/2)`` at ``FAR`` and 0 at -1 with two continuous derivatives, and everywhere else
the step applies the law itself: the scheme away from events is unchanged, and through an
event its force is a C2 function of ``(d, delta)`` whose impulse no longer depends on the
event's phase. The dashpot ``c d'`` acts with the hat-weighted share ``Phi(d / |delta|)``
of the two half-steps the contact is closed (``Phi`` the hat's distribution function: 0
below -1, ``(1 + x)^2 / 2`` to 0, ``1 - (1 - x)^2 / 2`` to 1, 1 beyond), the exact average
of its switch along the linear motion, C1.

References
----------
Hairer, E., Lubich, C. and Wanner, G. (2006). *Geometric Numerical Integration*, 2nd ed.,
Springer, sec. I.1.4 (Störmer-Verlet).
"""

from __future__ import annotations

import numpy as np

#: ``d / |delta|`` from which the law itself applies (``phi`` joins ``x^(3/2)`` there).
FAR = 8.0
#: Offsets of the three terms of ``psi`` and their weights (``1, -2, 1`` over 35/4).
OFFSETS = np.array([1.0, 0.0, -1.0])
WEIGHTS = np.array([1.0, -2.0, 1.0]) / 8.75
#: Powers ``0..7`` of the bridge polynomial.
POWERS = np.arange(8.0)


def _smooth_part(x: float) -> tuple[float, float, float, float]:
    """``psi(x) - x^(3/2)`` and its first three derivatives at ``x >= 1`` (closed form)."""
    y = x + OFFSETS
    w = np.array([1.0, -2.0, 1.0])
    v = float(w @ y**3.5) / 8.75 - x**1.5
    d1 = float(w @ y**2.5) * 0.4 - 1.5 * x**0.5
    d2 = float(w @ y**1.5) - 0.75 * x**-0.5
    d3 = 1.5 * float(w @ y**0.5) + 0.375 * x**-1.5
    return v, d1, d2, d3


def _bridge() -> np.ndarray:
    """Monomial coefficients (low to high) of ``q``: zero with three derivatives at -1 (so
    that ``psi``, which starts as ``(x + 1)^(7/2)``, dominates it there: ``phi >= 0``), the
    smooth part with two derivatives at :data:`FAR`."""
    def row(x0: float, order: int) -> list[float]:
        out = []
        for j in range(POWERS.size):
            c = 1.0
            for r in range(order):
                c *= j - r
            out.append(c * x0 ** (j - order) if j >= order else 0.0)
        return out

    v, d1, d2, d3 = _smooth_part(FAR)
    rows = [row(-1.0, k) for k in range(4)] + [row(FAR, k) for k in range(4)]
    return np.linalg.solve(np.array(rows), np.array([0.0, 0.0, 0.0, 0.0, v, d1, d2, d3]))


#: Coefficients of ``q`` (powers ``0..5`` of ``x``).
BRIDGE = _bridge()
#: Those of ``q'``.
BRIDGE_SLOPE = np.concatenate([BRIDGE[1:] * POWERS[1:], [0.0]])


def phi(x: np.ndarray, tangent: bool = False) -> tuple[np.ndarray, np.ndarray | None]:
    """``phi(x)`` for ``-1 <= x <= FAR`` (module docstring) and, with ``tangent``, its
    derivative (powers by products and square roots: no ``pow``)."""
    y = np.maximum(x[:, None] + OFFSETS, 0.0)
    y25 = y * y * np.sqrt(y)
    val = (y25 * y) @ WEIGHTS
    val -= _horner(BRIDGE, x)
    if not tangent:
        return val, None
    return val, 3.5 * (y25 @ WEIGHTS) - _horner(BRIDGE_SLOPE, x)


def _horner(c: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The polynomial of coefficients ``c`` (low to high) at ``x``."""
    r = np.full_like(x, c[-1])
    for ci in c[-2::-1]:
        r *= x
        r += ci
    return r


def near_events(x: np.ndarray) -> np.ndarray:
    """Flat indices of the contacts near an event: ``-1 < x < FAR``, ``x = d / |delta|``
    (NaN, a contact at rest at ``d = 0``, is not)."""
    m = x > -1.0
    m &= x < FAR
    return m.ravel().nonzero()[0]


def hertz_force(d: np.ndarray, a: np.ndarray, x: np.ndarray, A: float | np.ndarray,
                near: np.ndarray, out: np.ndarray, tangent: bool = False
                ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The Hertz force ``A [d]_+^(3/2)`` the step applies (module docstring), into ``out``.

    Parameters
    ----------
    d : numpy.ndarray
        Overlaps (m), any shape (the bead-bead contacts (N - 1, n), a wall's (n,)).
    a : numpy.ndarray
        ``|d'| dt`` (m), same shape.
    x : numpy.ndarray
        ``d / a``, same shape.
    A : float or numpy.ndarray
        Hertz coefficient (N/m^1.5), a scalar or one per contact (same shape).
    near : numpy.ndarray
        Flat indices of the contacts near an event (:func:`near_events`).
    out : numpy.ndarray
        N, same shape, written.
    tangent : bool
        Also return ``dF/dd`` (N/m) and ``dF/da`` (N/m), else None.

    Returns
    -------
    tuple
        ``(dF/dd, dF/da)`` or ``(None, None)``.
    """
    dp = np.maximum(d, 0.0)
    sq = np.sqrt(dp)
    np.multiply(dp, sq, out=out)
    out *= A
    fd = fa = None
    if tangent:
        fd = 1.5 * A * sq
        fa = np.zeros_like(d)
    if near.size:
        an = a.flat[near]
        xn = x.flat[near]
        val, dval = phi(xn, tangent)
        s = (A if np.ndim(A) == 0 else np.asarray(A).flat[near]) * np.sqrt(an)
        out.flat[near] = s * an * val
        if tangent:
            fd.flat[near] = s * dval
            fa.flat[near] = s * (1.5 * val - xn * dval)
    return fd, fa


def closed_share(d: np.ndarray, a: np.ndarray, near: np.ndarray, tangent: bool = False
                 ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """``Phi(d / a)``: the hat-weighted share of the two half-steps a contact is closed
    along its linear motion (module docstring): 1 for ``d >= a``, 0 for ``d <= -a``.

    Parameters
    ----------
    d : numpy.ndarray
        Overlaps (m), any shape.
    a : numpy.ndarray
        ``|d'| dt`` (m), same shape.
    near : numpy.ndarray
        Flat indices of the contacts with ``|d| < a`` (others are 0 or 1).
    tangent : bool
        Also return ``dPhi/dd`` and ``dPhi/da`` (1/m), else None.

    Returns
    -------
    tuple
        ``(Phi, dPhi/dd, dPhi/da)``.
    """
    share = (d > 0).astype(float)
    gd = ga = None
    if tangent:
        gd = np.zeros_like(d)
        ga = np.zeros_like(d)
    if near.size:
        an = a.flat[near]
        x = d.flat[near] / an
        share.flat[near] = np.where(x <= 0, 0.5 * (1.0 + x) ** 2, 1.0 - 0.5 * (1.0 - x) ** 2)
        if tangent:
            slope = 1.0 - np.abs(x)
            gd.flat[near] = slope / an
            ga.flat[near] = -slope * x / an
    return share, gd, ga
