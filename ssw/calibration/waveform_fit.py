"""A fit of a waveform model to its records (:mod:`ssw.calibration.waveform`): the
bounded Levenberg-Marquardt over the scaled coordinates (:func:`fit`, :class:`Fit`),
the observations a step loses, and what the fit's covariance gives (the globals'
covariance, the noise's share of a parameter's standard deviation, the first-order
propagation of held parameters' uncertainty).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ssw.calibration.hits import Column, State, get, put
from ssw.calibration.observation import (
    Observed,
    Setup,
    _bounds,
    dtheta_dx,
    from_x,
    observe,
    to_x,
)

#: The chi^2 quantile beyond which a fit says the model does not explain the records.
FLAG_QUANTILE = 0.999


@dataclass(frozen=True)
class Fit:
    """A fit of a waveform model's free parameters to the records. SI units.

    Parameters
    ----------
    state : State
        The parameters at the optimum.
    free : list of Column
        The fitted parameters.
    values : numpy.ndarray
        (q,) their values, SI.
    cov_x : numpy.ndarray
        (q, q) their covariance in the scaled coordinates
        (:func:`~ssw.calibration.observation.coordinate`), from the Gauss-Newton curvature at the
        optimum (unscaled by the misfit).
    chi2 : float
        The weighted residuals' sum of squares (data and priors).
    dof : int
        Observations minus free parameters.
    quantile : float
        ``P(X <= chi2)`` for ``X`` chi^2-distributed with ``dof`` degrees of freedom (1:
        far beyond what the noise explains).
    converged : bool
        The Levenberg-Marquardt stopped at a first-order point.
    runs : int
        Chain runs.
    start : list of dict
        The global start's grid (:func:`~ssw.calibration.start.global_start`) with each
        point's chi^2, if any.
    unexplained : int
        Observations the record has a value for and the model, at the optimum, none.
    floor : dict
        The model-error floor of the fit's weights (``floor`` of :class:`Setup`).
    discrepancy : ssw.calibration.discrepancy.Discrepancy or None
        The model's discrepancy the fit corrects its features by (``discrepancy`` of
        :class:`Setup`).
    prior : dict
        The measured globals' priors of the fit, global -> (mean, standard deviation), SI
        (``prior`` of :class:`Setup`).
    """

    state: State
    free: list[Column]
    values: np.ndarray
    cov_x: np.ndarray
    chi2: float
    dof: int
    quantile: float
    converged: bool
    runs: int
    start: list[dict] = field(default_factory=list)
    unexplained: int = 0
    floor: dict[str, float] = field(default_factory=dict)
    discrepancy: Any = None
    prior: dict[str, tuple[float, float]] = field(default_factory=dict)

    @property
    def flagged(self) -> bool:
        """The misfit is beyond the noise (:data:`FLAG_QUANTILE`), or the record has
        observations the model has no value for (a pulse or a trigger crossing the model
        does not produce: its chi^2 then counts only the rest)."""
        return not self.quantile <= FLAG_QUANTILE or self.unexplained > 0

    @property
    def misfit(self) -> float:
        """``max(1, chi2 / dof)``: the factor a model-discrepancy term scales the
        covariance by (Press et al. 2007, sec. 15.1: errors scaled by the fit's
        ``sqrt(chi2 / dof)`` when the model does not reach the noise)."""
        return float(max(1.0, self.chi2 / max(self.dof, 1)))

    def std(self, col: Column, scaled: bool = True) -> float:
        """The standard error of ``col`` in its scaled coordinate (relative for a log
        coordinate), times ``sqrt(misfit)`` when ``scaled``.

        Parameters
        ----------
        col : Column
            A fitted parameter.
        scaled : bool
            Scale by ``sqrt(misfit)`` (:attr:`misfit`).

        Returns
        -------
        float
            The standard error in the scaled coordinate.
        """
        j = self.free.index(col)
        s = float(np.sqrt(max(self.cov_x[j, j], 0.0)))
        return s * np.sqrt(self.misfit) if scaled else s


def _residuals(setup: Setup, state: State, free: list[Column], wanted: set[str]
               ) -> tuple[np.ndarray, np.ndarray, int]:
    """Weighted residuals and their Jacobian in the scaled coordinates of ``free`` (rows
    where the model or the data has no value, a feature not found, count 0), and how many
    rows the record has a value for but the model none (unexplained)."""
    return _weighted(setup, observe(setup, state, wanted), state, free)


def _weighted(setup: Setup, obs: Observed, state: State, free: list[Column],
              rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`_residuals` of the observations ``obs`` of ``state`` (only ``rows``, a
    boolean mask, when given)."""
    index = {c: j for j, c in enumerate(obs.columns)}
    vals = np.array([get(state, c) for c in free])
    keep = slice(None) if rows is None else rows
    J = (obs.jacobian[keep][:, [index[c] for c in free]]
         * dtheta_dx(setup, free, vals)[None, :])
    sigma = obs.sigma[keep]
    r = (obs.model[keep] - obs.data[keep]) / sigma
    ok = np.isfinite(r) & np.all(np.isfinite(J), axis=1)
    unexplained = int(np.count_nonzero(~ok & np.isfinite(obs.data[keep])))
    return (np.where(ok, r, 0.0), np.where(ok[:, None], J / sigma[:, None], 0.0),
            unexplained)


def fit(setup: Setup, state: State, free: list[Column], iterations: int | None = None
        ) -> Fit:
    """Fit the ``free`` parameters of ``state`` to the records by the one bounded
    Levenberg-Marquardt (:func:`ssw.calibration.lm.levenberg_marquardt`), in the scaled
    coordinates, each parameter within its range (:data:`~ssw.calibration.hits.PARAMETERS`).
    A trial point where the model loses observations that the current point explains (a hit's pulse
    or trigger
    crossing it no longer produces) is rejected: those rows would drop out of chi^2, a
    fall that is no better fit and a trap the fit cannot leave.

    Parameters
    ----------
    setup : Setup
        The model and the records (its chain step fixed: :meth:`Setup.fix_step`).
    state : State
        The start (the other parameters stay at their values).
    free : list of Column
        The parameters fitted.
    iterations : int or None
        At most this many model runs (default: the Levenberg-Marquardt's own limit).

    Returns
    -------
    Fit
        The optimum, its covariance and goodness of fit.
    """
    from scipy import stats

    from ssw.calibration.lm import LM_ITERATIONS, Problem, levenberg_marquardt

    wanted = {c.name for c in free}
    work = state.copy()
    x0 = to_x(setup, free, np.array([get(work, c) for c in free]))
    lo, hi = _bounds(setup, free)
    x0 = np.clip(x0, lo, hi)

    def at(x: np.ndarray) -> State:
        st = work.copy()
        for c, v in zip(free, from_x(setup, free, x), strict=True):
            put(st, c, v)
        return st

    r, J, lost = _residuals(setup, at(x0), free, wanted)
    pr = Problem(x0, r, J, float(r @ r), np.eye(len(free)))
    explained = _Explained(x0, lost)

    def evaluate(trial: dict[int, np.ndarray]) -> dict[int, tuple[np.ndarray, np.ndarray,
                                                                  float]]:
        out = {}
        for i, x in trial.items():
            rr, JJ, lost = _residuals(setup, at(x), free, wanted)
            out[i] = (rr, JJ, explained.cost(pr.x, x, rr, lost))
        return out

    levenberg_marquardt([pr], evaluate, lo, hi, iterations or LM_ITERATIONS)
    n_obs = int(np.count_nonzero(np.any(pr.J != 0, axis=1) | (pr.r != 0)))
    dof = max(n_obs - len(free), 1)
    cov = np.linalg.pinv(pr.J.T @ pr.J)
    dead = ~np.any(pr.J != 0, axis=0)  # no observation answers to it: unknown, not exact
    cov[dead, :] = 0.0
    cov[:, dead] = 0.0
    cov[dead, dead] = np.inf
    final = at(pr.x)
    return Fit(final, list(free), from_x(setup, free, pr.x), cov, float(pr.cost), dof,
               float(stats.chi2.cdf(pr.cost, dof)), bool(pr.converged), setup.runs,
               unexplained=explained.lost(pr.x), floor=dict(setup.floor),
               discrepancy=setup.discrepancy, prior=dict(setup.prior))


class _Explained:
    """The rows of the records that each point a fit evaluated leaves unexplained (the
    model has no value for them), and the cost of a trial point: its chi^2, or infinite
    where it loses observations that the problem's current point explains (a hit's pulse
    or trigger crossing not found). Such a point drops their rows from chi^2: a fall that
    is no better fit, and a trap the fit cannot leave (every way back adds the rows again).

    Parameters
    ----------
    x0 : numpy.ndarray
        The start (scaled coordinates).
    lost : int
        The rows it leaves unexplained.
    """

    def __init__(self, x0: np.ndarray, lost: int) -> None:
        self._lost = {x0.tobytes(): int(lost)}

    def lost(self, x: np.ndarray) -> int:
        """The rows an evaluated point ``x`` leaves unexplained."""
        return self._lost[x.tobytes()]

    def cost(self, current: np.ndarray, trial: np.ndarray, r: np.ndarray, lost: int
             ) -> float:
        """The cost of ``trial`` (residuals ``r``, ``lost`` rows unexplained) for a problem
        at ``current``: ``r . r``, or infinite when it loses rows ``current`` explains."""
        self._lost[trial.tobytes()] = int(lost)
        return np.inf if lost > self.lost(current) else float(r @ r)


def global_covariance(f: Fit, hits: float = 1.0) -> tuple[list[str], np.ndarray]:
    """The covariance of a fit's free globals in their scaled coordinates
    (:func:`~ssw.calibration.observation.coordinate`), scaled by the misfit
    (:attr:`Fit.misfit`), every per-hit parameter marginalized; with a model-error floor (``floor``
    of :class:`Fit`), times ``hits``:
    the model's error is the same on every hit of a sample and does not average down
    over them as the weights assume (conservative: the noise's share, far smaller, is
    scaled with it).

    Parameters
    ----------
    f : Fit
        A fit (a calibration of records, :func:`~ssw.calibration.waveform.calibrate_records`).
    hits : float
        Hits per sample.

    Returns
    -------
    tuple of (list of str, numpy.ndarray)
        The globals' names and their (g, g) covariance.
    """
    j = [i for i, c in enumerate(f.free) if c.index < 0]
    hits = hits if any(f.floor.values()) else 1.0
    return [f.free[i].name for i in j], f.cov_x[np.ix_(j, j)] * f.misfit * hits


def noise_std(setup: Setup, f: Fit, col: Column) -> float:
    """The standard error of ``col`` (its scaled coordinate) at a fit's optimum with the
    noise's weights alone: what the fit would give if the model were the device (the
    model-error floor and the misfit's scaling left out; the rest of a fit's standard error
    is the model's, :func:`ssw.measure.measure_information`).

    Parameters
    ----------
    setup : Setup
        The fit's model and records.
    f : Fit
        The fit.
    col : Column
        One of its free parameters.

    Returns
    -------
    float
        The standard error, scaled coordinate.
    """
    bare = replace(setup, floor={}, runs=0)
    _, J, _ = _residuals(bare, f.state, list(f.free), {c.name for c in f.free})
    setup.runs += bare.runs
    j = f.free.index(col)
    return float(np.sqrt(max(np.linalg.pinv(J.T @ J)[j, j], 0.0)))


def propagated(setup: Setup, f: Fit, names: list[str], cov: np.ndarray) -> np.ndarray:
    """The covariance the uncertainty of held globals (a calibration's,
    :func:`global_covariance`) gives a fit's free parameters, to first order: ``S C S^T``
    with ``S = -(J_f^T J_f)^+ J_f^T J_g`` the optimum's shift per unit of the globals
    (Gauss-Newton, every Jacobian weighted, in the scaled coordinates).

    Parameters
    ----------
    setup : Setup
        The fit's model and records.
    f : Fit
        The fit (the globals held at their values).
    names : list of str
        The globals (:data:`~ssw.calibration.hits.GLOBALS`).
    cov : numpy.ndarray
        (g, g) their covariance in their scaled coordinates.

    Returns
    -------
    numpy.ndarray
        (q, q) the covariance of ``f.free`` in their scaled coordinates.
    """
    cols = [Column(n) for n in names]
    _, J, _ = _residuals(setup, f.state, list(f.free) + cols,
                         {c.name for c in f.free} | set(names))
    q = len(f.free)
    Jf, Jg = J[:, :q], J[:, q:]
    S = -np.linalg.pinv(Jf.T @ Jf) @ (Jf.T @ Jg)
    return S @ np.asarray(cov, float) @ S.T
