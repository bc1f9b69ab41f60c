"""Roots of monotone functions, many at once: the one bracketed root finder of ssw.

Every scalar root ssw solves for is the root of a monotone function, one per element of an
array (a scene, a target): the indentation at which a wall carries a force, the
indentation at which a Hertz contact stores an energy. :func:`find_root` solves them all
together by Chandrupatla's method (1997: inverse quadratic interpolation, safeguarded by
bisection, on a bracket that always holds the root), vectorized over the elements with
numpy alone. It reaches full double precision in 8-16 evaluations of the function (the
bracket's two ends and its growth included) where bisection took 60-90
(``tests/test_roots.py`` counts them).

Where the function's slope is known and cheap, :func:`newton_bracketed` is the
safeguarded Newton iteration on the same kind of bracket (Newton's point when it stays in
the bracket, bisection otherwise), with a state per element for the caller's warm starts
and an exact stop on a piecewise-affine function: the indentation of a contact's force
(:mod:`ssw.contact.stress`), a return mapping's consistency equation.

The function is evaluated on whole arrays: ``f(x)`` takes and returns arrays of the
elements' shape, element ``i`` depending on ``x[i]`` alone (a wall's force, one value per
scene). ``f`` always sees every element: the converged ones stay at their last abscissa
while the others go on, so one call costs one evaluation of ``f``, whatever its number of
elements.

Why not scipy's ``scipy.optimize.elementwise.find_root`` (the same method, which ssw
wrapped before): measured on a 2-core machine, shared (best of 5-7),

* import: ``scipy.optimize.elementwise`` costs 0.15-0.25 s CPU on top of ``scipy.linalg``
  (it runs all of ``scipy/optimize/__init__.py``); this module needs numpy only;
* per call of ``f``: scipy's bookkeeping is 0.10-0.16 ms, this one's 0.03-0.05 ms (300
  cube roots: 1.30 ms a solve against 0.43 ms; 300 Hertz indentations grown from
  ``[0, 1 um]``: 1.7 ms against 0.65 ms);
* evaluations: scipy evaluates the bracket's two ends again (2 calls of ``f`` more a solve,
  each an LCP solve for the dynamic FEM wall's static law).

The iterates are those of scipy's code, bit for bit (``tests/test_roots.py`` compares them).

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
from typing import Any

import numpy as np

from ssw.errors import SolverError

#: Default relative tolerance on the root: 4 ulp (scipy's default for find_root).
XRTOL = 4.0 * float(np.finfo(float).eps)
#: Most doublings of a bracket's upper end (``grow=True``): 2^200 of the first guess.
MAX_GROWTH = 200
#: Most iterations of Chandrupatla's method: log2 of the ratio of the largest double to
#: the smallest normal one (bisection's worst case over the whole range; scipy's default).
MAX_ITERATIONS = 2046


@dataclass(frozen=True)
class Root:
    """Roots of an increasing function, element by element (SI units of the unknown).

    ``x`` is the estimate (the end of the final bracket with the smaller ``|f|``); ``lo``
    and ``hi`` the final bracket, ``f(lo) <= 0 <= f(hi)``: ``hi`` is the smallest abscissa
    known to reach the level, ``lo`` the largest known below it. ``calls``: evaluations of
    ``f`` (each on every element), including the bracket's growth.

    Parameters
    ----------
    x : numpy.ndarray
        The roots.
    lo : numpy.ndarray
        The brackets' lower ends.
    hi : numpy.ndarray
        The brackets' upper ends.
    calls : int
        Evaluations of ``f``.
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

    Notes
    -----
    Chandrupatla (1997), element by element. The bracket ``(x1, x2)`` holds the root,
    ``f1 = f(x1)`` and ``f2 = f(x2)`` of opposite signs; ``x3`` is the end last dropped.
    Each iteration evaluates ``f`` at

        ``xt = x1 + t (x2 - x1)``,

    ``t = 1/2`` at first. If ``f(xt)`` has the sign of ``f1``, ``x3 = x1``; else ``x3 = x2``
    and ``x2 = x1``; then ``x1 = xt``: ``(x1, x2)`` holds the root again and ``x3`` is the
    end dropped. The estimate ``x`` is the end of smaller ``|f|``; the element stops
    when ``f(x) = 0`` or ``|x2 - x1| < tol = xatol + xrtol |x|``. Otherwise, with

        ``xi = (x1 - x2) / (x3 - x2)``,  ``phi = (f1 - f2) / (f3 - f2)``,

    the inverse quadratic through the three points is monotone on the bracket when
    ``1 - sqrt(1 - xi) < phi < sqrt(xi)`` (the paper's criterion), and the next step is
    its value at ``f = 0``,

        ``t = f1 / (f1 - f2) * f3 / (f3 - f2) - alpha f1 / (f3 - f1) * f2 / (f2 - f3)``,
        ``alpha = (x3 - x1) / (x2 - x1)``,

    else bisection, ``t = 1/2``; ``t`` is clipped to ``[tl, 1 - tl]``,
    ``tl = tol / (2 |x2 - x1|)``, so that a step moves by at least half the tolerance.
    The final bracket is narrowed to ``x`` on the side of the sign of ``f(x)``.
    """
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
        lo, f_lo, hi, f_hi = _grow_bracket(full, lo, f_lo, hi, f_hi, limit)
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
        _chandrupatla(full, idx, lo[idx], f_lo[idx], hi[idx], f_hi[idx], x, out_lo, out_hi,
                      max(float(xatol), 4.0 * float(np.finfo(float).tiny)), float(xrtol))
    return Root(x.reshape(shape), out_lo.reshape(shape), out_hi.reshape(shape), calls)


def _grow_bracket(full: Callable[[np.ndarray], np.ndarray], lo: np.ndarray, f_lo: np.ndarray,
                  hi: np.ndarray, f_hi: np.ndarray, limit: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Move each bracket up until ``f(hi) >= 0``: ``lo`` to the old ``hi``, ``hi`` twice as
    far from it again, at most :data:`MAX_GROWTH` times (:func:`find_root`'s ``grow``).

    Parameters
    ----------
    full : callable
        The function on every element (flat arrays), counted and checked finite.
    lo : ndarray
        Lower ends (flat).
    f_lo : ndarray
        ``f(lo)``.
    hi : ndarray
        Upper ends (flat), first guesses.
    f_hi : ndarray
        ``f(hi)``.
    limit : float
        The largest upper end allowed.

    Returns
    -------
    tuple of ndarray
        ``(lo, f(lo), hi, f(hi))`` of the grown brackets.

    Raises
    ------
    SolverError
        The growth passed ``limit``.
    """
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
    return lo, f_lo, hi, f_hi


def _chandrupatla(full: Callable[[np.ndarray], np.ndarray], pos: np.ndarray,
                  x1: np.ndarray, f1: np.ndarray, x2: np.ndarray, f2: np.ndarray,
                  x: np.ndarray, out_lo: np.ndarray, out_hi: np.ndarray,
                  xatol: float, xrtol: float) -> None:
    """Chandrupatla's iteration on the elements ``pos``, writing their roots in place.

    Parameters
    ----------
    full : callable
        The function on every element (flat arrays), counted and checked finite.
    pos : ndarray
        Flat indices of the elements to solve, each with ``f1 < 0 < f2``.
    x1 : ndarray
        Lower ends of their brackets.
    f1 : ndarray
        ``f(x1)``, < 0.
    x2 : ndarray
        Upper ends of their brackets.
    f2 : ndarray
        ``f(x2)``, > 0.
    x : ndarray
        Abscissae of all elements (flat), where ``f`` sees the elements not in ``pos``;
        the roots of ``pos`` are written in it.
    out_lo : ndarray
        Final lower ends (flat), written at ``pos``.
    out_hi : ndarray
        Final upper ends (flat), written at ``pos``.
    xatol : float
        Absolute tolerance (> 0).
    xrtol : float
        Relative tolerance.

    Raises
    ------
    SolverError
        An end is not finite, or :data:`MAX_ITERATIONS` iterations did not converge.
    """
    finite = np.isfinite(x1) & np.isfinite(x2)
    if not finite.all():
        raise SolverError(
            f"a root's bracket has an end that is not finite: [{x1[~finite][:3].tolist()}, "
            f"{x2[~finite][:3].tolist()}] (give finite ends, or grow=True from a finite "
            "first guess)")
    xf = x.copy()  # the abscissae f sees: the converged elements keep their last one
    x3 = f3 = np.empty(0)
    t = 0.5  # the first point is the midpoint
    for it in range(MAX_ITERATIONS + 1):
        if it:
            # the new point, on the chord of the bracket
            xt = x1 + t * (x2 - x1)
            xf[pos] = xt
            ft = full(xf)[pos]
            # it replaces the end of its sign, which becomes x3
            same = np.sign(ft) == np.sign(f1)
            x3, f3 = np.where(same, x1, x2), np.where(same, f1, f2)
            x2, f2 = np.where(same, x2, x1), np.where(same, f2, f1)
            x1, f1 = xt, ft
        # the estimate: the end of smaller |f|; stop on f = 0 there or a short bracket
        near = np.abs(f1) < np.abs(f2)
        xm, fm = np.where(near, x1, x2), np.where(near, f1, f2)
        dx = np.abs(x2 - x1)
        tol = np.abs(xm) * xrtol + xatol
        stop = (fm == 0) | (dx < tol)
        if stop.any():
            p = pos[stop]
            x[p] = xm[stop]
            a, b = x1[stop], x2[stop]
            out_lo[p] = np.where(fm[stop] <= 0, xm[stop], np.minimum(a, b))
            out_hi[p] = np.where(fm[stop] >= 0, xm[stop], np.maximum(a, b))
            go = ~stop
            if not go.any():
                return
            pos, x1, f1, x2, f2, dx, tol = (
                pos[go], x1[go], f1[go], x2[go], f2[go], dx[go], tol[go])
            if it:
                x3, f3 = x3[go], f3[go]
        if it == 0:
            continue
        # inverse quadratic interpolation through the three points where it is monotone
        # (Chandrupatla's criterion, eq. 1), bisection elsewhere
        with np.errstate(divide="ignore", invalid="ignore"):
            xi = (x1 - x2) / (x3 - x2)
            phi = (f1 - f2) / (f3 - f2)
            alpha = (x3 - x1) / (x2 - x1)
            quad = ((1 - np.sqrt(1 - xi)) < phi) & (phi < np.sqrt(xi))
            t = np.where(quad, f1 / (f1 - f2) * f3 / (f3 - f2)
                         - alpha * f1 / (f3 - f1) * f2 / (f2 - f3), 0.5)
        # at least half the tolerance away from the ends of the bracket
        tl = 0.5 * tol / dx
        t = np.clip(t, tl, 1 - tl)
    raise SolverError(f"the bracketed root did not converge in {MAX_ITERATIONS} iterations "
                      f"(brackets left: [{x1[:3].tolist()}, {x2[:3].tolist()}])")


#: Newton steps allowed by :func:`newton_bracketed` (a piecewise-affine function: one per
#: piece crossed).
NEWTON_STEPS = 100


@dataclass(frozen=True)
class NewtonRoot:
    """Roots found by :func:`newton_bracketed`, element by element.

    ``x`` (n,) the roots (SI unit of the unknown); ``state`` the caller's state of each
    element at its root (a list, or an array with a row per element); ``lo`` and ``hi``
    (n,) the final brackets; ``calls`` the evaluations of the function (each on the
    elements still going).

    Parameters
    ----------
    x : numpy.ndarray
        The roots.
    state : list or numpy.ndarray
        The caller's state of each element at its root.
    lo : numpy.ndarray
        The brackets' lower ends.
    hi : numpy.ndarray
        The brackets' upper ends.
    calls : int
        Evaluations of the function.
    """

    x: np.ndarray
    state: list | np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    calls: int


def newton_bracketed(
    fun: Callable[[np.ndarray, Any], tuple[np.ndarray, np.ndarray, Any]],
    level: np.ndarray | float, lo: np.ndarray | float, hi: np.ndarray | float,
    state: list | np.ndarray, *, grow: bool = False,
    same_piece: Callable[[Any, Any], bool] | None = None,
    ftol: np.ndarray | float | None = None, max_steps: int = NEWTON_STEPS,
    x0: np.ndarray | float | None = None,
) -> NewtonRoot:
    """Safeguarded Newton iteration for ``f(x) = level``, ``f`` non-decreasing, every
    element at once, starting from the bracket's upper end (or ``x0``).

    Parameters
    ----------
    fun : callable
        ``fun(x, state) -> (f, slope, state)``: ``x`` (m,) the abscissae of some elements,
        ``state`` their states (the caller's warm starts, e.g. an active set; the elements'
        rows of an array state); returns ``f(x)`` (m,), its slope ``f'(x)`` (m,) and the
        states at ``x``.
    level : array_like
        (n,) or scalar, the value to reach (unit of ``f``).
    lo : array_like
        (n,) or scalar, lower ends of the brackets, ``f(lo) < level``.
    hi : array_like
        (n,) or scalar, upper ends, ``f(hi) >= level`` (with ``grow``: a first guess).
    state : list or numpy.ndarray
        The elements' states at ``hi`` before its evaluation (warm starts), length n: a
        list, or an array with a row per element (kept and selected by numpy indexing,
        no Python loop over the elements).
    grow : bool
        Double ``hi`` (warm-starting each evaluation from the last state) until
        ``f(hi) >= level``, at most :data:`MAX_GROWTH` times; ``lo`` stays.
    same_piece : callable or None
        ``same_piece(state, new_state) -> bool``: ``f`` is affine between the two states
        (a piecewise-affine ``f``, whose pieces the states name). A Newton step that lands
        on the piece it stepped along is exact: the element stops there.
    ftol : array_like or None
        (n,) or scalar: the element stops at an iterate with ``|f - level| <= ftol`` (unit
        of ``f``). At least one of ``same_piece`` and ``ftol`` must be given.
    max_steps : int
        Newton steps allowed.
    x0 : array_like or None
        (n,) or scalar, the first iterate, inside ``[lo, hi]``; None: ``hi`` (the only
        start ``grow`` accepts).

    Returns
    -------
    NewtonRoot
        The roots, their states and final brackets.

    Raises
    ------
    SolverError
        The growth found no upper end, or an element did not stop in ``max_steps``.

    Notes
    -----
    From ``x = hi`` (or ``x0``), each step updates the bracket by the sign of ``f(x) - level``
    (``f < level``: ``lo = x``; else ``hi = x``) and goes to Newton's point

        ``x' = x + (level - f(x)) / f'(x)``,

    if ``f'(x) > 0`` and ``lo < x' <= hi``, else to the bracket's midpoint (bisection:
    the bracket at least halves every two steps, so the iteration converges for any
    continuous ``f``; Press et al. 2007, sec. 9.4, ``rtsafe``). On a piecewise-affine
    ``f`` (a contact's force against its indentation, :mod:`ssw.contact.parametric`),
    Newton's point is the root once the step stays on one piece: one step per piece
    crossed.

    References
    ----------
    Press, W. H., Teukolsky, S. A., Vetterling, W. T. and Flannery, B. P. (2007).
    *Numerical Recipes*, 3rd ed., CUP, sec. 9.4 (Newton-Raphson with bisection).
    """
    if same_piece is None and ftol is None:
        raise ValueError("newton_bracketed needs same_piece or ftol to stop")
    if grow and x0 is not None:
        raise ValueError("newton_bracketed grows the bracket from hi: give no x0")
    level, lo, hi = (np.array(np.broadcast_to(np.asarray(v, float), (len(state),)))
                     for v in (level, lo, hi))
    n = level.size
    tol = None if ftol is None else np.broadcast_to(np.asarray(ftol, float), (n,))
    st = _copy(state)
    x = hi.copy() if x0 is None else np.array(np.broadcast_to(np.asarray(x0, float), (n,)))
    f, slope, st = fun(x.copy(), st)
    calls = 1
    if grow:
        calls += _grow_upper(fun, level, hi, f, slope, st)
        x = hi.copy()
    out_x, out_state = x.copy(), _copy(st)
    calls += _newton_steps(fun, level, lo, hi, tol, same_piece, max_steps,
                           (x, np.asarray(f, float), np.asarray(slope, float), st),
                           out_x, out_state)
    return NewtonRoot(out_x, out_state, lo, hi, calls)


def _grow_upper(fun: Callable[[np.ndarray, Any], tuple[np.ndarray, np.ndarray, Any]],
                level: np.ndarray, hi: np.ndarray, f: np.ndarray, slope: np.ndarray,
                st: list | np.ndarray) -> int:
    """Double the upper ends that do not reach ``level`` until each does, warm-starting
    every evaluation from the element's last state (:func:`newton_bracketed`'s ``grow``);
    ``hi``, ``f``, ``slope`` and ``st`` are updated in place. Returns the evaluations of
    ``fun``; raises SolverError after :data:`MAX_GROWTH` doublings."""
    calls = 0
    for _ in range(MAX_GROWTH):
        short = np.flatnonzero(f < level)
        if short.size == 0:
            return calls
        hi[short] *= 2.0
        f_s, s_s, st_s = fun(hi[short], _at(st, short))
        calls += 1
        f[short], slope[short] = f_s, s_s
        _put(st, short, st_s)
    raise SolverError(f"no abscissa up to {hi[f < level][:3].tolist()} reaches the "
                      f"level {level[f < level][:3].tolist()}")


def _newton_steps(fun: Callable[[np.ndarray, Any], tuple[np.ndarray, np.ndarray, Any]],
                  level: np.ndarray, lo: np.ndarray, hi: np.ndarray, tol: np.ndarray | None,
                  same_piece: Callable[[Any, Any], bool] | None, max_steps: int,
                  start: tuple[np.ndarray, np.ndarray, np.ndarray, Any],
                  out_x: np.ndarray, out_state: list | np.ndarray) -> int:
    """The safeguarded Newton steps of :func:`newton_bracketed` (its Notes) from ``start =
    (x, f, slope, states)`` of every element: the brackets ``lo``, ``hi`` are narrowed and
    the stopped elements' abscissae and states written into ``out_x``, ``out_state``, in
    place. Returns the evaluations of ``fun``; raises SolverError when an element does not
    stop in ``max_steps``."""
    calls = 0
    go = np.arange(level.size)
    xs, fs, ss, sts = start
    for _ in range(max_steps):
        lv, a, b = level[go], lo[go], hi[go]
        if tol is not None:
            done = np.abs(fs - lv) <= tol[go]
            if done.any():
                _keep(done, go, xs, sts, out_x, out_state)
                keep = ~done
                go, xs, fs, ss, lv, a, b = (v[keep] for v in (go, xs, fs, ss, lv, a, b))
                sts = _take(sts, keep)
                if go.size == 0:
                    return calls
        a = np.where(fs < lv, xs, a)
        b = np.where(fs < lv, b, xs)
        lo[go], hi[go] = a, b
        mid = 0.5 * (a + b)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(ss > 0, xs + (lv - fs) / ss, mid)
        nxt = np.where((a < step) & (step <= b), step, mid)
        f_n, s_n, st_n = fun(nxt, sts)
        calls += 1
        f_n, s_n = np.asarray(f_n, float), np.asarray(s_n, float)
        if same_piece is not None:
            done = (nxt == step) & np.array([bool(same_piece(p, q))
                                             for p, q in zip(sts, st_n, strict=True)])
            if done.any():
                _keep(done, go, nxt, st_n, out_x, out_state)
                keep = ~done
                go, nxt, f_n, s_n = (v[keep] for v in (go, nxt, f_n, s_n))
                st_n = _take(st_n, keep)
                if go.size == 0:
                    return calls
        xs, fs, ss, sts = nxt, f_n, s_n, st_n
    if go.size:
        raise SolverError(f"Newton's iteration did not reach the level "
                          f"{level[go][:3].tolist()} in {max_steps} steps (brackets "
                          f"[{lo[go][:3].tolist()}, {hi[go][:3].tolist()}])")
    return calls


def _copy(states: list | np.ndarray) -> list | np.ndarray:
    """A copy of the elements' states (a list, or an array with one row per element)."""
    return states.copy() if isinstance(states, np.ndarray) else list(states)


def _at(states: list | np.ndarray, idx: np.ndarray) -> list | np.ndarray:
    """The states of the elements ``idx``."""
    return states[idx] if isinstance(states, np.ndarray) else [states[i] for i in idx]


def _put(states: list | np.ndarray, idx: np.ndarray, values: list | np.ndarray) -> None:
    """Write ``values`` as the states of the elements ``idx``, in place."""
    if isinstance(states, np.ndarray):
        states[idx] = values
        return
    for j, i in enumerate(idx):
        states[i] = values[j]


def _take(states: list | np.ndarray, keep: np.ndarray) -> list | np.ndarray:
    """The states of the elements ``keep`` (bool) holds."""
    if isinstance(states, np.ndarray):
        return states[keep]
    return [s for s, k in zip(states, keep, strict=True) if k]


def _keep(done: np.ndarray, go: np.ndarray, x: np.ndarray, states: list | np.ndarray,
          out_x: np.ndarray, out_state: list | np.ndarray) -> None:
    """Write the stopped elements' abscissae and states (``done`` over ``go``) in place."""
    out_x[go[done]] = x[done]
    _put(out_state, go[done], _take(states, done))
