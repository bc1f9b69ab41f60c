"""E of a sample with an honest interval: the measured TOF through a (calibrated) device.

For each sample, E is the inverse of the device's TOF(E, nu) at the measured mean TOF
(:func:`ssw.tof.inverse.invert_batch`; at the middle of a Poisson's ratio range). Its
uncertainty combines, as standard uncertainties of ``ln E`` (i.e. relative ones; GUM,
JCGM 100:2008, sec. 5.1: independent contributions add in quadrature):

* ``tof``: the standard error of the mean TOF over the accepted hits,
  ``u = s_T / (T |k|)``, ``k = d ln TOF / d ln E`` at the sample;
* ``calibration``: the covariance ``C`` of the calibrated continuous parameters,
  ``u^2 = g^T C g`` with ``g_j = - (d ln TOF / d theta_j) / k``;
* ``poisson``: a Poisson's ratio known only as a range ``[lo, hi]``, taken as uniform
  (GUM 4.3.7): ``u = |ln E(hi) - ln E(lo)| / sqrt(12)``;
* ``wall``: the stated relative force error ``e`` of the wall law (``wall.force_error``: a
  fit's interpolation error, the FEM's discretisation error): a wall stiffer by ``(1 + e)``
  is a soil stiffer by about ``(1 + e)`` (exactly so for a Hertzian wall on a rigid bead),
  so ``u = e``;
* ``model (TOF)``: where the calibration's references reject its model (their chi^2 with
  the stated TOF uncertainties beyond its 95 % quantile), the calibration carries a relative
  TOF model error ``tau`` (:mod:`ssw.calibration.model_error`: the upper confidence bound
  of the references' misfit, also in the calibration's weights and so in its covariance); a
  sample's TOF departs from the model as a reference's does, so ``u = tau / |k|``
  (:func:`model_term`). Below that quantile there is no term (a calibration its references
  do not reject gives the same interval to the digit); above the degrees of freedom a note
  says so;
* ``integrator``: the TOF error of the time step, ``c (80 / steps_per_contact)^2`` with
  ``c`` the relative error measured at 80 steps against an independent DOP853 solution
  (:data:`INTEGRATOR_REL_ERROR_80`), ``u = c / |k|``.

The derivatives ``k`` and ``d ln TOF / d theta_j`` are the chain's exact forward
sensitivities from the run at the sample's E (:func:`ssw.tof.api.tof_derivatives`), or
its central differences of TOFs for a wall without them (``plastic``, a ``table`` wall's
E).

The interval is ``E exp(+- z u)`` with ``z = 1.96`` (95 % for a normal ``ln E``). Every
contribution is reported, so a user sees what dominates, and every one that could not be
included is listed in ``missing`` with the reason (no calibration, or one without
covariance; a wall law without a stated error; a TOF whose scatter is not estimable): an
interval that lacks a term says so, and a survey verdict on it is inconclusive.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ssw.errors import ConfigError
from ssw.tof.inverse import E_RANGE, invert_batch

#: Coverage factor of the interval (95 % for a normal ln E).
COVERAGE_Z = 1.96
#: Relative TOF error of the default 80 velocity-Verlet steps per contact against an
#: independent DOP853 solution (rtol 1e-10), the largest over soils of 10-1000 MPa (nu 0.3)
#: for the thesis chain at its nominal striker speed (0.52 m/s: 3.5e-5, at 1000 MPa) and at
#: the study's calibrated one (0.39 m/s: 4.95e-5, at 1000 MPa); rounded up. It scales as
#: dt^2 (tests/test_chain_order.py, tests/test_inverse_trust.py).
INTEGRATOR_REL_ERROR_80 = 5.0e-5


@dataclass(frozen=True)
class ModulusEstimate:
    """E (Pa) of one sample with its 95 % interval and the uncertainty budget.

    ``contributions``: standard uncertainty of ln E per source (about the relative
    standard uncertainty of E); ``u``: their quadrature sum.

    Parameters
    ----------
    E : float
        Pa, the sample's Young's modulus (the TOF inversion's).
    E_low : float
        Pa, lower end of the 95 % interval, ``E exp(-1.96 u)``.
    E_high : float
        Pa, upper end of the 95 % interval, ``E exp(+1.96 u)``.
    u : float
        -, standard uncertainty of ln E: the quadrature sum of ``contributions``.
    contributions : dict of str to float
        -, standard uncertainty of ln E per source.
    tof : float
        s, the measured mean TOF inverted.
    tof_sem : float
        s, its standard error (NaN: not known).
    nu : float
        -, the Poisson's ratio of the inversion (a range's middle).
    nu_range : tuple of float or None
        -, the stated Poisson's ratio range ``(lo, hi)``, or None.
    dlnTOF_dlnE : float
        -, the TOF's sensitivity to E at the estimate, ``d ln TOF / d ln E``.
    notes : tuple of str
        Remarks on the estimate (text).
    missing : dict of str to str
        Budget terms left out of the interval, each with the reason.
    extrapolated : bool
        Whether the wall law was used beyond its exact reach.
    """

    E: float
    E_low: float
    E_high: float
    u: float
    contributions: dict[str, float]
    tof: float
    tof_sem: float
    nu: float
    nu_range: tuple[float, float] | None
    dlnTOF_dlnE: float
    notes: tuple[str, ...] = field(default_factory=tuple)
    missing: dict[str, str] = field(default_factory=dict)
    extrapolated: bool = False

    def to_dict(self) -> dict[str, Any]:
        """The estimate as a JSON-ready mapping (SI units, ``coverage`` 0.95).

        Returns
        -------
        dict
            The fields (``missing`` as ``missing_terms``), lists for tuples.
        """
        d = asdict(self)
        d["nu_range"] = None if self.nu_range is None else list(self.nu_range)
        d["notes"] = list(self.notes)
        d["missing_terms"] = d.pop("missing")
        d["coverage"] = 0.95
        return d


def _nu_args(nu: Any, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(central, lo, hi) Poisson's ratios: a number, or (lo, hi) pairs."""
    arr = np.asarray(nu, float)
    if arr.ndim >= 1 and arr.shape[-1] == 2 and (arr.ndim == 2 or (k == 1 and arr.ndim == 1)):
        pairs = np.broadcast_to(arr.reshape(-1, 2), (k, 2))
        lo, hi = pairs[:, 0].copy(), pairs[:, 1].copy()
    else:
        lo = hi = np.broadcast_to(arr, (k,)).astype(float).copy()
    if np.any(~((lo > -1) & (lo <= hi) & (hi <= 0.5))):
        raise ConfigError("soil_nu", np.asarray(nu).tolist(),
                          "Poisson's ratios, or ranges lo:hi, with -1 < lo <= hi <= 0.5")
    return 0.5 * (lo + hi), lo, hi


def _inverted(T: np.ndarray, nu_c: np.ndarray, nu_lo: np.ndarray, nu_hi: np.ndarray,
              params: Any, wall: str, opts: dict[str, Any], E_range: tuple[float, float],
              grid: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """E (Pa) of each sample at its central Poisson's ratio, and ``ln E`` at a range's ends
    (NaN without a range), in one batched inversion (:func:`ssw.tof.inverse.invert_batch`;
    ``grid`` used when it holds every Poisson's ratio)."""
    k = T.size
    ranged = nu_hi > nu_lo
    targets = np.concatenate([T, T[ranged], T[ranged]])
    nus = np.concatenate([nu_c, nu_lo[ranged], nu_hi[ranged]])
    if grid is not None and np.any(grid.group_of(nus, {}) < 0):
        grid = None  # a range's end the grid was not computed for
    inv = invert_batch(targets, nus, params, wall, E_range=E_range, grid=grid, **opts)
    nr = int(ranged.sum())
    lnE_lo = np.full(k, np.nan)
    lnE_hi = np.full(k, np.nan)
    lnE_lo[ranged] = np.log(inv.E[k:k + nr])
    lnE_hi[ranged] = np.log(inv.E[k + nr:])
    return inv.E[:k], lnE_lo, lnE_hi


def _calibration_term(calibration: Any, cov: np.ndarray | None, g: np.ndarray,
                      contrib: dict[str, float], notes: list[str],
                      missing: dict[str, str]) -> None:
    """The ``calibration`` term ``sqrt(g^T C g)`` of one sample (``g_j = - (d ln TOF /
    d theta_j) / k``) into ``contrib``, or why it is missing into ``missing``; a note when
    the calibration holds parameters on their bounds."""
    if cov is not None:
        if calibration.at_bound:  # held parameters: fixed, not part of the covariance
            notes.append("the calibration holds " + ", ".join(
                f"{n} on its {side} bound" for n, side in calibration.at_bound.items())
                + ": its term is conditional on that")
        var = float(g @ cov @ g)
        if not var > 0:
            raise ConfigError("calibration covariance", var,
                              "a positive variance g^T C g of ln E (the covariance is not "
                              "positive definite: recalibrate)")
        contrib["calibration"] = float(np.sqrt(var))
    elif calibration is not None:
        missing["calibration"] = (
            "the calibration has no covariance (its references do not identify every "
            "parameter, or as many parameters as references without TOF uncertainties)")
    else:
        missing["calibration"] = ("uncalibrated device: the uncertainty of its "
                                  "parameters is not known")


def _wall_state(wall: str, params: Any, E: np.ndarray, nu: np.ndarray,
                opts: dict[str, Any], peak: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Each sample's own wall law (at its E, Pa, and Poisson's ratio): whether the chain's
    peak wall indentation ``peak`` (m) lies beyond the law's exact reach, and the law's
    stated relative force error per sample (None: it states none)."""
    from ssw.chain.wall import beyond_exact_reach
    from ssw.walls import build_wall

    w = build_wall(wall, params, E, nu, **opts)
    beyond = beyond_exact_reach(w, peak)
    force_error = getattr(w, "force_error", None)
    if force_error is not None:
        force_error = np.broadcast_to(np.asarray(force_error, float), (E.size,))
    return beyond, force_error


def estimate_moduli(
    tof: Any, tof_sem: Any, nu: Any, params: Any, wall: str,
    wall_options: dict[str, Any] | None = None, *, calibration: Any = None,
    E_range: tuple[float, float] = E_RANGE, grid: Any = None,
) -> list[ModulusEstimate]:
    """E with its interval for ``k`` samples (module docstring), in a few batched runs.

    Parameters
    ----------
    tof : array_like
        (k,) measured mean TOFs, s.
    tof_sem : array_like
        (k,) their standard errors, s; NaN where the scatter is not known (the ``tof``
        term is then listed as missing).
    nu : array_like
        A Poisson's ratio per sample, or (k, 2) ranges ``[lo, hi]``.
    params : ssw.chain.params.ChainParams
        The chain of the (calibrated) device.
    wall : str
        The wall law's name (:data:`ssw.walls.WALLS`).
    wall_options : dict or None
        The wall builder's options.
    calibration : ssw.calibration.Calibration or None
        The calibration whose covariance enters the interval.
    E_range : tuple of float
        ``(lo, hi)``, Pa: the moduli the inversion searches.
    grid : ForwardGrid, optional
        A forward grid of the same device over ``E_range``
        (:func:`ssw.tof.inverse.forward_grid`; the live estimate keeps one): used when it
        holds every inversion's Poisson's ratio, else one is computed.

    Returns
    -------
    list of ModulusEstimate
        One estimate per sample, in the order of ``tof``.
    """
    from ssw.tof import api

    opts = dict(wall_options or {})
    T = np.atleast_1d(np.asarray(tof, float)).ravel()
    k = T.size
    S = np.broadcast_to(np.asarray(tof_sem, float), (k,)).astype(float)
    if np.any(~((S >= 0) | np.isnan(S))):
        raise ConfigError("tof_sem", S.tolist(), "standard errors >= 0 s (NaN: unknown)")
    nu_c, nu_lo, nu_hi = _nu_args(nu, k)
    ranged = nu_hi > nu_lo
    E, lnE_lo, lnE_hi = _inverted(T, nu_c, nu_lo, nu_hi, params, wall, opts, E_range, grid)
    # one run: slope in E, and d TOF / d theta of the calibrated continuous parameters
    # (forward sensitivities where the wall has them, central differences otherwise)
    names: tuple[str, ...] = ()
    cov = None
    if calibration is not None and calibration.covariance is not None:
        names = calibration.covariance_parameters
        cov = calibration.covariance_array()
    der = api.tof_derivatives(E, nu_c, params, wall, derivatives=("E", *names), **opts)
    Tb = np.asarray(der.tof, float)
    slope = E * np.asarray(der.dtof["E"], float) / Tb
    # d ln TOF / d theta_j, (len(names), k)
    dln = np.array([np.asarray(der.dtof[n], float) / Tb for n in names]).reshape(-1, k)
    beyond, force_error = _wall_state(wall, params, E, nu_c, opts, der.run.peak_wall_indentation)
    tau, cal_notes = model_term(calibration)
    integrator = INTEGRATOR_REL_ERROR_80 * (80.0 / float(params.steps_per_contact)) ** 2
    out = []
    for i in range(k):
        contrib: dict[str, float] = {}
        notes: list[str] = list(cal_notes)
        missing: dict[str, str] = {}
        kk = float(slope[i])
        if np.isnan(S[i]):
            missing["tof"] = "the TOF's scatter is not known (too few hits to estimate it)"
        else:
            contrib["tof"] = float(S[i] / (T[i] * abs(kk)))
        _calibration_term(calibration, cov, -dln[:, i] / kk, contrib, notes, missing)
        if tau is not None:  # the references reject the model: its error, the sample's
            contrib[MODEL_TERM] = float(tau / abs(kk))
        if ranged[i]:
            contrib["poisson"] = float(abs(lnE_hi[i] - lnE_lo[i]) / np.sqrt(12.0))
        if beyond[i]:
            notes.append(f"EXTRAPOLATED: the chain presses the {wall} wall deeper than its "
                         "exact law reaches (a tabulated curve's end, the FEM law's computed "
                         "range): the force there is an extension, not the model")
        if force_error is not None and np.isfinite(force_error[i]):
            contrib["wall"] = float(force_error[i])
        else:
            missing["wall"] = f"the {wall} wall states no force error"
        contrib["integrator"] = float(integrator / abs(kk))
        u = float(np.sqrt(sum(v**2 for v in contrib.values())))
        out.append(ModulusEstimate(
            E=float(E[i]), E_low=float(E[i] * np.exp(-COVERAGE_Z * u)),
            E_high=float(E[i] * np.exp(COVERAGE_Z * u)), u=u, contributions=contrib,
            tof=float(T[i]), tof_sem=float(S[i]), nu=float(nu_c[i]),
            nu_range=(float(nu_lo[i]), float(nu_hi[i])) if ranged[i] else None,
            dlnTOF_dlnE=kk, notes=tuple(notes), missing=missing,
            extrapolated=bool(beyond[i])))
    return out


#: The budget's name of a calibration's model-error term (:func:`model_term`).
MODEL_TERM = "model (TOF)"


def model_term(cal: Any) -> tuple[float | None, list[str]]:
    """The TOF model's relative error ``tau`` a measurement through ``cal`` carries, and
    the notes every such measurement states.

    ``tau`` is the calibration's own (:class:`ssw.calibration.model_error.ModelError`, the
    upper confidence bound of a relative TOF error estimated from the references' misfit
    where they reject the model, Birge 1932, Paule & Mandel 1982; one estimator at every
    level, :mod:`ssw.calibration.model_error`); its term in ``ln E`` is ``tau / |d ln TOF /
    d ln E|`` at the sample. None where the references do not reject the model: between
    their degrees of freedom and the rejection quantile (a Birge ratio above 1) a note says
    so and the interval is the calibration's own. The calibration's findings
    (``warnings``: no convergence, a direction not identified) are notes too.

    Parameters
    ----------
    cal : ssw.calibration.Calibration or None
        The calibration.

    Returns
    -------
    tuple of (float or None, list of str)
        ``tau`` (1) or None, and the notes.

    References
    ----------
    R. T. Birge, "The calculation of errors by the method of least squares", Phys. Rev.
    40, 207 (1932); R. C. Paule and J. Mandel, "Consensus values and weighting factors",
    J. Res. Natl. Bur. Stand. 87, 377 (1982).
    """
    if cal is None:
        return None, []
    notes = [f"the calibration: {w}" for w in cal.warnings
             if not w.startswith(("MODEL ERROR", "RECORDS"))]  # (those: stated below, or by
    # a fit of records, ssw.measure.measure_information)
    term = cal.model_term()
    if term is not None:
        notes.append(f"{term.note()}: the term '{MODEL_TERM}' is tau / |d ln TOF / d ln E| "
                     "at the sample")
        return term.tau, notes
    chi2 = cal.provenance.get("chi2")
    dof = len(cal.references) - (len(cal.free) - len(cal.at_bound))
    if ("given" in str(cal.provenance.get("weights", "")) and chi2 is not None and dof >= 1
            and chi2 > dof):
        notes.append(f"the references' chi2 {chi2:.3g} exceeds its {dof} degree(s) of "
                     "freedom (the model does not reach them within their TOF "
                     "uncertainties) but stays below its 95 % quantile: the model is not "
                     "rejected and the interval is the calibration's own")
    return None, notes


class Estimator:
    """E with its interval from (mean TOF, standard error), fast enough to call after every
    hit (``ssw acquire``'s running E; :class:`ssw.signal.live.LiveTof`).

    E is the inversion ``ssw measure`` makes (:func:`ssw.tof.inverse.invert_batch`, with
    its guards and its secant refinement on the forward model), on the device's forward
    grid computed once (:func:`ssw.tof.inverse.forward_grid`, one batched run): the same
    recording gives the same E live and in ``ssw measure``. The contributions that do not
    depend on the TOF's scatter (calibration, the TOF model's error where the calibration
    carries one, Poisson's ratio, wall law, integrator) come
    from one full :func:`estimate_moduli` at the first estimate's TOF and are kept (they
    change slowly with E); the TOF's own contribution is recomputed at every call, with the
    slope ``d ln E / d TOF`` of the inversion's own interpolant on the grid (the derivative
    of :meth:`ssw.tof.inverse.ForwardGrid.interpolant`).

    Parameters
    ----------
    params : ChainParams
        The (calibrated) device's chain.
    wall : str
        The wall law's name.
    wall_options : dict, optional
        The wall law's options.
    nu : array_like
        The sample's Poisson's ratio, or its range ``(lo, hi)`` (E at its middle).
    calibration : Calibration, optional
        The calibration whose covariance enters.
    E_range : tuple of float
        ``(E_min, E_max)`` of the inversion, Pa.
    extra : dict, optional
        Further TOF uncertainties (s) per name, turned into ln E terms (e.g. sampling).

    Raises
    ------
    SolverError
        The forward TOF(E) is not invertible (:func:`ssw.tof.inverse.grid_fault`).
    """

    def __init__(self, params: Any, wall: str, wall_options: dict[str, Any] | None,
                 nu: Any, *, calibration: Any = None, E_range: tuple[float, float] = E_RANGE,
                 extra: dict[str, float] | None = None) -> None:
        from ssw.errors import SolverError
        from ssw.tof.inverse import forward_grid, grid_fault

        self.params, self.wall, self.opts = params, wall, dict(wall_options or {})
        self.nu, self.calibration, self.E_range = nu, calibration, E_range
        self.extra = dict(extra or {})  # further ln E contributions per TOF, e.g. sampling
        self.nu_c = float(_nu_args(nu, 1)[0][0])
        self.grid = forward_grid(self.nu_c, params, wall, E_range=E_range, **self.opts)
        E, T = self.grid.E, self.grid.T[0]
        fault = grid_fault(E, T, self.nu_c)
        if fault:
            raise SolverError(fault)
        # d ln E / d TOF: the inversion's own interpolant's derivative
        self._slope = self.grid.interpolant(0).derivative()
        self.tof_range = (float(T[-1]), float(T[0]))
        self._fixed: dict[str, float] | None = None

    def __call__(self, tof_mean: float, tof_sem: float) -> dict[str, Any]:
        """``{"E", "E_low", "E_high", "u", "contributions"}`` (Pa; ln E standard
        uncertainties) for a mean TOF (s) and its standard error (s).

        Raises
        ------
        OutOfRangeError
            The TOF lies outside the device's range over ``E_range``.
        """
        E = float(invert_batch([tof_mean], self.nu_c, self.params, self.wall,
                               E_range=self.E_range, grid=self.grid, **self.opts).E[0])
        if self._fixed is None:
            est = estimate_moduli([tof_mean], [0.0], np.asarray(self.nu, float), self.params,
                                  self.wall, self.opts, calibration=self.calibration,
                                  E_range=self.E_range, grid=self.grid)[0]
            self._fixed = {k: v for k, v in est.contributions.items() if k != "tof"}
            self.notes = est.notes
        dlnE_dT = abs(float(self._slope(tof_mean)))
        contrib = {"tof": float(tof_sem) * dlnE_dT, **self._fixed}
        for k, v in self.extra.items():  # TOF uncertainties (s) -> ln E
            contrib[k] = float(v) * dlnE_dT
        u = float(np.sqrt(sum(v**2 for v in contrib.values())))
        return {"E": E, "E_low": E * float(np.exp(-COVERAGE_Z * u)),
                "E_high": E * float(np.exp(COVERAGE_Z * u)), "u": u, "contributions": contrib}
