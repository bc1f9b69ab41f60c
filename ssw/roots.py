"""Roots of monotone functions, many at once: the one bracketed root finder of ssw.

Every scalar root ssw solves for is the root of a monotone function, one per element of an
array (a scene, a target): the indentation at which a wall carries a force, the
indentation at which a Hertz contact stores an energy. :func:`find_root` solves them all
together with scipy's elementwise Chandrupatla method
(``scipy.optimize.elementwise.find_root``; Chandrupatla 1997: inverse quadratic
interpolation, safeguarded by bisection, on a bracket that always holds the root). It
reaches full double precision in 8-16 evaluations of the function (the bracket's two ends
and its growth included) where bisection took 60-90 (``tests/test_roots.py`` counts
them).

The function is evaluated on whole arrays: ``f(x)`` takes and returns arrays of the
elements' shape, element ``i`` depending on ``x[i]`` alone (a wall's force, one value per
scene). scipy evaluates only the elements that have not converged yet; the wrapper here
keeps the others at their last abscissa, so ``f`` always sees every element and one call
costs one evaluation of ``f``, whatever its number of elements.

Cost: scipy's per-iteration bookkeeping is ~0.15 ms (2-core machine, shared), so for a
function cheaper than that the fewer evaluations do not pay: a 300-scene table wall's
static indentation takes 3.2 ms CPU against bisection's 1.5 ms, once per chain run. Where
an evaluation is a solve (the dynamic FEM wall's static law, an LCP each) the 6x fewer
evaluations are the time.

Tolerances: the bracket ``[lo, hi]`` is shrunk until ``hi - lo < xatol + xrtol |x|``
(``xatol`` in the unknown's SI unit, ``xrtol`` relative; defaults: 0 and
:data:`XRTOL`, a few ulp), or until ``f`` vanishes exactly at an end.

References
----------
Chandrupatla, T. R. (1997). A new hybrid quadratic/bisection algorithm for finding the zero
of a nonlinear function without using derivatives. *Advances in Engineering Software*
28(3), 145-149.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ssw.errors import SolverError

#: Default relative tolerance on the root: 4 ulp (scipy's default for find_root).
XRTOL = 4.0 * float(np.finfo(float).eps)
#: Most doublings of a bracket's upper end (``grow=True``): 2^200 of the first guess.
MAX_GROWTH = 200


@dataclass(frozen=True)
class Root:
    """Roots of an increasing function, element by element (SI units of the unknown).

    ``x`` is the estimate (the end of the final bracket with the smaller ``|f|``); ``lo``
    and ``hi`` the final bracket, ``f(lo) <= 0 <= f(hi)``: ``hi`` is the smallest abscissa
    known to reach the level, ``lo`` the largest known below it. ``calls``: evaluations of
    ``f`` (each on every element), including the bracket's growth.
    """

    x: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    calls: int


def find_root(
    f: Callable[[np.ndarray], np.ndarray], lo: np.ndarray, hi: np.ndarray, *,
    xatol: float = 0.0, xrtol: float = XRTOL, grow: bool = False,
    limit: float = np.inf,
) -> Root:
    """Roots of the non-decreasing ``f`` between ``lo`` and ``hi``, every element at once.

    Parameters
    ----------
    f : callable
        ``f(x) -> array`` of the shape of ``x``, non-decreasing and continuous in each
        element (module docstring: it is always called on every element).
    lo : array_like
        Lower ends of the brackets, with ``f(lo) <= 0``.
    hi : array_like
        Upper ends (``> lo``), with ``f(hi) >= 0``; with ``grow`` a first guess only.
    xatol : float
        Absolute tolerance on the root, in the unknown's unit.
    xrtol : float
        Relative tolerance on the root.
    grow : bool
        Double the distance of ``hi`` from the current ``lo`` (and move ``lo`` up to the
        old ``hi``) until ``f(hi) >= 0``.
    limit : float
        With ``grow``: the largest upper end allowed.

    Returns
    -------
    Root
        The roots, their final brackets and the number of calls of ``f``.

    Raises
    ------
    SolverError
        An end does not bracket the root (or the growth passed ``limit``), ``f`` is not
        finite, or the iteration did not converge.
    """
    from scipy.optimize.elementwise import find_root as chandrupatla

    lo, hi = np.broadcast_arrays(np.array(lo, float), np.array(hi, float))
    shape = lo.shape
    lo, hi = lo.ravel().copy(), hi.ravel().copy()
    calls = 0

    def full(x: np.ndarray) -> np.ndarray:
        """``f`` on every element (flat), checked finite."""
        nonlocal calls
        calls += 1
        y = np.broadcast_to(np.asarray(f(x.reshape(shape)), float), shape).ravel()
        if not np.all(np.isfinite(y)):
            raise SolverError("a root's function is not finite at x = "
                              f"{x[~np.isfinite(y)][:3].tolist()}")
        return y

    f_lo, f_hi = full(lo), full(hi)
    if grow:
        for _ in range(MAX_GROWTH):
            short = f_hi < 0
            if not short.any():
                break
            step = hi - lo
            lo, f_lo = np.where(short, hi, lo), np.where(short, f_hi, f_lo)
            hi = np.where(short, hi + 2.0 * step, hi)
            if np.any(hi > limit):
                raise SolverError(f"no root up to {limit:.6g}: the function stays below 0")
            f_hi = full(hi)
    bad = (f_lo > 0) | (f_hi < 0) | ((f_lo < 0) & ~(hi > lo))
    if bad.any():
        raise SolverError(f"the brackets [{lo[bad][:3].tolist()}, {hi[bad][:3].tolist()}] "
                          "do not hold a root of the non-decreasing function")
    # a root at an end (the lower one if both): that end is the whole bracket
    at_lo, at_hi = f_lo == 0, (f_hi == 0) & (f_lo < 0)
    x = np.where(at_lo, lo, hi)
    out_lo = np.where(at_lo, lo, np.where(at_hi, hi, lo))
    out_hi = np.where(at_lo, lo, hi)
    idx = np.flatnonzero(~(at_lo | at_hi))
    if idx.size:
        xf = x.copy()  # the abscissae f sees: the converged elements keep theirs

        def sub(xs: np.ndarray, i: np.ndarray) -> np.ndarray:
            xf[i] = xs
            return full(xf)[i]

        res = chandrupatla(sub, (lo[idx], hi[idx]), args=(idx,),
                           tolerances={"xatol": max(float(xatol), 4.0 * np.finfo(float).tiny),
                                       "xrtol": float(xrtol), "fatol": 0.0, "frtol": 0.0})
        if not np.all(res.success):
            raise SolverError(f"the bracketed root did not converge (status "
                              f"{sorted(set(np.atleast_1d(res.status).tolist()))})")
        x[idx] = res.x
        # the bracket, narrowed to the estimate by the sign of f there (it may end on an
        # exact zero with the other end still far)
        fx = np.asarray(res.f_x, float)
        out_lo[idx] = np.where(fx <= 0, res.x, np.minimum(*res.bracket))
        out_hi[idx] = np.where(fx >= 0, res.x, np.maximum(*res.bracket))
    return Root(x.reshape(shape), out_lo.reshape(shape), out_hi.reshape(shape), calls)
