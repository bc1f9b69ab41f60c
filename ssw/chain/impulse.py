"""The contact forces a step applies: each law averaged over the step's relative motion.

Velocity Verlet's positions obey ``u_(n+1) - 2 u_n + u_(n-1) = dt^2 a(u_n)`` (Störmer's
form; Hairer, Lubich & Wanner 2006, sec. I.1.4), while the exact motion obeys::

    u(t + dt) - 2 u(t) + u(t - dt) = dt^2 <a>,  <a> = int_{-dt}^{dt} (dt - |s|) a(t + s) ds / dt^2,

the acceleration averaged with the hat weight of the two half-steps around ``t``. Taking
``a(u_n)`` for ``<a>`` errs by ``O(dt^2)`` where the force is smooth in time, an error that
is a smooth function of the run's parameters. The Hertz law ``A [d]_+^(3/2)`` and the
dashpot's switch at ``d = 0`` are not smooth where a contact opens or closes: there the
error depends on where the event falls between two steps (``O(dt^(5/2))``, oscillating
with that phase). The phase moves as a parameter moves the waves, so TOFs were noisy in
their parameters (~1e-6 relative between moduli 0.1 % apart, ``ssw bench smooth``) and
exact derivatives of the discrete TOF wiggled with it.

Here every bead-bead contact exerts the hat average of its law along the linear relative
motion ``d + s d'``, ``|s| <= dt`` (``delta = d' dt``, ``d'`` the
overlap's rate at the half step)::

    F = A |delta|^(3/2) psi(d / |delta|),
    psi(x) = [(x + 1)_+^(7/2) - 2 x_+^(7/2) + (x - 1)_+^(7/2)] / (35/4),

the second difference of the law's double antiderivative: exact for a linear motion, C3
in ``(d, delta)`` through the event, so that the impulse no longer depends on the event's
phase. Far from an event (``d >= FAR |delta|``) the same average is summed from its Taylor
series in ``r = (delta / d)^2``, ``F = A d^(3/2) [1 + r / 16 + r^2 / 640 + ...]`` (relative
truncation ``r^3 / 4096 < 4e-12`` there; no cancellation), which differs from the law by
``(delta / d)^2 / 16``, a part of the step's own ``O(dt^2)`` error: TOFs move by ~1e-6
relative, and nearer the independent DOP853 solution (10 MPa: -7.4e-5 instead of -7.7e-5).
The dashpot ``c d'`` acts with the hat-weighted share ``Phi(d / |delta|)`` of the two
half-steps the contact is closed (``Phi`` the hat's distribution function: 0 below -1,
``(1 + x)^2 / 2`` to 0, ``1 - (1 - x)^2 / 2`` to 1, 1 beyond), the exact average of its
switch along the linear motion, C1 (unchanged away from events). The wall's law applies at
its point value (any law, and the same for a stateful wall's static limit: walls that
coincide give one TOF); the thesis device's wall stays closed under the chain's weight
through the first hit, so it has no event to smooth.

References
----------
Hairer, E., Lubich, C. and Wanner, G. (2006). *Geometric Numerical Integration*, 2nd ed.,
Springer, sec. I.1.4 (Störmer-Verlet).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

#: ``d / |delta|`` from which the average is summed from its series.
FAR = 20.0
#: Coefficients of ``r`` and ``r^2`` of the series ``psi / d^(3/2) = 1 + r / 16 + r^2 / 640
#: + r^3 / 4096 + ...``: the terms ``delta^2 G''''/12 + delta^4 G^(6)/360 + ...`` of the
#: second difference of ``G = d^(7/2) / (35/4)``.
SERIES = (1.0 / 16.0, 1.0 / 640.0)
#: Offsets of the three terms of ``psi`` and their weights (``1, -2, 1`` over 35/4).
OFFSETS = np.array([1.0, 0.0, -1.0])
WEIGHTS = np.array([1.0, -2.0, 1.0]) / 8.75


@lru_cache(maxsize=512)
def filled(shape: tuple[int, ...], value: float) -> np.ndarray:
    """A read-only array of ``shape`` holding ``value`` everywhere.

    numpy converts a Python scalar operand on every ufunc call; an array operand of the
    same shape is about twice as fast on the chain's small arrays (a few dozen values),
    where that overhead is most of a call's cost. The result is the same to the bit.

    Parameters
    ----------
    shape : tuple of int
        The shape.
    value : float
        The value.

    Returns
    -------
    numpy.ndarray
        float, not writeable (shared between calls).
    """
    out = np.full(shape, float(value))
    out.flags.writeable = False
    return out


def psi(x: np.ndarray, tangent: bool = False) -> tuple[np.ndarray, np.ndarray | None]:
    """``psi(x)`` (module docstring) for ``-1 <= x <= FAR`` and, with ``tangent``, its
    derivative (powers by products and square roots: no ``pow``).

    Parameters
    ----------
    x : numpy.ndarray
        (m,) ``d / |delta|``.
    tangent : bool
        Also ``psi'(x)``.

    Returns
    -------
    tuple
        ``(psi, psi')``, (m,) each (None without ``tangent``).
    """
    y = np.add(x[:, None], OFFSETS)
    np.maximum(y, filled(y.shape, 0.0), out=y)
    y25 = np.multiply(y, y)
    y25 *= np.sqrt(y)
    if not tangent:
        y *= y25
        return _weighted(y), None
    # both sums weighted at once: rows (y^3.5, y^2.5)
    both = np.empty((2, *y.shape))
    np.multiply(y25, y, out=both[0])
    both[1] = y25
    val, dval = _weighted(both)
    dval *= filled(dval.shape, 3.5)
    return val, dval


def _weighted(y: np.ndarray) -> np.ndarray:
    """``y @ WEIGHTS`` over the last axis (length 3), in a fixed order: explicit sums,
    not a matrix product, whose rounding may follow the batch's size (a scene's force
    does not depend on the scenes run with it)."""
    t = np.multiply(y, WEIGHTS)
    out = np.add(t[..., 0], t[..., 1])
    out += t[..., 2]
    return out


def near_events(x: np.ndarray, upper: float = FAR) -> np.ndarray:
    """Flat indices of the contacts near an event: ``-1 < x < upper``, ``x = d / |delta|``
    (NaN, a contact at rest at ``d = 0``, is not).

    Parameters
    ----------
    x : numpy.ndarray
        ``d / |delta|``, any shape, C-contiguous.
    upper : float
        The bound above: :data:`FAR` for the Hertz force's average, 1 for the dashpot's
        share (:func:`closed_share`).

    Returns
    -------
    numpy.ndarray
        Flat indices (int).
    """
    xf = x.reshape(-1)
    m = xf > filled(xf.shape, -1.0)
    m &= xf < filled(xf.shape, upper)
    return m.nonzero()[0]


def hertz_force(d: np.ndarray, a: np.ndarray, x: np.ndarray, A: float | np.ndarray,
                near: np.ndarray, out: np.ndarray, tangent: bool = False
                ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The Hertz force ``A [d]_+^(3/2)`` the step applies (module docstring), into ``out``.

    Parameters
    ----------
    d : numpy.ndarray
        Overlaps (m), any shape (the bead-bead contacts (N - 1, n), or with a wall's row),
        C-contiguous.
    a : numpy.ndarray
        ``|d'| dt`` (m), same shape, C-contiguous.
    x : numpy.ndarray
        ``d / a``, same shape, C-contiguous.
    A : float or numpy.ndarray
        Hertz coefficient (N/m^1.5), a scalar or one per contact (same shape).
    near : numpy.ndarray
        Flat indices of the contacts near an event (:func:`near_events`).
    out : numpy.ndarray
        N, same shape, C-contiguous, written.
    tangent : bool
        Also return ``dF/dd`` (N/m) and ``dF/da`` (N/m), else None.

    Returns
    -------
    tuple
        ``(dF/dd, dF/da)`` or ``(None, None)``.
    """
    # constant operands as arrays of the contacts' shape (:func:`filled`)
    sh = d.shape
    dp = np.maximum(d, filled(sh, 0.0))
    sq = np.sqrt(dp)
    # the series in r = 1 / x^2 (far contacts; near ones are overwritten below): r is 0 at
    # rest (x infinite) and bounded where it does not apply (fmin ignores a NaN x)
    r = np.multiply(x, x)
    np.reciprocal(r, out=r)
    one = filled(sh, 1.0)
    np.fmin(r, one, out=r)
    c1, c2 = SERIES
    poly = np.multiply(r, filled(sh, c2))
    poly += filled(sh, c1)
    poly *= r
    poly += one
    np.multiply(dp, sq, out=out)
    out *= poly
    Ac = filled(sh, A) if np.isscalar(A) else A
    out *= Ac
    fd = fa = None
    if tangent:
        # d/dd [d^1.5 P(r)] = d^0.5 (1.5 P - 2 r P'), d/da = d^1.5 P' 2 r / a = 2 P' a d^-0.5
        dpoly = np.multiply(r, filled(sh, 2.0 * c2))
        dpoly += filled(sh, c1)
        poly *= filled(sh, 1.5)
        r *= filled(sh, 2.0)
        r *= dpoly
        poly -= r
        fd = np.multiply(sq, Ac)
        fd *= poly
        # 2 A P' a / sqrt(d) where d > 0, else 0
        closed = dp > 0
        fa = np.multiply(dpoly, filled(sh, 2.0 * A) if np.isscalar(A) else 2.0 * A)
        fa *= a
        np.divide(fa, sq, out=fa, where=closed)
        fa *= closed
    if near.size:
        af, xf, of = a.reshape(-1), x.reshape(-1), out.reshape(-1)
        an = af[near]
        xn = xf[near]
        val, dval = psi(xn, tangent)
        s = np.sqrt(an)
        s *= A if np.isscalar(A) else np.asarray(A).reshape(-1)[near]
        of[near] = s * an * val
        if tangent:
            fd.reshape(-1)[near] = s * dval
            xn *= dval
            val *= 1.5
            val -= xn
            val *= s
            fa.reshape(-1)[near] = val
    return fd, fa


def closed_share(d: np.ndarray, a: np.ndarray, near: np.ndarray, tangent: bool = False
                 ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """``Phi(d / a)``: the hat-weighted share of the two half-steps a contact is closed
    along its linear motion (module docstring): 1 for ``d >= a``, 0 for ``d <= -a``.

    Parameters
    ----------
    d : numpy.ndarray
        Overlaps (m), any shape, C-contiguous.
    a : numpy.ndarray
        ``|d'| dt`` (m), same shape, C-contiguous.
    near : numpy.ndarray
        Flat indices of the contacts with ``|d| < a`` (others are 0 or 1).
    tangent : bool
        Also return ``dPhi/dd`` and ``dPhi/da`` (1/m), else None.

    Returns
    -------
    tuple
        ``(Phi, dPhi/dd, dPhi/da)``.
    """
    share = np.empty(d.shape)
    np.greater(d, filled(d.shape, 0.0), out=share)
    gd = ga = None
    if tangent:
        gd = np.zeros_like(d)
        ga = np.zeros_like(d)
    if near.size:
        an = a.reshape(-1)[near]
        x = d.reshape(-1)[near] / an
        share.reshape(-1)[near] = np.where(x <= 0, 0.5 * (1.0 + x) ** 2,
                                           1.0 - 0.5 * (1.0 - x) ** 2)
        if tangent:
            slope = 1.0 - np.abs(x)
            gd.reshape(-1)[near] = slope / an
            ga.reshape(-1)[near] = -slope * x / an
    return share, gd, ga
