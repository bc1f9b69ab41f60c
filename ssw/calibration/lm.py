"""Bounded Levenberg-Marquardt for many small least-squares problems advanced together.

A calibration refines several starts of its least squares (local minima of a global scan)
and one problem per leave-one-out subset at once: each iteration gathers every unfinished
problem's trial point and evaluates them in ONE batched run of the chain (the cost of a run
grows far slower than its number of scenes). ``scipy.optimize.least_squares`` (``trf`` with
bounds) solves one problem per call and asks for one point at a time, so the same work
would take one chain run per evaluation of each problem instead of one per iteration of
all of them; hence this loop.

Method: Levenberg-Marquardt (Marquardt 1963; Nocedal & Wright 2006, sec. 10.3) with
Nielsen's damping update (Madsen, Nielsen & Tingleff 2004, eq. 2.21), made for box bounds
``lo <= x <= hi`` by an active set (Kanzow, Yamashita & Fukushima 2004, the projected
Levenberg-Marquardt step; Bertsekas 1982, the active set of a projected Newton method):

* a coordinate is **active** when it lies on a bound and the gradient ``g = J^T r`` of
  ``chi^2 / 2`` points out of the box there (``g_j > 0`` on its lower bound, ``< 0`` on its
  upper one): it stays on the bound, and the step is taken in the other coordinates;
* the damped Gauss-Newton step of the free coordinates is projected onto the box (a
  coordinate that crosses a bound stops on it and is active at the next iteration if the
  gradient still points out);
* a problem is **converged** at a first-order (KKT) point: the undamped Gauss-Newton step of
  its free coordinates would gain less than :func:`tolerance` in chi^2, every active
  coordinate's gradient pointing out of the box. A parameter whose optimum lies beyond its
  bound therefore converges ON the bound, and the problem's other parameters to their
  optimum given it.

Each problem may search a subspace only (``basis``: the directions a leave-one-out subset
identifies); its active coordinates are then removed from that subspace.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

#: Iterations of one refinement.
LM_ITERATIONS = 40
#: Initial damping (relative to the curvature's diagonal).
LM_LAMBDA0 = 1e-3
#: Damping beyond which a problem stops unconverged: 1e8 times the curvature's own scale,
#: a step 1e-8 of the Gauss-Newton one that still does not lower chi^2.
LM_LAMBDA_MAX = 1e8
#: A step below LM_XTOL in the scaled coordinates (1e-6 relative for a log parameter) is nil.
LM_XTOL = 1e-6
#: A decrease of chi^2 below LM_FTOL is nothing to gain (chi^2 is in units of the data's
#: uncertainties squared: a change of 1 is one standard uncertainty, so 1e-3 moves the
#: parameters by ~0.03 of their standard errors; the model TOF's own noise, the sub-step
#: interpolation of its peaks, makes chi^2 jitter by ~1e-5 near chi^2 ~ 1); chi^2 itself
#: below it is an exact fit. Where the misfit exceeds the data's uncertainties (chi^2 per
#: degree of freedom ``c > 1``: weights that are not uncertainties, or a model that does not
#: describe the data) the standard errors scale by ``sqrt(c)`` and so does the chi^2 a step
#: must gain: the tolerance is ``LM_FTOL * max(1, c)`` (:func:`tolerance`), the same
#: fraction of the standard errors, and above the model's noise amplified by the misfit.
LM_FTOL = 1e-3
#: A coordinate within BOUND_TOL (scaled units) of a bound is on it.
BOUND_TOL = 1e-9

#: ``evaluate({i: x}) -> {i: (r, J, cost)}``: weighted residuals (n_i,), their Jacobian in the
#: scaled coordinates (n_i, p) and chi^2 of each problem's point, in one batched model run.
Evaluate = Callable[[dict[int, np.ndarray]], dict[int, tuple[np.ndarray, np.ndarray, float]]]


@dataclass
class Problem:
    """One least-squares problem as Levenberg-Marquardt advances it.

    Parameters
    ----------
    x : numpy.ndarray
        Scaled coordinates (p,) of the continuous parameters.
    r : numpy.ndarray
        Weighted residuals at ``x``.
    J : numpy.ndarray
        Their Jacobian in ``x``, (n, p).
    cost : float
        ``r . r`` (chi^2).
    basis : numpy.ndarray
        (p, q) the directions searched: the identity for a full fit; a subset fit searches
        only what it identifies.
    lam : float
        Nielsen's damping.
    nu_up : float
        Its growth factor after a rejected step.
    done : bool
        Stopped (converged or not).
    converged : bool
        Stopped at a first-order point (module docstring).
    iterations : int
        Trial points evaluated.
    active : numpy.ndarray
        (p,) -1 for a coordinate held on its lower bound, +1 on its upper one, 0 free (the
        last iteration's active set).
    """

    x: np.ndarray
    r: np.ndarray
    J: np.ndarray
    cost: float
    basis: np.ndarray
    lam: float = LM_LAMBDA0
    nu_up: float = 2.0
    done: bool = False
    converged: bool = False
    iterations: int = 0
    active: np.ndarray = field(default_factory=lambda: np.zeros(0, int))


def tolerance(pr: Problem) -> float:
    """The chi^2 a step must gain to count (:data:`LM_FTOL`, scaled by the misfit per
    degree of freedom when it exceeds 1).

    Parameters
    ----------
    pr : Problem
        The problem (its cost, residuals and searched directions).

    Returns
    -------
    float
        -, ``LM_FTOL max(1, cost / dof)`` with ``dof = n - q`` (at least 1); ``LM_FTOL``
        at a non-finite cost.
    """
    dof = max(pr.r.size - pr.basis.shape[1], 1)
    return LM_FTOL * max(1.0, pr.cost / dof) if np.isfinite(pr.cost) else LM_FTOL


def active_set(x: np.ndarray, g: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The coordinates held on a bound: on it (within :data:`BOUND_TOL`) with the gradient
    pointing out of the box.

    Parameters
    ----------
    x : numpy.ndarray
        Scaled coordinates, (p,).
    g : numpy.ndarray
        The gradient of ``chi^2 / 2`` there, ``J^T r`` (p,).
    lo : numpy.ndarray
        Lower bounds, (p,).
    hi : numpy.ndarray
        Upper bounds, (p,).

    Returns
    -------
    numpy.ndarray
        (p,) ints: -1 held on the lower bound, +1 on the upper one, 0 free.
    """
    lower = (x - lo <= BOUND_TOL) & (g > 0)
    upper = (hi - x <= BOUND_TOL) & (g < 0)
    return np.where(lower, -1, np.where(upper, 1, 0))


def free_basis(basis: np.ndarray, active: np.ndarray) -> np.ndarray:
    """The directions of ``basis`` (p, q) that leave the ``active`` coordinates unchanged
    (an orthonormal basis of that subspace, (p, q')).

    Parameters
    ----------
    basis : numpy.ndarray
        (p, q) the directions a problem searches.
    active : numpy.ndarray
        (p,) the active set (:func:`active_set`; nonzero: held on a bound).

    Returns
    -------
    numpy.ndarray
        (p, q') with ``q' <= q``.
    """
    held = active != 0
    if not held.any():
        return basis
    rows = basis[held]
    _, sv, Vt = np.linalg.svd(rows, full_matrices=True)
    rank = int(np.sum(sv > 1e-12 * max(float(sv.max(initial=0.0)), 1.0)))
    B = basis @ Vt[rank:].T
    B[held] = 0.0  # exactly: the held coordinates do not move
    return B


def levenberg_marquardt(problems: list[Problem], evaluate: Evaluate, lo: np.ndarray,
                        hi: np.ndarray, iterations: int = LM_ITERATIONS,
                        prune: Callable[[int, list[Problem]], None] | None = None) -> None:
    """Advance every problem in place by the bounded Levenberg-Marquardt of the module
    docstring; the unfinished problems' trial points go to ``evaluate`` together.

    Parameters
    ----------
    problems : list of Problem
        The problems, each at an admissible start (``lo <= x <= hi``) with its residuals,
        Jacobian and chi^2 there.
    evaluate : callable
        ``evaluate({i: x}) -> {i: (r, J, cost)}`` for the problems' trial points (one
        batched model run).
    lo : numpy.ndarray
        Lower bounds of the scaled coordinates, (p,).
    hi : numpy.ndarray
        Upper bounds, (p,).
    iterations : int
        At most this many evaluations.
    prune : callable, optional
        ``prune(iteration, problems)`` may stop hopeless starts (setting ``done``).

    Notes
    -----
    A problem stops **unconverged** when its damping exceeds :data:`LM_LAMBDA_MAX` (no step
    lowers chi^2 although the linear model says one should: a noisy or discontinuous
    model) or when the iterations run out.
    """
    for it in range(iterations):
        if prune is not None:
            prune(it, problems)
        trial: dict[int, np.ndarray] = {}
        predicted: dict[int, float] = {}
        clipped: dict[int, bool] = {}
        for i, pr in enumerate(problems):
            if pr.done:
                continue
            step = _step(pr, lo, hi)
            if step is None:
                continue
            trial[i], predicted[i], clipped[i] = step
        if not trial:
            return
        for i, (r, J, cost) in evaluate(trial).items():
            pr = problems[i]
            pr.iterations += 1
            if cost < pr.cost:
                gain = pr.cost - cost
                rho = min(gain / max(predicted[i], 1e-300), 1.0)  # capped: no overflow
                pr.x, pr.r, pr.J, pr.cost = trial[i], r, J, cost
                pr.lam = max(pr.lam * max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3), 1e-12)
                pr.nu_up = 2.0
                # a step stopped by a bound gains little and may still be far from the
                # optimum on it: the next iteration decides (the active set changes)
                if (gain <= tolerance(pr) and not clipped[i]) or cost < LM_FTOL:
                    pr.done = pr.converged = True
            else:
                _reject(pr)
    # the iterations ran out: whatever is not done did not converge


def _reject(pr: Problem) -> None:
    """A step that does not lower chi^2: more damping; stalled beyond LM_LAMBDA_MAX."""
    pr.lam *= pr.nu_up
    pr.nu_up *= 2.0
    if pr.lam > LM_LAMBDA_MAX:
        pr.done = True  # stalled: NOT converged


def _step(pr: Problem, lo: np.ndarray, hi: np.ndarray
          ) -> tuple[np.ndarray, float, bool] | None:
    """The problem's projected damped step ``(trial x, predicted chi^2 decrease, whether a
    bound stopped it)``, or None when it stops here (converged, or stalled)."""
    if pr.cost < LM_FTOL:
        pr.done = pr.converged = True  # fitted exactly
        return None
    g_full = pr.J.T @ pr.r
    pr.active = active_set(pr.x, g_full, lo, hi)
    B = free_basis(pr.basis, pr.active)
    if B.shape[1] == 0:
        pr.done = pr.converged = True  # nothing left to search
        return None
    A = pr.J @ B
    H, g = A.T @ A, A.T @ pr.r
    if float(g @ np.linalg.lstsq(H, g, rcond=None)[0]) < tolerance(pr):
        pr.done = pr.converged = True  # even the undamped step gains too little: KKT
        return None
    D = np.diag(np.maximum(np.diag(H), 1e-12))
    try:
        dz = -np.linalg.solve(H + pr.lam * D, g)
    except np.linalg.LinAlgError:
        dz = -g / (np.diag(D) * (1.0 + pr.lam))
    raw = pr.x + B @ dz
    t = np.clip(raw, lo, hi)
    st = t - pr.x
    if float(np.max(np.abs(st), initial=0.0)) < LM_XTOL:
        # nil (shrunk by the damping, or projected away): as a rejected step; the damping
        # turns the step towards the free gradient, which points into the box
        _reject(pr)
        return None
    predicted = -(2.0 * st @ g_full + float(np.sum((pr.J @ st) ** 2)))
    return t, predicted, bool(np.any(t != raw))
