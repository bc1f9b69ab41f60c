"""Least-squares identification of device parameters from measured TOFs on reference samples.

Problem. References ``i`` (known ``E_i``, ``nu_i``; measured ``T_i`` with standard uncertainty
``s_i``) and free parameters ``theta`` of the device, each within its range
(:func:`~ssw.calibration.scan.scan_ranges`): minimize the weighted sum of squares

    ``chi^2(theta) = sum_i ((TOF(E_i, nu_i; theta) - T_i) / s_i)^2``  subject to
    ``lo <= theta <= hi``.

The observations and the model's derivatives are those of :mod:`ssw.calibration.residuals`
(one function ``theta -> (values, d values / d theta)``): the search's steps take central
differences of the batched model (the cheaper at a calibration's few scenes); the covariance
at the solution the chain's exact forward sensitivities where the walls carry them
(:func:`ssw.calibration.residuals.model_derivatives`), so that other kinds of observations
can join the TOFs. TOF is not monotone in the parameters (REFERENCE.md: TOF rises then falls
with the striker speed under gravity), so no bracketing is assumed:

1. **global scan**: a tensor grid of the continuous parameters (log-spaced where a parameter
   is scaled, :data:`ssw.device.PARAMETERS`) times every value of the integer ones, all
   evaluated in batched runs (:class:`ssw.calibration.model.TofModel`); every grid local
   minimum of ``chi^2`` is a start;
2. **local refinement**: the bounded Levenberg-Marquardt of :mod:`ssw.calibration.lm` in the
   scaled coordinates ``x`` (``ln theta`` or ``theta / scale``); the starts of every problem
   (the full set and each leave-one-out subset) advance together, one batched run per
   iteration. A parameter whose optimum lies beyond its range converges ON its bound (the
   others to their optimum given it): a legitimate answer, flagged (``at_bound``);
3. **result**: the best solution; other solutions with ``chi^2`` within 1 of it are listed
   (the data do not choose between them); on a tie the one nearest the device's nominal
   values is taken.

Steps 1 and 2 and the pick of 3 live in :mod:`ssw.calibration.scan` (their names importable
from here as well); this module holds the identification (:func:`identify`), its local
analysis, the leave-one-out subsets, the uncertainty and the input's checks.

Uncertainty (Bard 1974; Press et al. 2007, sec. 15.5): with the weighted Jacobian ``J``
(the model's derivatives at the solution) of the parameters NOT held on a bound, their
covariance is ``(J^T J)^-1``: conditional on the held ones, which are fixed at their bound
(their rows and columns are absent, not given a fictitious variance; a bound is not a
measurement, and the first-order interval of a parameter there would reach outside its
range). When no TOF uncertainty is given, the weights are ``1 / (1 % of T_i)`` and the
covariance is scaled by the residual variance ``chi^2 / (n - q)``, ``q`` the parameters in
it (none when ``n = q``). The singular values of ``J`` in the scaled coordinates say what the
data identify: a direction ``v`` with a small singular value ``sigma`` moves the TOFs by one
standard uncertainty only when the parameters move by ``1/sigma`` along ``v`` (scaled
units), i.e. the data cannot separate the parameters mixed in ``v``; below 1 (more than an
e-fold) the calibration says so and gives no standard errors (:data:`IDENTIFIED_MIN`).

Model error. Where the references' chi^2 with their stated TOF uncertainties exceeds its
95 % quantile (:func:`ssw.calibration.model_error.rejects`, ``n - q`` degrees of freedom,
:func:`degrees_of_freedom`), the model does not describe the device to the references'
precision: the fit is repeated with a relative TOF model error ``tau`` in the weights,
``std_i^2 + tau^2 T_i^2``, ``tau`` the upper confidence bound its residuals call for,
re-estimated until it settles (``_with_model_error``; :mod:`ssw.calibration.model_error`
states the estimator and why). The covariance and the leave-one-out fits then use those
weights; ``Fit.chi2`` stays the references' chi^2 with their stated uncertainties and
``Fit.model_error`` states the term. A calibration is refused only for its input (TOFs the
device cannot produce, :func:`check_producible`; fewer references than parameters freed,
:func:`check_enough`); a fit that does not converge, leaves a direction unidentified or
needs the model-error term answers with the finding stated (:func:`fit_warnings`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ssw.calibration.lm import LM_FTOL, LM_ITERATIONS, Problem, active_set, levenberg_marquardt  # noqa: F401
from ssw.calibration.model import Reference, TofModel
from ssw.calibration.model_error import (
    PASSES,
    RTOL,
    ModelError,
    chi2_cdf,
    floor_bound,
    rejects,
)
from ssw.calibration.residuals import (
    Derivatives,
    Observations,
    bounds_x,
    central_differences,
    dtheta_dx,
    from_x,
    model_derivatives,
    to_x,
)

# The global scan and the batched refinement from its starts, re-exported.
from ssw.calibration.scan import (  # noqa: F401
    DISTINCT,
    PRUNE_AFTER,
    PRUNE_CHI2,
    SCAN_BUDGET,
    SCAN_POINTS_1D,
    STARTS,
    Solution,
    _grid_minima,
    _lm_batch,
    _order,
    _pick,
    _scaled,
    _starts,
    scan_grid,
    scan_ranges,
)
from ssw.device import parameter, parameter_value
from ssw.errors import ConfigError, SolverError  # noqa: F401

#: The parameters a calibration identifies when none are named: the striker speed and the
#: static load on the chain (the soft/stiff TOF contrast of the references is set by the
#: static load, their common level by the speed: README "Calibration").
DEFAULT_FREE = ("striker_velocity", "preload")
#: Relative TOF weight when no uncertainty is given (covariance rescaled by chi^2/(n-q)).
DEFAULT_REL_STD = 0.01
#: A direction counts as not identified when its singular value (of the Jacobian weighted
#: by the TOF uncertainties, in the scaled coordinates) is below IDENTIFIED_MIN: the data
#: then tolerate, within one standard uncertainty, a change of more than one e-fold of a
#: log-scaled parameter (one ``scale`` of another) along it; or below IDENTIFIED_RATIO of
#: the largest one (numerically rank deficient).
IDENTIFIED_MIN = 1.0
IDENTIFIED_RATIO = 1e-3
#: The side of a range a held parameter sits on (:func:`ssw.calibration.lm.active_set`).
SIDES = {-1: "lower", 1: "upper"}


# --------------------------------------------------------------------- results
@dataclass(frozen=True)
class Fit:
    """The identification on all references, its uncertainty and the alternatives.

    ``covariance``, ``std``, ``singular_values`` and ``singular_vectors`` are over
    ``covariance_names``: the continuous free parameters not held on a bound
    (``at_bound``: name -> ``lower`` | ``upper``), conditional on the held ones.

    Parameters
    ----------
    names : tuple of str
        The free parameters, in order.
    theta : numpy.ndarray
        (p,) the identified values, SI.
    chi2 : float
        -, the weighted sum of squared residuals at ``theta``.
    tof_model : numpy.ndarray
        (n,) s, the model's TOF at each reference.
    residuals : numpy.ndarray
        (n,) s, model minus measured TOF.
    weights_known : bool
        Whether the references state their TOF uncertainty (else
        :data:`DEFAULT_REL_STD`, the covariance rescaled by ``chi2 / (n - q)``).
    covariance : numpy.ndarray or None
        (q, q) SI, over ``covariance_names``; None if not estimable.
    std : numpy.ndarray or None
        (q,) SI, the standard errors.
    singular_values : numpy.ndarray
        (q,) of the weighted Jacobian in scaled coordinates.
    singular_vectors : numpy.ndarray
        (q, q), columns: the right singular vectors.
    jacobian : numpy.ndarray
        (n, p) ``d TOF / d theta`` of every continuous parameter, s per SI unit.
    unidentified : tuple of str
        Directions the data cannot pin (texts).
    alternatives : tuple of dict of str to float
        Other solutions within chi^2 + 1.
    converged : bool
        Whether the least squares converged.
    scan_points : int
        Points per axis of the global scan.
    evaluations : int
        Parameter sets the model evaluated (a cost counter).
    runs : int
        Batched chain runs.
    covariance_names : tuple of str
        The continuous free parameters no bound holds.
    at_bound : dict of str to str
        Held parameter -> ``lower`` | ``upper``.
    tof_range : numpy.ndarray or None
        (n, 2) s, the TOFs the scanned device can give on each reference.
    model_error : ssw.calibration.model_error.ModelError or None
        The TOF model-error term where the references reject the model.
    """

    names: tuple[str, ...]
    theta: np.ndarray
    chi2: float
    tof_model: np.ndarray
    residuals: np.ndarray  # s, model - measured
    weights_known: bool
    covariance: np.ndarray | None  # SI, (q, q); None if not estimable
    std: np.ndarray | None  # SI, (q,)
    singular_values: np.ndarray  # (q,) of the weighted Jacobian in scaled coordinates
    singular_vectors: np.ndarray  # (q, q), columns: right singular vectors
    jacobian: np.ndarray  # (n, p) d TOF / d theta of every continuous one, s per SI unit
    unidentified: tuple[str, ...]  # texts: directions the data cannot pin
    alternatives: tuple[dict[str, float], ...]  # other solutions within chi^2 + 1
    converged: bool
    scan_points: int
    evaluations: int
    runs: int
    covariance_names: tuple[str, ...] = ()  # the continuous free ones no bound holds
    at_bound: dict[str, str] = field(default_factory=dict)
    tof_range: np.ndarray | None = None  # (n, 2) s: the TOFs the scan's device can give
    model_error: ModelError | None = None  # the references reject the model: its term


# --------------------------------------------------------------------- local analysis
@dataclass(frozen=True)
class Local:
    """A least-squares point's local picture: which parameters a bound holds, and the
    singular value decomposition of the weighted Jacobian of the others.

    ``held`` (p,): -1 / +1 held on the lower / upper bound, 0 free
    (:func:`ssw.calibration.lm.active_set`); ``free`` the indices of the free ones;
    ``sv`` (q,) and ``V`` (q, q) the singular values and right singular vectors of their
    weighted Jacobian (scaled coordinates), ``sv`` padded with zeros when the data are
    fewer than ``q``; ``floor`` the singular value below which a direction is not
    identified.

    Parameters
    ----------
    held : numpy.ndarray
        (p,) -1 / +1 held on the lower / upper bound, 0 free.
    free : numpy.ndarray
        Indices of the free parameters.
    sv : numpy.ndarray
        (q,) singular values of their weighted Jacobian (scaled coordinates).
    V : numpy.ndarray
        (q, q) right singular vectors (columns).
    floor : float
        The singular value below which a direction is not identified.
    """

    held: np.ndarray
    free: np.ndarray
    sv: np.ndarray
    V: np.ndarray
    floor: float

    @property
    def identified(self) -> bool:
        """Every free direction identified (and at least one free parameter)."""
        return self.sv.size > 0 and float(self.sv.min()) >= self.floor and float(
            self.sv.max()) > 0


def local(x: np.ndarray, r: np.ndarray, Jw: np.ndarray, lo: np.ndarray, hi: np.ndarray
          ) -> Local:
    """The :class:`Local` picture of a least-squares point.

    Parameters
    ----------
    x : numpy.ndarray
        The point, scaled coordinates (p,).
    r : numpy.ndarray
        The weighted residuals there (n,).
    Jw : numpy.ndarray
        Their Jacobian in the scaled coordinates (n, p).
    lo : numpy.ndarray
        Lower bounds of the scaled coordinates (p,).
    hi : numpy.ndarray
        Upper bounds (p,).

    Returns
    -------
    Local
        The held parameters and the singular values of the others.
    """
    held = active_set(x, Jw.T @ r, lo, hi)
    free = np.flatnonzero(held == 0)
    q = free.size
    if q:
        _, s, Vt = np.linalg.svd(Jw[:, free], full_matrices=True)
        sv = np.zeros(q)
        sv[: s.size] = s
        V = Vt.T
    else:
        sv, V = np.zeros(0), np.zeros((0, 0))
    floor = max(IDENTIFIED_MIN, IDENTIFIED_RATIO * float(sv.max(initial=0.0)))
    return Local(held, free, sv, V, floor)


def _held_names(names: tuple[str, ...], held: np.ndarray) -> dict[str, str]:
    """``{name: "lower" | "upper"}`` of the parameters a bound holds."""
    return {n: SIDES[int(h)] for n, h in zip(names, held, strict=True) if h}


# --------------------------------------------------------------------- public
@dataclass(frozen=True)
class SubsetFit:
    """A calibration on a subset of the references (a leave-one-out fit).

    ``theta``: its values (SI); ``chi2``; ``singular_values`` of the subset's weighted
    Jacobian at ``theta`` (scaled coordinates) over the parameters no bound holds there
    (``at_bound``); ``identified``: every one >= the floor (:data:`IDENTIFIED_MIN`).

    Parameters
    ----------
    refs : tuple of int
        Indices of the subset's references.
    theta : numpy.ndarray
        (p,) its values, SI.
    chi2 : float
        -, its weighted sum of squared residuals.
    identified : bool
        Every free direction's singular value >= the floor.
    singular_values : numpy.ndarray
        Of the subset's weighted Jacobian at ``theta`` (scaled coordinates).
    iterations : int
        Iterations of the refinement.
    at_bound : dict of str to str
        Held parameter -> ``lower`` | ``upper``.
    """

    refs: tuple[int, ...]
    theta: np.ndarray
    chi2: float
    identified: bool
    singular_values: np.ndarray
    iterations: int
    at_bound: dict[str, str] = field(default_factory=dict)


def refine_subsets(model: TofModel, obs: Observations, derivs: Derivatives,
                   start: np.ndarray, subsets: list[tuple[int, ...]],
                   ranges: dict[str, tuple[float, float]], iterations: int = 16,
                   at_start: tuple[np.ndarray, np.ndarray] | None = None,
                   ) -> dict[tuple[int, ...], SubsetFit]:
    """Fits of subsets of the references, from ``start`` (the full calibration, SI).

    Each subset's least squares within the directions it identifies AT ``start`` (right
    singular vectors, with singular values >= :data:`IDENTIFIED_MIN`, of its weighted
    Jacobian over the parameters no bound holds there; Hansen 1998, truncated SVD), the
    others held at ``start``'s values. Where the subset identifies every parameter this is
    its least-squares solution; where it does not (a valley of near-exact fits), the point
    that differs from the full calibration only in what the subset can tell, a well-defined
    answer instead of an arbitrary point of the valley. The bounded Levenberg-Marquardt of
    the main fit (:mod:`ssw.calibration.lm`), all subsets together, one call of ``derivs``
    per iteration.

    Parameters
    ----------
    model : TofModel
        The forward model (its free parameters and their kinds).
    obs : Observations
        The observations of every reference.
    derivs : callable
        The model's derivatives (:mod:`ssw.calibration.residuals`).
    start : numpy.ndarray
        The full calibration's values, SI, ``model.free`` order.
    subsets : list of tuple of int
        The subsets (indices of the references).
    ranges : dict
        Each free parameter's range, SI.
    iterations : int
        At most this many iterations.
    at_start : tuple, optional
        The model's values (n,) and their Jacobian in the scaled coordinates (n, p) at
        ``start`` when already computed (``_uncertainty``), so that they are not
        computed again.

    Returns
    -------
    dict
        Subset -> :class:`SubsetFit`.
    """
    cont = model.continuous
    idx = [model.free.index(n) for n in cont]
    lo, hi = bounds_x(cont, ranges)
    x0 = to_x(start[idx], cont)
    cols = {key: obs.columns(key) for key in subsets}

    def rows_of(points: list[np.ndarray]) -> np.ndarray:
        th = np.repeat(start[None, :], len(points), axis=0)
        th[:, idx] = from_x(np.array(points), cont)
        return th

    def evaluate(points: dict[int, np.ndarray]) -> dict[int, tuple]:
        keys = list(points)
        f, Jx = _scaled(derivs, rows_of([points[i] for i in keys]), idx, cont)
        return {i: obs.weighted(f[k], Jx[k], cols[subsets[i]]) for k, i in enumerate(keys)}

    if at_start is None:
        f0, J0 = (a[0] for a in _scaled(derivs, rows_of([x0]), idx, cont))
    else:
        f0, J0 = at_start
    probs = []
    for key in subsets:
        r, Jw, chi2 = obs.weighted(f0, J0, cols[key])
        loc = local(x0, r, Jw, lo, hi)
        # the identified directions (of the parameters no bound holds) are searched; the
        # others stay at `start`
        basis = np.zeros((len(cont), int(np.sum(loc.sv >= loc.floor))))
        basis[loc.free] = loc.V[:, loc.sv >= loc.floor]
        probs.append(Problem(x0.copy(), r, Jw, chi2, basis))
    levenberg_marquardt(probs, evaluate, lo, hi, iterations)
    out = {}
    for key, pr in zip(subsets, probs, strict=True):
        loc = local(pr.x, pr.r, pr.J, lo, hi)
        theta = start.copy()
        theta[idx] = from_x(pr.x, cont)
        out[key] = SubsetFit(key, theta, pr.cost, loc.identified, loc.sv, pr.iterations,
                             _held_names(cont, loc.held))
    return out


def identify(
    model: TofModel, refs: list[Reference], *, ranges: dict[str, tuple[float, float]] | None = None,
    subsets: list[tuple[int, ...]] | None = None, scan_points: int | None = None,
) -> tuple[Fit, dict[tuple[int, ...], SubsetFit]]:
    """Identify ``model.free`` from ``refs`` (scan, then bounded Levenberg-Marquardt).

    Parameters
    ----------
    model : TofModel
        The forward model on the references.
    refs : list of Reference
        The references, in the model's order.
    ranges : dict, optional
        Scan range (SI) per free parameter (default :data:`ssw.device.PARAMETERS`'s).
    subsets : list of tuple of int, optional
        Subsets of ``refs`` (e.g. the leave-one-out sets), each fitted as the smallest
        change of the calibration (:func:`refine_subsets`).
    scan_points : int, optional
        Grid points per continuous parameter of the global scan.

    Returns
    -------
    tuple
        The :class:`Fit` and the subsets' :class:`SubsetFit` by subset.

    Raises
    ------
    ConfigError
        When some references give a TOF uncertainty and others not.
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
    obs = Observations.tof(T, s)
    rng = scan_ranges(model.free, ranges, model.device)
    # the search's steps take central differences (one batched run of 1 + 2 p points per
    # row); the covariance at the solution, a result, takes the exact derivatives. Measured
    # with the compiled step on the study's calibration (2 free parameters, 3 references):
    # 2.9-3.2 s of user CPU so, 3.5-3.8 s with the exact derivatives at every step too (one
    # row alone costs 1.5 plain runs by differences, 1.2 by the tangent)
    search_derivs = central_differences(model, model.free, rng)
    derivs = model_derivatives(model, rng)
    nominal = np.array([parameter_value(model.device, n) for n in model.free])
    for j, n in enumerate(model.free):  # the nominal start inside the scan
        nominal[j] = np.clip(nominal[j], *rng[n])
    model.fix_time_step(rng)
    grid, axes = scan_grid(model, rng, scan_points)
    tof = model(grid)
    tof_range = check_producible(refs, tof, rng)
    key = tuple(range(len(refs)))
    problems = [(key, x0, fixed) for x0, fixed in
                _starts(model, grid, axes, tof, obs, key, nominal, rng)]
    # the refinement's step: near the candidates (2x their fastest striker), not the scan's
    # fastest striker; one step for every run from here on
    cont = model.continuous
    model.refix_time_step(np.array([_order(np.concatenate([from_x(x0, cont), fx])[None, :],
                                           cont, model.integers, model.free)[0]
                                    for _, x0, fx in problems]), rng)
    sols = _lm_batch(model, obs, search_derivs, problems, rng)
    best, others = _pick(sols, to_x(nominal, model.free), model)
    fit, at_best = _uncertainty(model, obs, derivs, known, best, others, rng, grid.shape[0])
    if known and rejects(fit.chi2, degrees_of_freedom(fit)):
        # the references reject the model: its error enters the weights (module docstring)
        stated = obs.std
        obs, best, merr = _with_model_error(model, obs, search_derivs, best, rng,
                                            degrees_of_freedom(fit), fit.chi2)
        fit, at_best = _uncertainty(model, obs, derivs, known, best, others, rng,
                                    grid.shape[0])
        fit = replace(fit, chi2=float(np.sum((fit.residuals / stated) ** 2)),
                      model_error=replace(merr, chi2_with_term=fit.chi2))
    fit = replace(fit, tof_range=tof_range)
    if not subsets:
        return fit, {}
    subs = refine_subsets(model, obs, search_derivs, best.theta, list(subsets), rng,
                          at_start=at_best)
    return fit, subs


def degrees_of_freedom(fit: Fit) -> int:
    """The references' degrees of freedom at a fit: references minus the free parameters
    no bound holds (integers included: each is fitted, by the scan).

    With ``Fit.chi2`` (the stated uncertainties' chi^2) it is what an information criterion
    of a model (a dissipation law) needs: ``AIC = chi2 + 2 k``, ``BIC = chi2 + k ln n``,
    ``k = n - dof`` the parameters fitted (Burnham & Anderson 2002, sec. 2.2).

    Parameters
    ----------
    fit : Fit
        The identification.

    Returns
    -------
    int
        ``n - k`` (may be 0 or less: nothing to test the model on).
    """
    return int(fit.residuals.size - (len(fit.names) - len(fit.at_bound)))


def _with_model_error(model: TofModel, obs: Observations, derivs: Derivatives,
                      best: Solution, ranges: dict[str, tuple[float, float]], dof: int,
                      chi2: float) -> tuple[Observations, Solution, ModelError]:
    """The fit with a relative TOF model error ``tau`` in the weights
    (:mod:`ssw.calibration.model_error`): ``tau`` the upper confidence bound the residuals
    of the last fit call for (:func:`ssw.calibration.model_error.floor_bound`, relative to
    each measured TOF), the parameters refitted from ``best`` with the weights ``std^2 +
    tau^2 TOF^2`` (the bounded Levenberg-Marquardt of the main fit), until ``tau`` settles
    (:data:`ssw.calibration.model_error.RTOL`, at most
    :data:`ssw.calibration.model_error.PASSES` fits).

    Returns
    -------
    tuple
        The observations with the term's weights, the last fit's solution and the
        :class:`ssw.calibration.model_error.ModelError` (its ``chi2_with_term`` to fill).
    """
    T, s = obs.values, obs.std
    cont = model.continuous
    cont_idx = [model.free.index(n) for n in cont]
    int_idx = [model.free.index(n) for n in model.integers]
    key = tuple(range(T.size))
    tau_used, sol, settled, passes = None, best, False, 0
    eff = obs
    while passes < PASSES and not settled:
        passes += 1
        tau = floor_bound(sol.tof_model - T, s, T, dof)
        settled = tau_used is not None and abs(tau - tau_used) <= RTOL * tau
        eff = Observations(T, np.hypot(s, tau * T), obs.reference, obs.kind)
        start = (key, to_x(sol.theta[cont_idx], cont), sol.theta[int_idx])
        new = _lm_batch(model, eff, derivs, [start], ranges)[0]
        if np.isfinite(new.chi2):
            sol = new
        tau_used = tau
    merr = ModelError(float(tau_used), float(chi2), int(dof), chi2_cdf(chi2, dof), np.nan,
                      passes, bool(settled))
    return eff, sol, merr


def _uncertainty(model: TofModel, obs: Observations, derivs: Derivatives, known: bool,
                 best: Solution, others: list[Solution],
                 ranges: dict[str, tuple[float, float]], scan_points: int
                 ) -> tuple[Fit, tuple[np.ndarray, np.ndarray]]:
    """The fit at ``best``: Jacobian (``derivs``, one call), the parameters a bound holds,
    the others' covariance conditional on them, singular values. Also returns the model's
    values and scaled Jacobian there (the subsets' start)."""
    names, cont = model.free, model.continuous
    cont_idx = [names.index(n) for n in cont]
    n = obs.values.size
    f, Jx = _scaled(derivs, best.theta[None, :], cont_idx, cont)
    f0, Jx = f[0], Jx[0]
    lo, hi = bounds_x(cont, ranges)
    x0 = to_x(best.theta[cont_idx], cont)
    r, Jw, chi2 = obs.weighted(f0, Jx, np.arange(n))
    loc = local(x0, r, Jw, lo, hi)
    q = loc.free.size
    free_names = tuple(cont[j] for j in loc.free)
    D = dtheta_dx(best.theta[cont_idx], cont)
    cov = std = None
    if loc.identified and n >= q:
        cov_x = loc.V @ np.diag(1.0 / loc.sv**2) @ loc.V.T
        if not known:
            cov_x = cov_x * chi2 / (n - q) if n > q else None
        if cov_x is not None:
            Df = D[loc.free]
            cov = Df[:, None] * cov_x * Df[None, :]
            std = np.sqrt(np.diag(cov))
    unid = []
    for k in range(q):
        if loc.sv[k] < loc.floor or k >= n:
            v = loc.V[:, k]
            terms = " ".join(f"{v[j]:+.2f} {_coord(free_names[j])}"
                             for j in range(q) if abs(v[j]) > 0.2)
            unid.append(f"direction {terms} (singular value {loc.sv[k]:.3g}): the data "
                        "cannot separate these parameters")
    alts = tuple({nm: float(v) for nm, v in zip(names, so.theta, strict=True)}
                 | {"chi2": so.chi2} for so in others)
    fit = Fit(names, best.theta, chi2, f0, f0 - obs.values, known, cov, std, loc.sv, loc.V,
              Jx / D[None, :], tuple(unid), alts, best.converged, scan_points,
              model.evaluations, model.runs, free_names, _held_names(cont, loc.held))
    return fit, (f0, Jx)


def _coord(name: str) -> str:
    p = parameter(name)
    return f"ln({name})" if p.log else f"{name}/{p.scale:g} {p.unit}"


#: Margin of the producible TOF range: a reference up to this fraction beyond the scan's
#: extremes may still be reached between its grid points or just past its ranges' corners.
PRODUCIBLE_MARGIN = 0.05


def check_producible(refs: list[Reference], tof: np.ndarray,
                     ranges: dict[str, tuple[float, float]]) -> np.ndarray:
    """The TOF range (s, (n, 2)) the scanned device gives on each reference; CalibrationError
    naming every reference whose measured TOF lies outside it (by more than
    :data:`PRODUCIBLE_MARGIN`): no parameter within the ranges can fit it (a TOF in ms typed
    as s, a wrong sample, a device unlike the one described).

    Parameters
    ----------
    refs : list of Reference
        The references.
    tof : numpy.ndarray
        (m, n) s, the scan's TOF per parameter set and reference (NaN: none).
    ranges : dict of str to tuple of float
        The scan ranges (SI), named in the error.

    Returns
    -------
    numpy.ndarray
        (n, 2) s, the lowest and highest TOF on each reference.

    Raises
    ------
    ssw.errors.CalibrationError
        A reference's TOF outside what the device can produce.
    """
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


def check_enough(n: int, free: tuple[str, ...]) -> None:
    """ConfigError unless ``n`` references (one TOF each) can determine the ``free``
    parameters: at least as many references as parameters freed.

    Parameters
    ----------
    n : int
        The references.
    free : tuple of str
        The parameters freed.

    Raises
    ------
    ConfigError
        Fewer references than free parameters.
    """
    if n < len(free):
        raise ConfigError("--free", list(free),
                          f"at most {n} parameter(s) with {n} reference(s), one TOF each: "
                          "free fewer (--free NAME), or add references (--reference, "
                          "--reference-recording)")


def fit_warnings(fit: Fit) -> list[str]:
    """What a user of a calibration must know of its fit (empty: nothing): the model's error
    term where the references reject the model, a least squares that did not converge,
    directions the references do not identify (no standard errors then), no degree of
    freedom to test the model on, a covariance that is not finite and positive definite.
    None of these refuses the calibration: it answers, labelled (README "Calibration").

    Parameters
    ----------
    fit : Fit
        The identification.

    Returns
    -------
    list of str
        One sentence per finding.
    """
    out = []
    if fit.model_error is not None:
        out.append(fit.model_error.note())
    if not fit.converged:
        out.append("NOT CONVERGED: the least squares did not converge (Levenberg-Marquardt "
                   "stalled or ran out of iterations): the values are its last iterate")
    if fit.unidentified:
        out.append("NOT IDENTIFIED: the references do not identify every free parameter: "
                   + "; ".join(fit.unidentified) + " (no standard errors: the intervals "
                   "through the calibration lack its term; free fewer parameters, or add "
                   "references that tell them apart)")
    if fit.weights_known and degrees_of_freedom(fit) < 1:
        out.append("as many references as parameters fitted: no degree of freedom to test "
                   "the model on, its error is not estimated (add references)")
    if fit.covariance is not None:
        C = np.asarray(fit.covariance, float)
        if not np.all(np.isfinite(C)) or np.any(np.linalg.eigvalsh(0.5 * (C + C.T)) <= 0):
            out.append("the covariance is not finite and positive definite")
    return out


def leave_one_out_sets(n: int) -> list[tuple[int, ...]]:
    """Every subset of ``range(n)`` without one element (none for n < 2).

    Parameters
    ----------
    n : int
        The number of references.

    Returns
    -------
    list of tuple of int
        The ``n`` subsets, the one without ``i`` at ``i``.
    """
    return [tuple(j for j in range(n) if j != i) for i in range(n)] if n >= 2 else []


def theta_dict(names: tuple[str, ...], theta: np.ndarray) -> dict[str, Any]:
    """Named values, integers as ints.

    Parameters
    ----------
    names : tuple of str
        Parameter names (:data:`ssw.device.PARAMETERS`).
    theta : numpy.ndarray
        Their values, SI.

    Returns
    -------
    dict
        Name -> value (int for an integer parameter, else float).
    """
    return {n: (round(float(v)) if parameter(n).kind == "integer" else float(v))
            for n, v in zip(names, theta, strict=True)}
