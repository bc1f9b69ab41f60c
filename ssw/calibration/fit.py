"""Least-squares identification of device parameters from measured TOFs on reference samples.

Problem. References ``i`` (known ``E_i``, ``nu_i``; measured ``T_i`` with standard uncertainty
``s_i``) and free parameters ``theta`` of the device: minimize the weighted sum of squares

    ``chi^2(theta) = sum_i ((TOF(E_i, nu_i; theta) - T_i) / s_i)^2``.

TOF is not monotone in the parameters (REFERENCE.md: TOF rises then falls with the striker
speed under gravity), so no bracketing is assumed:

1. **global scan**: a tensor grid of the continuous parameters (log-spaced where a parameter
   is scaled, :data:`ssw.device.PARAMETERS`) times every value of the integer ones, all
   evaluated in batched runs (:class:`ssw.calibration.model.TofModel`); every grid local
   minimum of ``chi^2`` is a start;
2. **local refinement**: Levenberg-Marquardt (Marquardt 1963; Nocedal & Wright 2006,
   sec. 10.3) in the scaled coordinates ``x`` (``ln theta`` or ``theta / scale``), forward
   differences for the Jacobian; the starts of every problem (the full set and each
   leave-one-out subset) advance together, one batched run per iteration;
3. **result**: the best solution; other solutions with ``chi^2`` within 1 of it are listed
   (the data do not choose between them); on a tie the one nearest the device's nominal
   values is taken.

Uncertainty (Bard 1974; Press et al. 2007, sec. 15.5): with the weighted Jacobian ``J``
(central differences at the solution) the parameter covariance is ``(J^T J)^-1``; when no
TOF uncertainty is given, the weights are ``1 / (1 % of T_i)`` and the covariance is scaled
by the residual variance ``chi^2 / (n - p)`` (none when ``n = p``). The singular values of
``J`` in the scaled coordinates say what the data identify: a direction ``v`` with a small
singular value ``sigma`` moves the TOFs by one standard uncertainty only when the parameters
move by ``1/sigma`` along ``v`` (scaled units), i.e. the data cannot separate the
parameters mixed in ``v``; below 1 (more than an e-fold) the calibration says so and gives
no standard errors (:data:`IDENTIFIED_MIN`).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ssw.calibration.model import Reference, TofModel
from ssw.device import parameter, parameter_value
from ssw.errors import ConfigError, SolverError

#: Grid points per continuous parameter: this many for one, fewer for several (product cap).
SCAN_POINTS_1D = 32
SCAN_BUDGET = 144
#: Local minima of the scan refined per problem.
STARTS = 4
#: After PRUNE_AFTER iterations a start stops when its chi^2 exceeds its problem's best by
#: more than PRUNE_CHI2 (a basin that far worse is no candidate: the alternatives reported
#: are those within chi^2 + 1).
PRUNE_AFTER, PRUNE_CHI2 = 4, 10.0
#: Relative step of the forward-difference Jacobian in the scaled coordinates.
FD_STEP = 1e-3
#: Levenberg-Marquardt: iterations, initial damping, convergence tolerances: a step below
#: LM_XTOL in the scaled coordinates (1e-6 relative for a log parameter), or a decrease of
#: chi^2 below LM_FTOL (chi^2 is in units of the TOF uncertainties squared: a change of 1
#: is one standard uncertainty, so 1e-3 moves the parameters by ~0.03 of their standard
#: errors; the model TOF's own noise, the sub-step interpolation of its peaks, makes chi^2
#: jitter by ~1e-5 near chi^2 ~ 1), or chi^2 itself below LM_FTOL (an exact fit).
LM_ITERATIONS = 40
LM_LAMBDA0 = 1e-3
#: Damping beyond which a problem stops unconverged: 1e8 times the curvature's own scale,
#: a step 1e-8 of the Gauss-Newton one that still does not lower chi^2.
LM_LAMBDA_MAX = 1e8
LM_XTOL = 1e-6
LM_FTOL = 1e-3
#: Relative TOF weight when no uncertainty is given (covariance rescaled by chi^2/(n-p)).
DEFAULT_REL_STD = 0.01
#: Solutions count as distinct when a scaled coordinate differs by more than this (5 % of
#: a log-scanned parameter, 0.05 x the scale of another).
DISTINCT = 0.05
#: A direction counts as not identified when its singular value (of the Jacobian weighted
#: by the TOF uncertainties, in the scaled coordinates) is below IDENTIFIED_MIN: the data
#: then tolerate, within one standard uncertainty, a change of more than one e-fold of a
#: log-scaled parameter (one ``scale`` of another) along it; or below IDENTIFIED_RATIO of
#: the largest one (numerically rank deficient).
IDENTIFIED_MIN = 1.0
IDENTIFIED_RATIO = 1e-3


# --------------------------------------------------------------------- coordinates
def to_x(theta: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """Scaled coordinates of parameter values (columns in ``names`` order)."""
    th = np.asarray(theta, float)
    out = np.empty_like(th)
    for j, n in enumerate(names):
        p = parameter(n)
        out[..., j] = np.log(th[..., j]) if p.log else th[..., j] / p.scale
    return out


def from_x(x: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """Parameter values (SI) of scaled coordinates."""
    xx = np.asarray(x, float)
    out = np.empty_like(xx)
    for j, n in enumerate(names):
        p = parameter(n)
        out[..., j] = np.exp(xx[..., j]) if p.log else xx[..., j] * p.scale
    return out


def dtheta_dx(theta: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """``d theta / d x`` per parameter (theta for log coordinates, scale otherwise)."""
    return np.array([theta[j] if parameter(n).log else parameter(n).scale
                     for j, n in enumerate(names)])


def bounds_x(names: tuple[str, ...], ranges: dict[str, tuple[float, float]]
             ) -> tuple[np.ndarray, np.ndarray]:
    lo = np.array([ranges[n][0] for n in names], float)
    hi = np.array([ranges[n][1] for n in names], float)
    return to_x(lo, names), to_x(hi, names)


def fd_pair(x: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two points of a central difference of step :data:`FD_STEP` per scaled
    coordinate, ``x -+ FD_STEP``, shifted (same spacing) to stay inside ``[lo, hi]``: a
    solution on a bound (a preload of 0 N) is differentiated one-sidedly instead of at an
    inadmissible value."""
    a = np.asarray(x, float) - FD_STEP
    b = np.asarray(x, float) + FD_STEP
    below, above = a < lo, b > hi
    a = np.where(below, lo, np.where(above, hi - 2 * FD_STEP, a))
    b = np.where(below, lo + 2 * FD_STEP, np.where(above, hi, b))
    return a, b


def scan_ranges(free: tuple[str, ...], overrides: dict[str, tuple[float, float]] | None,
                device: Any = None) -> dict[str, tuple[float, float]]:
    """The scan range of each free parameter (defaults of :data:`ssw.device.PARAMETERS`;
    the bead count starts where the device's beads below the sensor still leave a sensor
    with a bead above it)."""
    out = {}
    for n in free:
        p = parameter(n)
        lo, hi = (overrides or {}).get(n, (p.lower, p.upper))
        if n == "beads" and device is not None and n not in (overrides or {}):
            lo = max(lo, device.beads_below_sensor + 2)
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi) or (p.log and lo <= 0) or (
                n == "preload" and lo < 0):
            raise ConfigError(f"--range {n}", f"{lo}:{hi}",
                              "LO:HI with LO < HI (LO > 0 for a log-scanned parameter)")
        out[n] = (float(lo), float(hi))
    return out


# --------------------------------------------------------------------- results
@dataclass(frozen=True)
class Solution:
    """One local least-squares solution of one problem (a subset of the references)."""

    refs: tuple[int, ...]
    theta: np.ndarray  # SI, model.free order
    chi2: float
    tof_model: np.ndarray  # s, at the subset's references
    converged: bool
    iterations: int


@dataclass(frozen=True)
class Fit:
    """The identification on all references, its uncertainty and the alternatives."""

    names: tuple[str, ...]
    theta: np.ndarray
    chi2: float
    tof_model: np.ndarray
    residuals: np.ndarray  # s, model - measured
    weights_known: bool
    covariance: np.ndarray | None  # SI, (p, p); None if not estimable
    std: np.ndarray | None  # SI
    singular_values: np.ndarray  # of the weighted Jacobian in scaled coordinates
    singular_vectors: np.ndarray  # (p, p), columns: right singular vectors
    jacobian: np.ndarray  # (n, p) d TOF / d theta, s per SI unit
    unidentified: tuple[str, ...]  # texts: directions the data cannot pin
    alternatives: tuple[dict[str, float], ...]  # other solutions within chi^2 + 1
    converged: bool
    scan_points: int
    evaluations: int
    runs: int
    at_bound: tuple[str, ...] = ()  # continuous parameters on a bound of their range
    tof_range: np.ndarray | None = None  # (n, 2) s: the TOFs the scan's device can give


# --------------------------------------------------------------------- scan
def scan_grid(model: TofModel, ranges: dict[str, tuple[float, float]],
              points: int | None = None) -> tuple[np.ndarray, list[np.ndarray]]:
    """The scan's parameter sets (m, p) in ``model.free`` order, and each axis's values."""
    cont, ints = model.continuous, model.integers
    n = points or (SCAN_POINTS_1D if len(cont) == 1 else
                   max(6, int(np.floor(SCAN_BUDGET ** (1.0 / max(len(cont), 1))))))
    axes: dict[str, np.ndarray] = {}
    for name in cont:
        lo, hi = ranges[name]
        axes[name] = (np.geomspace(lo, hi, n) if parameter(name).log else np.linspace(lo, hi, n))
    for name in ints:
        lo, hi = ranges[name]
        axes[name] = np.arange(int(np.ceil(lo)), int(np.floor(hi)) + 1, dtype=float)
    grid = np.array(list(itertools.product(*(axes[nm] for nm in model.free))), float)
    return grid, [axes[nm] for nm in model.free]


def _chi2(tof: np.ndarray, refs: np.ndarray, T: np.ndarray, s: np.ndarray) -> np.ndarray:
    r = (tof[:, refs] - T[refs]) / s[refs]
    c = np.sum(r**2, axis=1)
    return np.where(np.all(np.isfinite(r), axis=1), c, np.inf)


def _grid_minima(cost: np.ndarray, shape: tuple[int, ...], n_best: int) -> np.ndarray:
    """Indices (flat) of the grid's local minima (<= every axis neighbour), best first."""
    c = cost.reshape(shape)
    is_min = np.isfinite(c)
    for ax in range(c.ndim):
        if shape[ax] < 2:
            continue
        pad = [(0, 0)] * c.ndim
        pad[ax] = (1, 1)
        cp = np.pad(c, pad, constant_values=np.inf)
        lo = np.take(cp, range(0, shape[ax]), axis=ax)
        hi = np.take(cp, range(2, shape[ax] + 2), axis=ax)
        is_min &= (c <= lo) & (c <= hi)
    idx = np.flatnonzero(is_min.ravel())
    idx = idx[np.argsort(cost[idx])]
    return idx[:n_best]


# --------------------------------------------------------------------- refinement
@dataclass
class _Problem:
    """One least-squares problem as Levenberg-Marquardt advances it.

    ``x`` (p,) scaled coordinates of the continuous parameters; ``r`` weighted residuals,
    ``J`` their Jacobian in ``x`` (n_sub, p), ``cost`` = r.r; ``basis`` (p, q): the
    directions searched (the identity for a full fit; a subset fit searches only what it
    identifies); ``lam``/``nu_up``: Nielsen's damping and its growth factor.
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


def _levenberg_marquardt(problems: list[_Problem], evaluate: Any, lo: np.ndarray,
                         hi: np.ndarray, iterations: int, prune: Any = None) -> None:
    """Advance every problem in place by Levenberg-Marquardt (Marquardt 1963; Nocedal &
    Wright 2006, sec. 10.3) with Nielsen's damping update (Madsen, Nielsen & Tingleff 2004,
    eq. 2.21), steps clipped to ``[lo, hi]``; the unfinished problems' trial points go to
    ``evaluate({i: x}) -> {i: (r, J, cost)}`` together (one batched model run).

    A problem is **converged** when the undamped Gauss-Newton step along its basis would
    gain less than :data:`LM_FTOL` in chi^2 (the first-order optimality test: at a minimum),
    when a bound stops the step, when an accepted step gains less than that, or when chi^2
    itself is below it (an exact fit). It **stops unconverged** when its damping exceeds
    :data:`LM_LAMBDA_MAX` (no step along the gradient lowers chi^2 although the linear
    model says one should: a noisy or discontinuous model) or when the iterations run
    out. ``prune(iteration, problems)`` may stop hopeless starts.
    """
    for it in range(iterations):
        if prune is not None:
            prune(it, problems)
        trial: dict[int, np.ndarray] = {}
        predicted: dict[int, float] = {}
        for i, pr in enumerate(problems):
            if pr.done:
                continue
            if pr.basis.shape[1] == 0 or pr.cost < LM_FTOL:
                pr.done = pr.converged = True  # nothing to search, or fitted exactly
                continue
            A = pr.J @ pr.basis
            H, g = A.T @ A, A.T @ pr.r
            if float(g @ np.linalg.lstsq(H, g, rcond=None)[0]) < LM_FTOL:
                pr.done = pr.converged = True  # even the undamped step gains too little
                continue
            D = np.diag(np.maximum(np.diag(H), 1e-12))
            try:
                dz = -np.linalg.solve(H + pr.lam * D, g)
            except np.linalg.LinAlgError:
                dz = -g / (np.diag(D) * (1.0 + pr.lam))
            raw = pr.x + pr.basis @ dz
            t = np.clip(raw, lo, hi)
            if float(np.max(np.abs(t - pr.x), initial=0.0)) < LM_XTOL:
                if float(np.max(np.abs(raw - pr.x), initial=0.0)) >= LM_XTOL:
                    pr.done = pr.converged = True  # the step is nil: held by a bound
                    continue
                # the damping has shrunk the step to nothing: as a rejected step
                pr.lam *= pr.nu_up
                pr.nu_up *= 2.0
                pr.done = pr.lam > LM_LAMBDA_MAX  # stalled: NOT converged
                continue
            st = np.linalg.lstsq(pr.basis, t - pr.x, rcond=None)[0]  # the clipped step
            trial[i] = t
            predicted[i] = -(2.0 * st @ g + st @ H @ st)  # chi^2 decrease it predicts
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
                if gain <= LM_FTOL or cost < LM_FTOL:
                    pr.done = pr.converged = True
            else:
                pr.lam *= pr.nu_up
                pr.nu_up *= 2.0
                if pr.lam > LM_LAMBDA_MAX:
                    pr.done = True  # stalled: NOT converged
    # the iterations ran out: whatever is not done did not converge


def _lm_batch(model: TofModel, T: np.ndarray, s: np.ndarray,
              problems: list[tuple[tuple[int, ...], np.ndarray, np.ndarray]],
              ranges: dict[str, tuple[float, float]]) -> list[Solution]:
    """Every (refs, x0 of the continuous parameters, integer values) start refined at once
    (:func:`_levenberg_marquardt`): each iteration evaluates every unfinished start's trial
    point and its forward-difference Jacobian (backward on an upper bound: every point
    stays admissible) in one batched model call."""
    cont, ints = model.continuous, model.integers
    p = len(cont)
    lo, hi = bounds_x(cont, ranges)
    fixed = [pr[2] for pr in problems]
    refs = [np.asarray(pr[0], int) for pr in problems]

    def evaluate(points: dict[int, np.ndarray]) -> dict[int, tuple]:
        rows, steps = [], {}
        for i, xi in points.items():
            steps[i] = np.where(xi + FD_STEP > hi, -FD_STEP, FD_STEP)
            for pt in [xi] + [xi + steps[i][j] * np.eye(p)[j] for j in range(p)]:
                rows.append(np.concatenate([from_x(pt, cont), fixed[i]]))
        tof = model(_order(np.array(rows), cont, ints, model.free))
        out, k = {}, 0
        for i in points:
            block = tof[k:k + p + 1][:, refs[i]]
            k += p + 1
            r = (block[0] - T[refs[i]]) / s[refs[i]]
            J = ((block[1:] - block[0]) / s[refs[i]]).T / steps[i][None, :]
            ok = np.all(np.isfinite(r)) and np.all(np.isfinite(J))
            out[i] = (r, J if ok else np.zeros_like(J), float(r @ r) if ok else np.inf)
        return out

    x0 = {i: np.asarray(pr[1], float).reshape(p) for i, pr in enumerate(problems)}
    start = evaluate(x0)
    probs = [_Problem(x0[i], *start[i], np.eye(p)) for i in range(len(problems))]
    for pr in probs:
        pr.done = not np.isfinite(pr.cost)  # a start on a failing corner: dropped
    keys = [tuple(rf.tolist()) for rf in refs]

    def prune(it: int, ps: list[_Problem]) -> None:
        if it < PRUNE_AFTER:
            return
        best: dict[tuple, float] = {}
        for k_, pr in zip(keys, ps, strict=True):
            best[k_] = min(best.get(k_, np.inf), pr.cost)
        for k_, pr in zip(keys, ps, strict=True):
            if not pr.done and pr.cost > best[k_] + PRUNE_CHI2:
                pr.done = True  # a basin that much worse is no candidate

    _levenberg_marquardt(probs, evaluate, lo, hi, LM_ITERATIONS, prune)
    out = []
    for i, pr in enumerate(probs):
        theta = _order(np.concatenate([from_x(pr.x, cont), fixed[i]])[None, :], cont, ints,
                       model.free)[0]
        tof = (T[refs[i]] + s[refs[i]] * pr.r if np.isfinite(pr.cost)
               else np.full(len(refs[i]), np.nan))
        out.append(Solution(tuple(int(j) for j in refs[i]), theta, float(pr.cost), tof,
                            pr.converged, pr.iterations))
    return out


def _order(rows: np.ndarray, cont: tuple[str, ...], ints: tuple[str, ...],
           free: tuple[str, ...]) -> np.ndarray:
    """Columns (continuous..., integer...) reordered to ``free``."""
    names = list(cont) + list(ints)
    return rows[:, [names.index(n) for n in free]]


def _starts(model: TofModel, grid: np.ndarray, axes: list[np.ndarray], tof: np.ndarray,
            refs: tuple[int, ...], T: np.ndarray, s: np.ndarray, nominal: np.ndarray,
            ranges: dict[str, tuple[float, float]]) -> list[tuple[np.ndarray, np.ndarray]]:
    """(x of the continuous parameters, integer values) starts of one problem: for each
    value of the integer parameters whose best grid point is within PRUNE_CHI2 of the
    scan's best, the local minima of its continuous grid; and the device's nominal values
    (with the best integer values)."""
    cont_idx = [model.free.index(n) for n in model.continuous]
    int_idx = [model.free.index(n) for n in model.integers]
    cost = _chi2(tof, np.asarray(refs), T, s)
    starts = []
    cont_shape = tuple(axes[j].size for j in cont_idx)
    ints = grid[:, int_idx]
    combos = np.unique(ints, axis=0) if int_idx else np.zeros((1, 0))
    best_all = float(np.min(cost)) if np.isfinite(cost).any() else np.inf
    for combo in combos:
        rows = np.flatnonzero(np.all(ints == combo, axis=1))
        sub = cost[rows]
        if not np.isfinite(sub).any() or float(np.min(sub)) > best_all + PRUNE_CHI2:
            continue
        # the grid is a product with the integer axes last-varying or not: rebuild the
        # continuous sub-grid by sorting its rows lexicographically
        order = np.lexsort(grid[rows][:, cont_idx].T[::-1]) if cont_idx else np.arange(1)
        for flat in _grid_minima(sub[order], cont_shape, STARTS):
            th = grid[rows[order[flat]]]
            starts.append((to_x(th[cont_idx], model.continuous), th[int_idx]))
    lo, hi = bounds_x(model.continuous, ranges)
    nom_x = np.clip(to_x(nominal[cont_idx], model.continuous), lo, hi)
    best = grid[int(np.argmin(cost))] if np.isfinite(cost).any() else nominal
    starts.append((nom_x, best[int_idx]))
    return starts


def _pick(sols: list[Solution], nominal_x: np.ndarray, model: TofModel
          ) -> tuple[Solution, list[Solution]]:
    """The best solution (ties within LM_FTOL of the least chi^2 go to the one nearest the
    nominal values) and the distinct others within chi^2 + 1."""
    finite = [so for so in sols if np.isfinite(so.chi2)]
    if not finite:
        raise SolverError("no parameter set of the scan gives a TOF on every reference: widen "
                          "the ranges (--range) or check the references")
    best_c = min(so.chi2 for so in finite)
    # solutions the refinement cannot tell apart (chi^2 within its convergence tolerance,
    # e.g. the two roots of a non-monotone TOF fitted exactly) go to the nominal's nearest
    ties = [so for so in finite if so.chi2 <= best_c + LM_FTOL]

    def dist(so: Solution) -> float:
        return float(np.linalg.norm(to_x(so.theta, model.free) - nominal_x))

    best = min(ties, key=dist)
    others = []
    for so in sorted(finite, key=lambda q: q.chi2):
        if so is best or so.chi2 > best.chi2 + 1.0:
            continue
        xs = to_x(so.theta, model.free)
        if all(np.max(np.abs(xs - to_x(o.theta, model.free))) > DISTINCT
               for o in [best, *others]):
            others.append(so)
    return best, others


# --------------------------------------------------------------------- public
@dataclass(frozen=True)
class SubsetFit:
    """A calibration on a subset of the references (a leave-one-out fit).

    ``theta``: its values (SI); ``chi2``; ``singular_values`` of the subset's weighted
    Jacobian at ``theta`` (scaled coordinates); ``identified``: every one >= the floor
    (:data:`IDENTIFIED_MIN`) there.
    """

    refs: tuple[int, ...]
    theta: np.ndarray
    chi2: float
    identified: bool
    singular_values: np.ndarray
    iterations: int


def refine_subsets(model: TofModel, T: np.ndarray, s: np.ndarray, start: np.ndarray,
                   subsets: list[tuple[int, ...]], ranges: dict[str, tuple[float, float]],
                   iterations: int = 16,
                   at_start: tuple[np.ndarray, np.ndarray] | None = None,
                   ) -> dict[tuple[int, ...], SubsetFit]:
    """Fits of subsets of the references, from ``start`` (the full calibration, SI): the
    subset's least squares within the directions it identifies AT ``start`` (right singular
    vectors of its weighted Jacobian there with singular values >= :data:`IDENTIFIED_MIN`;
    Hansen 1998, truncated SVD), the others held at ``start``'s values. Where the subset
    identifies every parameter this is its least-squares solution; where it does not (a
    valley of near-exact fits), the point that differs from the full calibration only in
    what the subset can tell, a well-defined answer instead of an arbitrary point of the
    valley. Levenberg-Marquardt in the identified coordinates (Nielsen's damping update, as
    in the main fit: a near-singular Jacobian along a curved valley cannot throw a step
    across the range), a step that raises chi^2 rejected, the best point returned; all
    subsets advance together, one batched run (central differences) per iteration.
    ``at_start``: the model's TOFs (s, every reference) and their central-difference
    Jacobian (s per scaled unit, ``model.continuous`` columns) at ``start`` when already
    computed (``_uncertainty``), so that they are not computed again."""
    cont = model.continuous
    idx = [model.free.index(n) for n in cont]
    p = len(cont)
    lo, hi = bounds_x(cont, ranges)
    x0 = to_x(start[idx], cont)

    def evaluate(points: dict[tuple[int, ...], np.ndarray]
                 ) -> dict[tuple[int, ...], tuple[np.ndarray, np.ndarray, float]]:
        """Weighted residuals, Jacobian (per scaled unit) and chi^2 of each subset's point."""
        rows = []
        for xk in points.values():
            a, b = fd_pair(xk, lo, hi)
            pts = [xk]
            for j in range(p):
                for end in (b, a):
                    pt = xk.copy()
                    pt[j] = end[j]
                    pts.append(pt)
            for pt in pts:
                th = start.copy()
                th[idx] = from_x(pt, cont)
                rows.append(th)
        tof = model(np.array(rows))
        out = {}
        for k, key in enumerate(points):
            blk = tof[k * (1 + 2 * p):(k + 1) * (1 + 2 * p)]
            Jx = np.stack([(blk[1 + 2 * j] - blk[2 + 2 * j]) / (2 * FD_STEP)
                           for j in range(p)], axis=1)  # (n_refs, p), s per scaled unit
            out[key] = weigh(key, blk[0], Jx)
        return out

    def weigh(key: tuple[int, ...], f0: np.ndarray, Jx: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, float]:
        sub = np.asarray(key)
        r = (f0[sub] - T[sub]) / s[sub]
        ok = np.all(np.isfinite(r)) and np.all(np.isfinite(Jx[sub]))
        return r, Jx[sub] / s[sub, None], float(r @ r) if ok else np.inf

    cur = ({key: v for key, v in evaluate({key: x0.copy() for key in subsets}).items()}
           if at_start is None else {key: weigh(key, *at_start) for key in subsets})
    probs = []
    for key in subsets:
        r, Jw, chi2 = cur[key]
        _, sv, Vt = np.linalg.svd(Jw, full_matrices=False)
        floor = max(IDENTIFIED_MIN, IDENTIFIED_RATIO * float(sv.max(initial=0.0)))
        # the identified directions at the start: searched; the others stay at `start`
        probs.append(_Problem(x0.copy(), r, Jw, chi2, Vt[sv >= floor].T))

    def evaluate_idx(points: dict[int, np.ndarray]) -> dict[int, tuple]:
        res = evaluate({subsets[i]: xi for i, xi in points.items()})
        return {i: res[subsets[i]] for i in points}

    _levenberg_marquardt(probs, evaluate_idx, lo, hi, iterations)
    x = {key: pr.x for key, pr in zip(subsets, probs, strict=True)}
    cur = {key: (pr.r, pr.J, pr.cost) for key, pr in zip(subsets, probs, strict=True)}
    its = {key: pr.iterations for key, pr in zip(subsets, probs, strict=True)}
    out = {}
    for key in subsets:
        r, Jw, chi2 = cur[key]
        sv_ = np.linalg.svd(Jw, compute_uv=False)
        svf = np.zeros(p)
        svf[: sv_.size] = sv_
        floor = max(IDENTIFIED_MIN, IDENTIFIED_RATIO * float(svf.max(initial=0.0)))
        theta = start.copy()
        theta[idx] = from_x(x[key], cont)
        out[key] = SubsetFit(key, theta, chi2, bool(np.all(svf >= floor)), svf, its[key])
    return out


def identify(
    model: TofModel, refs: list[Reference], *, ranges: dict[str, tuple[float, float]] | None = None,
    subsets: list[tuple[int, ...]] | None = None, scan_points: int | None = None,
) -> tuple[Fit, dict[tuple[int, ...], SubsetFit]]:
    """Identify ``model.free`` from ``refs`` (scan, then Levenberg-Marquardt); also fit each
    subset of ``subsets`` (indices of ``refs``, e.g. the leave-one-out sets) as the smallest
    change of that calibration (:func:`refine_subsets`).
    """
    if len(refs) != model.n_refs:
        raise ValueError("references and model disagree")
    T = np.array([r.tof for r in refs])
    given = [r.tof_std is not None for r in refs]
    if any(given) and not all(given):
        raise ConfigError("references", [r.id or i for i, r in enumerate(refs)
                                         if r.tof_std is None],
                          "a TOF uncertainty for every reference or for none (these have "
                          "none; the others do): weights of two kinds cannot be combined")
    known = all(given)
    s = np.array([r.tof_std if known else DEFAULT_REL_STD * r.tof for r in refs], float)
    rng = scan_ranges(model.free, ranges, model.device)
    nominal = np.array([parameter_value(model.device, n) for n in model.free])
    for j, n in enumerate(model.free):  # the nominal start inside the scan
        nominal[j] = np.clip(nominal[j], *rng[n])
    model.fix_time_step(rng)
    grid, axes = scan_grid(model, rng, scan_points)
    tof = model(grid)
    tof_range = check_producible(refs, tof, rng)
    key = tuple(range(len(refs)))
    problems = [(key, x0, fixed) for x0, fixed in
                _starts(model, grid, axes, tof, key, T, s, nominal, rng)]
    # the refinement's step: near the candidates (2x their fastest striker), not the scan's
    # fastest striker; one step for every run from here on
    cont = model.continuous
    model.refix_time_step(np.array([_order(np.concatenate([from_x(x0, cont), fx])[None, :],
                                           cont, model.integers, model.free)[0]
                                    for _, x0, fx in problems]), rng)
    sols = _lm_batch(model, T, s, problems, rng)
    best, others = _pick(sols, to_x(nominal, model.free), model)
    fit = _uncertainty(model, refs, T, s, known, best, others, rng, grid.shape[0])
    fit = replace(fit, tof_range=tof_range)
    if not subsets:
        return fit, {}
    D = dtheta_dx(fit.theta[[model.free.index(n) for n in cont]], cont)
    subs = refine_subsets(model, T, s, best.theta, list(subsets), rng,
                          at_start=(fit.tof_model, fit.jacobian * D[None, :]))
    return fit, subs


def _uncertainty(model: TofModel, refs: list[Reference], T: np.ndarray, s: np.ndarray,
                 known: bool, best: Solution, others: list[Solution],
                 ranges: dict[str, tuple[float, float]], scan_points: int) -> Fit:
    """Central-difference Jacobian at the solution, covariance, singular values."""
    names = model.free
    cont_idx = [names.index(n) for n in model.continuous]
    p = len(cont_idx)
    n = len(refs)
    x0 = to_x(best.theta, names)
    lo, hi = bounds_x(model.continuous, ranges)
    a, b = fd_pair(x0[cont_idx], lo, hi)
    rows = [best.theta]
    for k, j in enumerate(cont_idx):
        for end in (b, a):
            xx = x0.copy()
            xx[j] = end[k]
            rows.append(from_x(xx, names))
    for j, nm in enumerate(names):  # integers: exact values
        if parameter(nm).kind == "integer":
            for r_ in rows:
                r_[j] = best.theta[j]
    tof = model(np.array(rows))
    f0 = tof[0]
    Jx = np.zeros((n, p))
    for k in range(p):
        Jx[:, k] = (tof[1 + 2 * k] - tof[2 + 2 * k]) / (2.0 * FD_STEP)
    Jw = Jx / s[:, None]
    if p:
        _, sv, Vt = np.linalg.svd(Jw, full_matrices=True)
        sv_full = np.zeros(p)
        sv_full[: sv.size] = sv
        V = Vt.T
    else:
        sv_full, V = np.zeros(0), np.zeros((0, 0))
    D = dtheta_dx(best.theta[cont_idx], model.continuous) if p else np.zeros(0)
    J_theta = Jx / D[None, :] if p else Jx
    resid = f0 - T
    chi2 = float(np.sum((resid / s) ** 2))
    cov = std = None
    smax = float(sv_full.max()) if p else 0.0
    floor = max(IDENTIFIED_MIN, IDENTIFIED_RATIO * smax)
    identified = p > 0 and n >= p and smax > 0 and float(sv_full.min()) >= floor
    if identified:
        cov_x = V @ np.diag(1.0 / sv_full**2) @ V.T
        if not known:
            cov_x = cov_x * chi2 / (n - p) if n > p else None
        if cov_x is not None:
            cov = D[:, None] * cov_x * D[None, :]
            std = np.sqrt(np.diag(cov))
    unid = []
    for k in range(p):
        if sv_full[k] < floor or k >= n:
            v = V[:, k]
            terms = " ".join(f"{v[j]:+.2f} {_coord(model.continuous[j])}"
                             for j in range(p) if abs(v[j]) > 0.2)
            unid.append(f"direction {terms} (singular value {sv_full[k]:.3g}): the data "
                        "cannot separate these parameters")
    alts = tuple({nm: float(v) for nm, v in zip(names, so.theta, strict=True)}
                 | {"chi2": so.chi2} for so in others)
    # on a bound: within one difference step of it (what the derivatives resolve); a
    # legitimate answer (a device without static load), differentiated one-sidedly
    on_bound = tuple(n for k, n in enumerate(model.continuous)
                     if min(x0[cont_idx][k] - lo[k], hi[k] - x0[cont_idx][k]) <= FD_STEP)
    return Fit(names, best.theta, chi2, f0, resid, known, cov, std, sv_full, V, J_theta,
               tuple(unid), alts, best.converged, scan_points, model.evaluations, model.runs,
               on_bound)


def _coord(name: str) -> str:
    p = parameter(name)
    return f"ln({name})" if p.log else f"{name}/{p.scale:g} {p.unit}"


#: Margin of the producible TOF range: a reference up to this fraction beyond the scan's
#: extremes may still be reached between its grid points or just past its ranges' corners.
PRODUCIBLE_MARGIN = 0.05
#: Quantile of chi^2 beyond which the misfit is refused (with given TOF uncertainties).
CHI2_QUANTILE = 0.999


def check_producible(refs: list[Reference], tof: np.ndarray,
                     ranges: dict[str, tuple[float, float]]) -> np.ndarray:
    """The TOF range (s, (n, 2)) the scanned device gives on each reference; CalibrationError
    naming every reference whose measured TOF lies outside it (by more than
    :data:`PRODUCIBLE_MARGIN`): no parameter within the ranges can fit it (a TOF in ms typed
    as s, a wrong sample, a device unlike the one described)."""
    from ssw.errors import CalibrationError

    ok = np.isfinite(tof)
    lo = np.array([np.min(tof[ok[:, j], j]) if ok[:, j].any() else np.nan
                   for j in range(len(refs))])
    hi = np.array([np.max(tof[ok[:, j], j]) if ok[:, j].any() else np.nan
                   for j in range(len(refs))])
    bad = []
    for j, r in enumerate(refs):
        if not np.isfinite(lo[j]):
            bad.append(f"reference {r.id or j}: no parameter set of the ranges gives a TOF on "
                       f"it (E {r.E:.4g} Pa, nu {r.nu:g})")
        elif not lo[j] * (1 - PRODUCIBLE_MARGIN) <= r.tof <= hi[j] * (1 + PRODUCIBLE_MARGIN):
            bad.append(f"reference {r.id or j}: TOF = {r.tof:.6g} s is outside what the device "
                       f"can produce on it, [{lo[j]:.4g}, {hi[j]:.4g}] s")
    if bad:
        span = ", ".join(f"{n} {a:.4g}..{b:.4g}" for n, (a, b) in ranges.items())
        raise CalibrationError("; ".join(bad) + f" (over the parameter ranges {span}; "
                               "TOFs are in seconds)")
    return np.stack([lo, hi], axis=1)


def check_fit(fit: Fit, n: int) -> list[str]:
    """Why a fit cannot be trusted (empty: it can): not converged, parameters the references
    do not identify, chi^2 beyond its :data:`CHI2_QUANTILE` quantile for ``n - p`` degrees
    of freedom (with given TOF uncertainties), a covariance that is not finite and positive
    definite."""
    from scipy.special import chdtri  # chi^2 inverse survival function (scipy.stats is
    # a 0.8 s import for this one number)

    out = []
    if not fit.converged:
        out.append("the least squares did not converge (Levenberg-Marquardt stalled or ran "
                   "out of iterations)")
    if fit.unidentified:
        out.append("the references do not identify every free parameter: "
                   + "; ".join(fit.unidentified) + " (free fewer parameters, or add "
                   "references that tell them apart)")
    p = int(fit.singular_values.size)
    if fit.weights_known and n > p:
        limit = float(chdtri(n - p, 1.0 - CHI2_QUANTILE))
        if fit.chi2 > limit:
            out.append(f"chi^2 = {fit.chi2:.4g} exceeds its {CHI2_QUANTILE:.1%} quantile "
                       f"{limit:.4g} for {n - p} degrees of freedom: the model cannot fit the "
                       "references within their uncertainties (residuals "
                       + ", ".join(f"{x:+.3g} s" for x in fit.residuals) + ")")
    if fit.covariance is not None:
        C = np.asarray(fit.covariance, float)
        if not np.all(np.isfinite(C)) or np.any(np.linalg.eigvalsh(0.5 * (C + C.T)) <= 0):
            out.append("the covariance is not finite and positive definite")
    return out


def leave_one_out_sets(n: int) -> list[tuple[int, ...]]:
    """Every subset of ``range(n)`` without one element (none for n < 2)."""
    return [tuple(j for j in range(n) if j != i) for i in range(n)] if n >= 2 else []


def theta_dict(names: tuple[str, ...], theta: np.ndarray) -> dict[str, Any]:
    """Named values, integers as ints."""
    return {n: (round(float(v)) if parameter(n).kind == "integer" else float(v))
            for n, v in zip(names, theta, strict=True)}
