"""The global scan of a TOF calibration (:mod:`ssw.calibration.fit`): each free
parameter's range (:func:`scan_ranges`), the tensor grid evaluated in batched runs
(:func:`scan_grid`), its local minima as starts (``_starts``), the batched
bounded Levenberg-Marquardt of every problem's starts (``_lm_batch``,
:class:`Solution`) and the pick among the solutions (``_pick``).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.calibration.lm import LM_FTOL, LM_ITERATIONS, Problem, levenberg_marquardt
from ssw.calibration.model import TofModel
from ssw.calibration.residuals import (
    Derivatives,
    Observations,
    bounds_x,
    dtheta_dx,
    from_x,
    to_x,
)
from ssw.device import parameter
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
#: Solutions count as distinct when a scaled coordinate differs by more than this (5 % of
#: a log-scanned parameter, 0.05 x the scale of another).
DISTINCT = 0.05


def scan_ranges(free: tuple[str, ...], overrides: dict[str, tuple[float, float]] | None,
                device: Any = None) -> dict[str, tuple[float, float]]:
    """The scan range of each free parameter (defaults of :data:`ssw.device.PARAMETERS`;
    the bead count starts where the device's beads below the sensor still leave a sensor
    with a bead above it).

    Parameters
    ----------
    free : tuple of str
        The free parameters' names.
    overrides : dict of str to tuple of float or None
        ``(lo, hi)`` per parameter replacing its default range, in its SI unit.
    device : ssw.device.Device or None
        The nominal device (the bead count's lower end).

    Returns
    -------
    dict of str to tuple of float
        ``(lo, hi)`` per free parameter, SI.

    Raises
    ------
    ssw.errors.ConfigError
        A range that is not ``LO < HI`` (``LO > 0`` when log-scanned; preload >= 0).
    """
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
    """One local least-squares solution of one problem (a subset of the references).

    Parameters
    ----------
    refs : tuple of int
        Indices of the references of the problem.
    theta : numpy.ndarray
        The parameters (SI), in ``model.free`` order.
    chi2 : float
        -, the weighted sum of squared residuals.
    tof_model : numpy.ndarray
        s, the model's TOF at the subset's references.
    converged : bool
        Whether the local least squares converged.
    iterations : int
        Its iterations.
    """

    refs: tuple[int, ...]
    theta: np.ndarray  # SI, model.free order
    chi2: float
    tof_model: np.ndarray  # s, at the subset's references
    converged: bool
    iterations: int


# --------------------------------------------------------------------- scan
def scan_grid(model: TofModel, ranges: dict[str, tuple[float, float]],
              points: int | None = None) -> tuple[np.ndarray, list[np.ndarray]]:
    """The scan's parameter sets (m, p) in ``model.free`` order, and each axis's values.

    Parameters
    ----------
    model : TofModel
        The TOF model (its continuous and integer free parameters).
    ranges : dict of str to tuple of float
        ``(lo, hi)`` per free parameter, SI.
    points : int or None
        Points per continuous axis (None: ``SCAN_POINTS_1D`` for one, else within
        ``SCAN_BUDGET``); integer axes take every integer in range.

    Returns
    -------
    tuple
        The (m, p) grid (SI) and the list of each axis's values.
    """
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
def _scaled(derivs: Derivatives, theta: np.ndarray, cont_idx: list[int],
            cont: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The model's values (m, n) at the rows of ``theta`` and their Jacobian in the scaled
    coordinates of the continuous parameters (m, n, p): one call of ``derivs``."""
    f, jac = derivs(theta)
    return f, jac * dtheta_dx(theta[:, cont_idx], cont)[:, None, :]


def _lm_batch(model: TofModel, obs: Observations, derivs: Derivatives,
              problems: list[tuple[tuple[int, ...], np.ndarray, np.ndarray]],
              ranges: dict[str, tuple[float, float]]) -> list[Solution]:
    """Every (refs, x0 of the continuous parameters, integer values) start refined at once
    (:func:`ssw.calibration.lm.levenberg_marquardt`): each iteration evaluates every
    unfinished start's trial point and its Jacobian (``derivs``) in one batched call."""
    cont, ints = model.continuous, model.integers
    cont_idx = [model.free.index(n) for n in cont]
    p = len(cont)
    lo, hi = bounds_x(cont, ranges)
    fixed = [pr[2] for pr in problems]
    cols = [obs.columns(pr[0]) for pr in problems]

    def evaluate(points: dict[int, np.ndarray]) -> dict[int, tuple]:
        keys = list(points)
        rows = _order(np.array([np.concatenate([from_x(points[i], cont), fixed[i]])
                                for i in keys]), cont, ints, model.free)
        f, Jx = _scaled(derivs, rows, cont_idx, cont)
        return {i: obs.weighted(f[k], Jx[k], cols[i]) for k, i in enumerate(keys)}

    x0 = {i: np.asarray(pr[1], float).reshape(p) for i, pr in enumerate(problems)}
    start = evaluate(x0)
    probs = [Problem(x0[i], *start[i], np.eye(p)) for i in range(len(problems))]
    for pr in probs:
        pr.done = not np.isfinite(pr.cost)  # a start on a failing corner: dropped
    keys = [tuple(int(j) for j in pr[0]) for pr in problems]

    def prune(it: int, ps: list[Problem]) -> None:
        if it < PRUNE_AFTER:
            return
        best: dict[tuple, float] = {}
        for k_, pr in zip(keys, ps, strict=True):
            best[k_] = min(best.get(k_, np.inf), pr.cost)
        for k_, pr in zip(keys, ps, strict=True):
            if not pr.done and pr.cost > best[k_] + PRUNE_CHI2:
                pr.done = True  # a basin that much worse is no candidate

    levenberg_marquardt(probs, evaluate, lo, hi, LM_ITERATIONS, prune)
    out = []
    for i, pr in enumerate(probs):
        theta = _order(np.concatenate([from_x(pr.x, cont), fixed[i]])[None, :], cont, ints,
                       model.free)[0]
        c = cols[i]
        tof = (obs.values[c] + obs.std[c] * pr.r if np.isfinite(pr.cost)
               else np.full(c.size, np.nan))
        out.append(Solution(keys[i], theta, float(pr.cost), tof, pr.converged,
                            pr.iterations))
    return out


def _order(rows: np.ndarray, cont: tuple[str, ...], ints: tuple[str, ...],
           free: tuple[str, ...]) -> np.ndarray:
    """Columns (continuous..., integer...) reordered to ``free``."""
    names = list(cont) + list(ints)
    return rows[:, [names.index(n) for n in free]]


def _starts(model: TofModel, grid: np.ndarray, axes: list[np.ndarray], tof: np.ndarray,
            obs: Observations, refs: tuple[int, ...], nominal: np.ndarray,
            ranges: dict[str, tuple[float, float]]) -> list[tuple[np.ndarray, np.ndarray]]:
    """(x of the continuous parameters, integer values) starts of one problem: for each
    value of the integer parameters whose best grid point is within PRUNE_CHI2 of the
    scan's best, the local minima of its continuous grid; and the device's nominal values
    (with the best integer values)."""
    cont_idx = [model.free.index(n) for n in model.continuous]
    int_idx = [model.free.index(n) for n in model.integers]
    cost = obs.chi2(tof, obs.columns(refs))
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
