"""What each level of information identifies: singular values, correlations and marginal
uncertainties of the parameters, at stated noise (``ssw identify``).

For a model's observations ``y(theta)`` with standard deviations ``s`` (independent), the
whitened Jacobian ``A = (dy / dx) / s`` in the scaled coordinates ``x`` of the parameters
(``ln theta`` for a log-scaled one, ``theta / scale`` otherwise:
:data:`ssw.calibration.hits.PARAMETERS`) gives the Fisher information ``A^T A`` (Bard
1974; Press et al. 2007, sec. 15.5). Nuisance parameters (a hit's time offset and
delay) are profiled out: the information of the parameters of interest is that of ``(I -
P_b) A_a``, ``P_b`` the projection onto the nuisances' columns (the Schur complement).
Independent hits add their information.

Stated here (:func:`summarize`):

* the **singular values** of the profiled whitened Jacobian: a direction ``v`` with
  singular value ``sigma`` moves the observations by one standard deviation when the
  parameters move by ``1 / sigma`` along ``v`` (scaled units);
* the **marginal standard uncertainty** of each parameter, every other parameter free
  (the diagonal of the pseudo-inverse; infinite when the parameter has a share in a
  direction the data do not see at all);
* the **correlations** between the parameters;
* **identified** (:data:`IDENTIFIED_U`): a parameter whose marginal standard uncertainty,
  every other parameter free, is at most 0.1 in its scaled coordinate: 10 % of its value
  for a log-scaled parameter (E, the masses, the striker speed, the gain), a tenth of its
  scale for the others (0.05 for nu, 0.5 N for the preload, a tenth of the dissipation
  law's typical coefficient for the contact dissipation: 0.5 N s/m for the dashpot,
  :func:`ssw.chain.dissipation.parameter`).

The contact dissipation (``damping``) is the coefficient of the device's law
(:mod:`ssw.chain.dissipation`), in the law's unit and scaled coordinate.

References
----------
Bard, Y. (1974). *Nonlinear Parameter Estimation*. Academic Press, ch. 7.
Press, W. H., Teukolsky, S. A., Vetterling, W. T. and Flannery, B. P. (2007). *Numerical
Recipes*, 3rd ed., sec. 15.5.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

#: A parameter is identified when its marginal standard uncertainty (scaled coordinate,
#: every other parameter free) is at most this.
IDENTIFIED_U = 0.1
#: Singular values below this share of the largest are a direction the data do not see:
#: the model's waveform is computed to ~1e-5 of its largest sensitivity (its forward
#: sensitivities against fourth-order differences of its samples), so a smaller singular
#: value cannot be told from an exact degeneracy (a half-space's E / (1 - nu^2)).
NULL_RTOL = 1e-5


#: A parameter whose unit vector has more than this share in the directions the data do
#: not see has no marginal uncertainty (infinite); below it, the share is the null
#: direction's numerical tilt.
BLIND_SHARE = 1e-3


@dataclass(frozen=True)
class Information:
    """The information a set of observations carries on parameters of interest.

    Parameters
    ----------
    names : tuple of str
        The parameters of interest.
    singular_values : numpy.ndarray
        (q,) of the profiled whitened Jacobian, largest first.
    vectors : numpy.ndarray
        (q, q) its right singular vectors (columns).
    std : numpy.ndarray
        (q,) marginal standard uncertainties, scaled coordinates (inf: not estimable).
    correlation : numpy.ndarray
        (q, q) correlations (NaN where a standard uncertainty is infinite).
    observations : int
        Rows of the Jacobian (data and priors).
    """

    names: tuple[str, ...]
    singular_values: np.ndarray
    vectors: np.ndarray
    std: np.ndarray
    correlation: np.ndarray
    observations: int

    @property
    def identified(self) -> tuple[str, ...]:
        """The parameters with a marginal standard uncertainty at most
        :data:`IDENTIFIED_U`."""
        return tuple(n for n, s in zip(self.names, self.std, strict=True)
                     if s <= IDENTIFIED_U)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: singular values, standard uncertainties, correlations, identified.

        Returns
        -------
        dict
            ``parameters``, ``singular_values``, ``std_scaled`` (None: not estimable),
            ``correlation``, ``identified``, ``observations``.
        """
        def num(v: float) -> float | None:
            return float(v) if np.isfinite(v) else None

        return {
            "parameters": list(self.names),
            "singular_values": [float(s) for s in self.singular_values],
            "std_scaled": {n: num(s) for n, s in zip(self.names, self.std, strict=True)},
            "correlation": [[num(c) for c in row] for row in self.correlation],
            "identified": list(self.identified), "observations": self.observations,
        }


def profile(A: np.ndarray, interest: np.ndarray) -> np.ndarray:
    """The whitened Jacobian of the parameters of interest with the others (nuisances)
    profiled out: ``(I - P_b) A_a``.

    Parameters
    ----------
    A : numpy.ndarray
        (n, p) whitened Jacobian, scaled coordinates.
    interest : numpy.ndarray
        (p,) bool, the parameters of interest.

    Returns
    -------
    numpy.ndarray
        (n, q) the interest columns orthogonal to the nuisances' span.
    """
    Aa, Ab = A[:, interest], A[:, ~interest]
    if Ab.shape[1] == 0:
        return Aa
    Q, s, _ = np.linalg.svd(Ab, full_matrices=False)
    Q = Q[:, s > NULL_RTOL * max(float(s.max(initial=0.0)), 1e-300)]
    return Aa - Q @ (Q.T @ Aa)


def summarize(Ap: np.ndarray, names: tuple[str, ...], observations: int | None = None
              ) -> Information:
    """Singular values, marginal uncertainties and correlations of a profiled whitened
    Jacobian (module docstring).

    Parameters
    ----------
    Ap : numpy.ndarray
        (n, q) profiled whitened Jacobian (:func:`profile`), or any matrix whose Gram
        matrix is the information (e.g. stacked hits).
    names : tuple of str
        The q parameters.
    observations : int or None
        Rows counted (default ``n``).

    Returns
    -------
    Information
        The summary.
    """
    _, s, Vt = np.linalg.svd(Ap, full_matrices=True)
    q = len(names)
    sv = np.zeros(q)
    sv[: s.size] = s
    V = Vt.T
    live = sv > NULL_RTOL * max(float(sv.max(initial=0.0)), 1e-300)
    var = (V[:, live] ** 2 / sv[live] ** 2).sum(axis=1)
    blind = (V[:, ~live] ** 2).sum(axis=1) > BLIND_SHARE**2
    std = np.where(blind, np.inf, np.sqrt(var))
    cov = (V[:, live] / sv[live] ** 2) @ V[:, live].T
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.sqrt(np.diag(cov))
        corr = cov / np.outer(d, d)
    corr[blind, :] = np.nan
    corr[:, blind] = np.nan
    return Information(tuple(names), sv, V, std, corr,
                       int(Ap.shape[0] if observations is None else observations))


def given(info_A: np.ndarray, names: tuple[str, ...], known: tuple[str, ...],
          observations: int | None = None) -> Information:
    """The information of the parameters other than ``known`` when those are known (their
    columns removed: conditional, not marginal).

    Parameters
    ----------
    info_A : numpy.ndarray
        (n, q) profiled whitened Jacobian over ``names``.
    names : tuple of str
        Its columns.
    known : tuple of str
        Parameters held at known values.
    observations : int or None
        Rows counted.

    Returns
    -------
    Information
        Over the remaining parameters.
    """
    keep = [j for j, n in enumerate(names) if n not in known]
    return summarize(info_A[:, keep], tuple(names[j] for j in keep), observations)


#: The parameters ``ssw identify`` reports, in order.
INTEREST = ("E", "nu", "striker_velocity", "preload", "sensor_mass", "striker_mass",
            "damping", "gain")
#: Step of nu's fourth-order central difference (the chain has no sensitivity to it; the
#: difference's error, ~h^4, stays far below the whitened information's resolution, so an
#: exact degeneracy, a half-space's E / (1 - nu^2), shows as one).
NU_STEP = 1e-3
#: The fourth-order central stencil: offsets (in steps) and weights over 12 h.
NU_OFFSETS, NU_WEIGHTS = (-2.0, -1.0, 1.0, 2.0), (1.0, -8.0, 8.0, -1.0)


@dataclass(frozen=True)
class Identifiability:
    """What TOF, features and the whole waveform identify on one sample (module
    docstring). SI units.

    Parameters
    ----------
    levels : dict
        Level -> :class:`Information` over :data:`INTEREST`, every parameter free.
    nu_known : dict
        Level -> :class:`Information` over the others, nu known (as a measurement takes
        it).
    device_known : dict
        Level -> :class:`Information` over E alone, nu and the device known (a calibrated
        device's measurement).
    values : dict
        The parameters' values, SI (``damping`` in its law's unit).
    noise : dict
        ``tof_scatter`` (s per hit), ``noise_rms`` (N), ``hits``, ``sample_rate`` (S/s).
    damping_law : str
        The contacts' dissipation law (:mod:`ssw.chain.dissipation`): the unit and scale
        of ``damping``, the contact dissipation.
    """

    levels: dict[str, Information]
    nu_known: dict[str, Information]
    device_known: dict[str, Information]
    values: dict[str, float]
    noise: dict[str, float]
    damping_law: str = "dashpot"

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (the criterion stated; ``std``: :func:`natural` units; ``labels``:
        each parameter's name in words, the contact dissipation's with its law).

        Returns
        -------
        dict
            Per level the information's mapping, with the values, noise and labels.
        """
        from ssw.calibration.waveform import parameter
        from ssw.chain.dissipation import law_of

        law = law_of(self.damping_law)

        def par(n: str) -> Any:
            return parameter(n, self.damping_law)

        tenth = f"{IDENTIFIED_U * law.scale:g} {law.unit}"
        return {
            "criterion": (f"identified: marginal standard uncertainty <= {IDENTIFIED_U} in "
                          "the scaled coordinate (10 % of the value for E, the masses, the "
                          "striker speed and the gain; 0.05 for nu; 0.5 N for the preload; "
                          f"{tenth} for the contact dissipation, {law.name}), every other "
                          "parameter free"),
            "values": dict(self.values), "noise": dict(self.noise),
            "damping_law": law.name,
            "labels": {**{n: n for n in INTEREST},
                       "damping": f"contact dissipation ({law.name}: {law.formula})"},
            "coordinates": {n: ("log" if par(n).log else
                                f"linear, scale {par(n).scale:g} {par(n).unit}")
                            for n in INTEREST},
            "units": {n: par(n).unit for n in INTEREST},
            "std": {view: {lv: natural(info, self.damping_law) for lv, info in d.items()}
                    for view, d in (("levels", self.levels), ("nu_known", self.nu_known),
                                    ("device_known", self.device_known))},
            "levels": {k: v.as_dict() for k, v in self.levels.items()},
            "nu_known": {k: v.as_dict() for k, v in self.nu_known.items()},
            "device_known": {k: v.as_dict() for k, v in self.device_known.items()},
        }


def natural(info: Information, damping_law: str = "dashpot") -> dict[str, float | None]:
    """Marginal standard uncertainties in natural units: relative (a fraction) for a
    log-scaled parameter, SI for the others (the contact dissipation's in the unit of
    ``damping_law``; None: not estimable).

    Parameters
    ----------
    info : Information
        The summary.
    damping_law : str
        The contacts' dissipation law (:mod:`ssw.chain.dissipation`).

    Returns
    -------
    dict
        Name -> the uncertainty, or None.
    """
    from ssw.calibration.waveform import parameter

    out: dict[str, float | None] = {}
    for n, s in zip(info.names, info.std, strict=True):
        p = parameter(n, damping_law)
        out[n] = None if not np.isfinite(s) else float(s if p.log else s * p.scale)
    return out


def _records_rows(setup: Any, state: Any, cols: list[Any], scale_nu: float) -> np.ndarray:
    """One hit's observations of a level in the scaled coordinates, weighted by their
    standard deviations: the columns ``cols`` (the first :data:`INTEREST` but ``nu``, then
    the nuisances) with ``nu``'s inserted second, its derivative a five-point central
    difference of step :data:`NU_STEP` (``nu`` is no parameter of the model).

    Parameters
    ----------
    setup : ssw.calibration.observation.Setup
        The model and the one hit's record (its time step fixed here).
    state : ssw.calibration.hits.State
        The parameters' values (SI).
    cols : list of ssw.calibration.hits.Column
        The columns, in order.
    scale_nu : float
        ``nu``'s scaled coordinate's unit.

    Returns
    -------
    numpy.ndarray
        (n_ok, len(cols) + 1) the rows with a finite model and Jacobian.
    """
    from dataclasses import replace as dc_replace

    from ssw.calibration.waveform import dtheta_dx, get, observe

    rec = setup.samples[0]
    setup.fix_step(state)
    obs = observe(setup, state)
    d_nu = 0.0
    for o, w in zip(NU_OFFSETS, NU_WEIGHTS, strict=True):
        moved = dc_replace(rec, nu=rec.nu + o * NU_STEP)
        d_nu = d_nu + w * observe(dc_replace(setup, samples=[moved], runs=0), state,
                                  wanted={"striker_velocity"}).model
    d_nu = d_nu / (12 * NU_STEP)
    index = {c: j for j, c in enumerate(obs.columns)}
    vals = np.array([get(state, c) for c in cols])
    scaled = dtheta_dx(setup, cols, vals)
    J = np.column_stack([obs.jacobian[:, index[c]] for c in cols])
    J = J * scaled[None, :]
    J = np.insert(J, 1, d_nu * scale_nu, axis=1)
    ok = np.isfinite(obs.model) & np.all(np.isfinite(J), axis=1)
    return J[ok] / obs.sigma[ok, None]


def _tof_row(params: Any, wall: str, wall_options: dict[str, Any], E: float, nu: float,
             scale_of: Any) -> np.ndarray:
    """The TOF's derivatives by :data:`INTEREST` in the scaled coordinates (s per unit; the
    gain's 0), ``nu``'s a five-point central difference of step :data:`NU_STEP`.

    Parameters
    ----------
    params : ChainParams
        The device's chain.
    wall : str
        The wall law.
    wall_options : dict
        Its options.
    E : float
        Pa, the sample's modulus.
    nu : float
        Its Poisson's ratio.
    scale_of : callable
        A parameter's name -> its scaled coordinate's unit.

    Returns
    -------
    numpy.ndarray
        (1, len(INTEREST)) the row.
    """
    from ssw.calibration.waveform import device_globals
    from ssw.tof import api

    glob = device_globals(params)
    td = api.tof_derivatives(E, nu, params, wall, **wall_options)
    T = np.asarray(api.tof(E, nu + np.array(NU_OFFSETS) * NU_STEP, params, wall,
                           **wall_options), float)
    row = [float(td.dtof["E"]) * E, float(np.dot(NU_WEIGHTS, T)) / (12 * NU_STEP) * scale_of("nu"),
           float(td.dtof["striker_velocity"]) * params.striker_velocity,
           float(td.dtof["preload"]) * scale_of("preload"),
           float(td.dtof["sensor_mass"]) * glob["sensor_mass"],
           float(td.dtof["striker_mass"]) * glob["striker_mass"],
           float(td.dtof["damping"]) * scale_of("damping"), 0.0]
    return np.array([row])


def identifiability(params: Any, wall: str, wall_options: dict[str, Any], E: float,
                    nu: float, settings: Any, *, hits: int = 5, tof_scatter: float = 1.53e-5,
                    noise: float | None = None, seed: int = 0) -> Identifiability:
    """The information of TOF, features and the whole waveform on :data:`INTEREST` for one
    sample, at the noise of a real recording (module docstring).

    The record is the model's own (noise-free, through :mod:`ssw.daq.model` with the
    acquisition ``settings``); its observations' standard deviations are the noise's: a
    TOF ``tof_scatter`` per hit; the features and samples the module's noise floor
    ``noise``, with each hit's time offset and delay (prior ``tof_scatter``) as nuisances
    (:mod:`ssw.calibration.waveform`). ``hits`` independent hits add their information.

    Parameters
    ----------
    params : ChainParams
        The device's chain (its striker speed, preload, masses, dissipation coefficient:
        the values; its dissipation law, ``damping_law``, the coefficient's unit).
    wall : str
        The wall law.
    wall_options : dict
        Its options.
    E : float
        Pa, the sample's modulus.
    nu : float
        Its Poisson's ratio.
    settings : ssw.daq.settings.DaqSettings
        The acquisition (rate, sensitivity, coupling, record and trigger).
    hits : int
        Hits averaged.
    tof_scatter : float
        s, one hit's TOF scatter (the thesis: 1.53e-5 s).
    noise : float or None
        N rms, the noise floor (default: the NI 9234's, :mod:`ssw.daq.model`).
    seed : int
        The record's sample phase.

    Returns
    -------
    Identifiability
        Per level, all free and nu known.
    """
    from dataclasses import replace as dc_replace

    from ssw.calibration.waveform import (
        Column,
        Hits,
        Setup,
        State,
        device_globals,
        parameter,
    )
    from ssw.daq.model import Acquisition
    from ssw.daq.settings import SimulationSettings
    from ssw.daq.simulated import SimulatedBackend

    quiet = dc_replace(settings, simulation=SimulationSettings(
        noise_rms=0.0, trigger_jitter=0.0, striker_velocity_cov=0.0))
    acq = Acquisition.of(settings, noise_rms=noise)
    hit = next(SimulatedBackend(soil_E=E, soil_nu=nu, chain_params=params, wall=wall,
                                wall_options=wall_options, seed=seed).hits(quiet, 1))
    rec = Hits.of(hit.force[None, :], [hit.trigger_index], acq.sample_rate, E=E, nu=nu,
                  noise=acq.noise)
    fs = acq.sample_rate
    tau = hit.extra["t_first_sample"] + hit.trigger_index / fs
    glob = device_globals(params)
    state = State(np.array([E]), np.array([params.striker_velocity]), np.array([tau]),
                  np.zeros(1), glob)
    values = {"E": E, "nu": nu, "striker_velocity": params.striker_velocity, **glob}
    cols = [Column("E", 0), None, Column("striker_velocity", 0), Column("preload"),
            Column("sensor_mass"), Column("striker_mass"), Column("damping"),
            Column("gain")]
    nuis = [Column("time_offset", 0), Column("delay", 0)]
    levels, known, alone = {}, {}, {}
    device = tuple(n for n in INTEREST if n != "E")
    def scale_of(name: str) -> float:
        return parameter(name, params.damping_law).scale

    scale_nu = scale_of("nu")
    for level in ("features", "waveform"):
        setup = Setup(params, wall, wall_options, acq, level, [rec], settings.trigger_level,
                      tof_scatter=tof_scatter)
        A = _records_rows(setup, state, [c for c in cols if c] + nuis, scale_nu)
        interest = np.arange(A.shape[1]) < len(INTEREST)
        Ap = profile(A, interest) * np.sqrt(hits)
        levels[level] = summarize(Ap, INTEREST, A.shape[0] * hits)
        known[level] = given(Ap, INTEREST, ("nu",), A.shape[0] * hits)
        alone[level] = given(Ap, INTEREST, device, A.shape[0] * hits)
    # TOF: one per hit, the chain's (the TOF level's model), scatter tof_scatter
    A = _tof_row(params, wall, wall_options, E, nu, scale_of) / tof_scatter * np.sqrt(hits)
    levels = {"tof": summarize(A, INTEREST, hits), **levels}
    known = {"tof": given(A, INTEREST, ("nu",), hits), **known}
    alone = {"tof": given(A, INTEREST, device, hits), **alone}
    return Identifiability(levels, known, alone, values,
                           {"tof_scatter": tof_scatter, "noise_rms": acq.noise,
                            "hits": hits, "sample_rate": fs}, params.damping_law)
