"""What a hit's record says beyond its TOF: the observations of a level of information and
their exact derivatives.

Three levels (``--information``):

* ``tof``: one TOF per hit (today's calibration and measurement, :mod:`ssw.calibration.fit`,
  :mod:`ssw.modulus`);
* ``features``: per hit the seven features of :mod:`ssw.signal.features` (TOF, the
  reflected-to-incident amplitude ratio, the secondary reflection's TOF and amplitude
  ratio, both pulse widths, the incident amplitude);
* ``waveform``: per hit every sample of the record from just before the trigger to the
  end of the secondary reflected pulse (the rattle after it is chaotic and is not used).

The model of a record (:func:`observe`): the chain (:func:`ssw.tof.api.sensor_derivatives`,
its dense output with forward sensitivities and time derivative) through the measurement
model (:mod:`ssw.daq.model`), sampled at the record's sample times, then, for ``features``,
the same upsampling and feature extraction as the record (:mod:`ssw.signal.features`). A
simulated record and a recorded one are the same kind of object, so the residuals compare
like with like, and every derivative is exact: the chain's sensitivities through the linear
measurement model (and the extractor's chain rule).

Parameters (:data:`~ssw.calibration.hits.PARAMETERS`; SI, each with its scaled coordinate,
``ln x`` or ``x / scale``):

* per sample: ``E`` (known for a reference, free for a measured sample);
* per hit: the striker speed ``striker_velocity`` (hits differ; the amplitude and the pulse
  widths tell each hit's own), the trigger's time offset ``time_offset`` (the chain time of
  the record's trigger sample) and a ``delay`` of the reflected waves;
* global (the device): ``preload``, ``sensor_mass``, ``striker_mass``, ``damping`` (the
  contact dashpot), ``gain`` (the DAQ gain: true over stated sensitivity).

Two per-hit priors enter as observations of their own (kinds ``trigger`` and ``delay``):

* the **trigger**: an analog-edge trigger fires at the first sample at or above its level,
  so the trigger sample lies within one sample period after the model's crossing ``t_c``
  of the level: ``time_offset - t_c - 1/(2 f_s)`` has standard deviation ``1 / (f_s
  sqrt 12)`` (a uniform phase), with the trigger's jitter added. A record whose time
  offset the trigger does not explain (a delayed channel, a wrong pretrigger count) fails
  here;
* the **delay**: a real device's hits scatter in TOF beyond what their striker speeds
  explain (the thesis: 1.53e-5 s per hit); a shift ``delay`` of the reflected waves (the
  record after the midpoint between the incident and reflected peaks) with a zero-mean
  prior of that standard deviation carries it, so that the TOF itself weighs no more than
  the stated scatter allows, and the other features and samples bring what they add.

A measured global enters as one more (kind ``prior``): the striker's weighed mass, the
device file's value with the uncertainty the file states (``striker.mass_std``), else the
relative width of :data:`~ssw.calibration.hits.GLOBAL_PRIORS` (under model error the
records alone trade it for the DAQ gain; Brynjarsdottir and O'Hagan 2014).

References
----------
Brynjarsdottir, J. and O'Hagan, A. (2014). Learning about physical parameters: the
importance of model discrepancy. Inverse Problems 30, 114007.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace  # noqa: F401
from typing import Any

import numpy as np

# The records, the model's observations, the fit and the start, re-exported: every name
# of the calibration of records stays importable from here.
from ssw.calibration.hits import (  # noqa: F401
    CHAIN_GLOBALS,
    GLOBALS,
    LEAD,
    LEVELS,
    PARAMETERS,
    PER_HIT,
    RAIL_SHARE,
    TAIL_SAMPLES,
    TAIL_WIDTHS,
    Column,
    Hits,
    State,
    _record_features,
    columns_of,
    device_globals,
    get,
    measured_priors,
    parameter,
    put,
)
from ssw.calibration.model_error import FLOOR_CONFIDENCE, floor_bound  # noqa: F401
from ssw.calibration.observation import (  # noqa: F401
    Observed,
    Setup,
    _bounds,
    _corrected,
    _features,
    _names,
    _recorded,
    coordinate,
    dtheta_dx,
    from_x,
    initial_state,
    observe,
    to_x,
)
from ssw.calibration.start import (  # noqa: F401
    REFINE_LEVELS,
    REFINE_POINTS,
    START_DAMPING,
    START_FLOOR,
    START_ITERATIONS,
    START_SENSOR_MASS,
    _fit_points,
    global_start,
    model_floor,
    refine_start,
    start_damping,
)
from ssw.calibration.waveform_fit import (  # noqa: F401
    FLAG_QUANTILE,
    Fit,
    _Explained,
    _residuals,
    _weighted,
    fit,
    global_covariance,
    noise_std,
    propagated,
)
from ssw.daq.model import Acquisition, filter_fine, fine_grid, trigger_time  # noqa: F401
from ssw.device import PARAMETERS as DEVICE_PARAMETERS  # noqa: F401
from ssw.device import Parameter  # noqa: F401
from ssw.errors import ConfigError, RecordingError  # noqa: F401
from ssw.signal.features import NAMES as FEATURES
from ssw.signal.features import pulse_features, upsample  # noqa: F401
from ssw.signal.peaks import UPSAMPLE  # noqa: F401

#: Fits of the global parameters with the floor re-estimated from their residuals
#: (:func:`model_floor`) after the first, at most; they stop when the floor settles
#: (every kind within :data:`FLOOR_RTOL` of the last pass's).
FLOOR_PASSES = 4
#: The floor's relative change that counts as settled.
FLOOR_RTOL = 0.1


def calibrate_records(samples: list[Hits], params: Any, wall: str,
                      wall_options: dict[str, Any], acq: Acquisition, level: str,
                      trigger_level: float, tof_scatter: float,
                      free_globals: tuple[str, ...] = GLOBALS, scan: bool = True,
                      gain: float = 1.0,
                      start_grid: tuple[tuple[float, ...], tuple[float, ...]] | None = None,
                      refine_levels: int = REFINE_LEVELS, discrepancy: bool = True,
                      prior: dict[str, Any] | None = None) -> Fit:
    """Fit the device's global parameters to reference records (every sample's E known):
    every one of ``free_globals`` with each hit's striker speed, time offset and delay,
    each measured global (:data:`~ssw.calibration.hits.GLOBAL_PRIORS`: the striker's
    mass) held near the device file's value by its prior.

    1. The start (``_start``): when the sensor's mass and the dashpot may be freed, the
       best point of a grid of them refined around it (:func:`global_start`,
       :func:`refine_start`); else (or with ``scan`` False) the device's values, the hits
       fitted with the globals held, and the model-error floor their residuals call for.
    2. A fit of every free parameter, the floor re-estimated from its residuals
       (:func:`model_floor`) and the fit again until the floor settles (``_settled``): a
       calibration's chi^2 is then its degrees of freedom by construction; what it says
       about the model is the floor (in the result and every measurement's weights).
    3. If some global is not identified, the fit again with only the identified ones
       free, the others at their start's values (``_identified``).
    4. Under model error at the features level (a kind's floor above
       :data:`~ssw.calibration.start.START_FLOOR`; two references or more;
       ``discrepancy``): the model's discrepancy (:mod:`ssw.calibration.discrepancy`)
       estimated with the hits refitted, then the floor its corrected residuals leave and
       the fit of step 2 with it (``_with_discrepancy``).

    Parameters
    ----------
    samples : list of Hits
        The references' records, each with its E.
    params : ChainParams
        The device's chain (the start, and the values of what is not freed).
    wall : str
        The wall law.
    wall_options : dict
        Its options.
    acq : Acquisition
        The measurement model.
    level : str
        ``features`` or ``waveform``.
    trigger_level : float
        N, the records' trigger level.
    tof_scatter : float
        s, a hit's TOF scatter (the delays' prior).
    free_globals : tuple of str
        The globals that may be freed (:data:`~ssw.calibration.hits.GLOBALS`).
    scan : bool
        Start from :func:`global_start` when the sensor's mass and the dashpot may be
        freed; False: from ``params`` (a calibration of the same records at another level,
        e.g. the waveform's from the features').
    gain : float
        The DAQ gain's start (another level's calibration's).
    start_grid : tuple or None
        The global start's sensor masses (multiples of the device's) and contact dissipation
        coefficients (the unit of ``params.damping_law``; N s/m for the dashpot); None:
        :data:`~ssw.calibration.start.START_SENSOR_MASS` by :func:`start_damping` of the law.
    refine_levels : int
        Refinements of the global start (:func:`refine_start`).
    discrepancy : bool
        Step 4 where the features' floor says the model departs (False: the floor alone).
    prior : dict or None
        The measured globals' priors (:func:`measured_priors`' ``prior``: another level's,
        the device file's values); None: :func:`measured_priors` of ``params``.

    Returns
    -------
    Fit
        The last fit (its ``free`` lists the globals it identified first; its ``floor`` the
        model-error floor; its ``discrepancy`` the correction, if any; its ``start`` the grid).

    Raises
    ------
    ConfigError
        A reference without its E.
    """
    if any(s.E is None for s in samples):
        raise ConfigError("reference", [s.id for s in samples if s.E is None],
                          "references with a known E")
    setup = Setup(params, wall, dict(wall_options), acq, level, samples, trigger_level,
                  tof_scatter=tof_scatter)
    glob = device_globals(params, gain)
    setup.prior = measured_priors(glob, free_globals, prior)
    E = np.array([s.E for s in samples], float)
    v0 = float(params.striker_velocity)
    n_h = setup.n_hits
    setup.fix_step(State(E, np.full(n_h, 1.5 * v0), np.zeros(n_h), np.zeros(n_h), glob))
    per_hit = [Column(name, h) for name in PER_HIT for h in range(n_h)]
    free = [Column(g) for g in free_globals]
    grid = ((start_grid or (None, None))
            if scan and {"sensor_mass", "damping"} <= set(free_globals) else None)
    state, scan = _start(setup, glob, E, v0, per_hit, grid, refine_levels)
    f = _settled(setup, fit(setup, state, free + per_hit), free + per_hit)
    f, free = _identified(setup, f, state, free, per_hit)
    if (discrepancy and level == "features" and len(samples) >= 2
            and max(f.floor.values(), default=0.0) > START_FLOOR):
        f = _with_discrepancy(setup, f.state, free, per_hit)
    return replace(f, start=scan)


def _start(setup: Setup, glob: dict[str, float], E: np.ndarray, v0: float,
           per_hit: list[Column], grid: tuple[Any, Any] | None,
           refine_levels: int) -> tuple[State, list[dict]]:
    """Step 1 of :func:`calibrate_records`: the start of the globals' fit, and the
    model-error floor of its weights.

    Parameters
    ----------
    setup : Setup
        The model and the records (its ``floor`` is set).
    glob : dict
        The device's globals (SI; :func:`device_globals`).
    E : numpy.ndarray
        (n_samples,) the references' Young's moduli, Pa.
    v0 : float
        m/s, the device's striker speed.
    per_hit : list of Column
        Every hit's parameters.
    grid : tuple or None
        The global start's sensor masses and dissipation coefficients (each None: the
        default grid): the best point of the grid (:func:`global_start`, weights with the
        floor :data:`~ssw.calibration.start.START_FLOOR`) refined around it
        (:func:`refine_start`). None: the device's values, each hit's parameters fitted with the
        globals held, and the floor
        their residuals call for (:func:`model_floor`).
    refine_levels : int
        Refinements of the global start.

    Returns
    -------
    tuple
        The start's state and the grid's points (empty without a grid).
    """
    if grid is not None:
        kinds = FEATURES if setup.level == "features" else ("waveform",)
        setup.floor = dict.fromkeys(kinds, START_FLOOR)
        return refine_start(setup, glob, E, v0, *global_start(setup, glob, E, v0, *grid),
                            levels=refine_levels)
    # the device's globals; each hit's own parameters, and the floor they leave
    hits_only = fit(setup, initial_state(setup, glob, E, v0), per_hit)
    setup.floor = model_floor(setup, hits_only)
    return hits_only.state, []


def _settled(setup: Setup, f: Fit, cols: list[Column]) -> Fit:
    """Step 2 of :func:`calibrate_records`: the model-error floor estimated from a fit's
    residuals (:func:`model_floor`) and the fit again with it, until the floor settles
    (every kind within :data:`FLOOR_RTOL` of the last pass's; at most
    :data:`FLOOR_PASSES` times).

    Parameters
    ----------
    setup : Setup
        The model and the records (its ``floor`` is set to each pass's).
    f : Fit
        The fit with the start's floor.
    cols : list of Column
        The free parameters.

    Returns
    -------
    Fit
        The last fit.
    """
    for _ in range(FLOOR_PASSES):  # the floor: the start's, then the residuals' own
        floor = model_floor(setup, f)
        settled = all(abs(v - setup.floor.get(k, 0.0)) <= FLOOR_RTOL * v
                      for k, v in floor.items())
        setup.floor = floor
        f = fit(setup, f.state, cols)
        if settled:
            break
    return f


def _identified(setup: Setup, f: Fit, start: State, free: list[Column],
                per_hit: list[Column]) -> tuple[Fit, list[Column]]:
    """Step 3 of :func:`calibrate_records`: while some free global is not identified (its
    standard error, scaled by the misfit, beyond
    :data:`ssw.calibration.information.IDENTIFIED_U` in its scaled coordinate), the fit
    again with only the identified ones free, the others at their start's values.

    Parameters
    ----------
    setup : Setup
        The model and the records.
    f : Fit
        The fit of every free global.
    start : State
        The start (the values of the globals that are not identified).
    free : list of Column
        The free globals.
    per_hit : list of Column
        Every hit's parameters (always free).

    Returns
    -------
    tuple
        The last fit and the globals it identified.
    """
    from ssw.calibration.information import IDENTIFIED_U

    while True:
        kept = [c for c in free if f.std(c) <= IDENTIFIED_U]
        if len(kept) == len(free):
            return f, free
        free = kept
        st = f.state.copy()  # what is not identified goes back to its start's value
        st.globals.update({g: start.globals[g] for g in GLOBALS if Column(g) not in free})
        f = fit(setup, st, free + per_hit)


def refit_discrepancy(samples: list[Hits], params: Any, wall: str,
                      wall_options: dict[str, Any], acq: Acquisition, trigger_level: float,
                      tof_scatter: float, state: State) -> Fit:
    """The model's discrepancy and floor fitted on ``samples`` alone with the device's
    globals held (a leave-one-out refit, :func:`ssw.calibration.records.leave_one_out`):
    each hit's parameters from ``state`` (the calibration's own fit of them), then the
    passes of :func:`calibrate_records`' step 4 with no global freed.

    Parameters
    ----------
    samples : list of Hits
        References, each with its E.
    params : ChainParams
        The calibrated device's chain.
    wall : str
        The wall law.
    wall_options : dict
        Its options.
    acq : Acquisition
        The measurement model.
    trigger_level : float
        N, the records' trigger level.
    tof_scatter : float
        s, a hit's TOF scatter (the delays' prior).
    state : State
        The samples' E, their hits' parameters and the device's globals (the gain among
        them).

    Returns
    -------
    Fit
        The hits' fit with the refitted ``discrepancy`` and ``floor``.
    """
    setup = Setup(params, wall, dict(wall_options), acq, "features", samples, trigger_level,
                  tof_scatter=tof_scatter)
    n_h = setup.n_hits
    v0 = float(params.striker_velocity)
    setup.fix_step(State(state.E, np.full(n_h, 1.5 * v0), np.zeros(n_h), np.zeros(n_h),
                         dict(state.globals)))
    per_hit = [Column(name, h) for name in PER_HIT for h in range(n_h)]
    return _with_discrepancy(setup, state, [], per_hit)


def _with_discrepancy(setup: Setup, state: State, free: list[Column],
                      per_hit: list[Column]) -> Fit:
    """The references' fit from ``state`` again with the model's discrepancy
    (:mod:`ssw.calibration.discrepancy`): the line estimated and the hits refitted
    :data:`~ssw.calibration.discrepancy.PASSES` times with the globals held, then the floor
    the corrected residuals leave (each feature's at least the line's cross-validated
    error) and the globals ``free`` freed again."""
    from ssw.calibration.discrepancy import PASSES, estimate

    E = np.array([s.E for s in setup.samples], float)
    for _ in range(PASSES):
        bare = replace(setup, floor={}, discrepancy=None, runs=0)
        obs = observe(bare, state, set())
        setup.runs += bare.runs
        rows = np.isin(obs.kind, FEATURES)
        shape = (setup.n_hits, len(FEATURES))
        setup.discrepancy = estimate(obs.model[rows].reshape(shape),
                                     obs.data[rows].reshape(shape), state.delay,
                                     setup.hit_of(), E)
        f = fit(setup, state, per_hit)
        state = f.state
    floor = model_floor(setup, f)
    least = setup.discrepancy.sigma
    if least is not None:  # what the line misses from reference to reference
        floor = {k: max(floor.get(k, 0.0), float(least[i])) for i, k in enumerate(FEATURES)}
    setup.floor = floor
    return fit(setup, f.state, free + per_hit)


def with_fit(cal: Any, f: Fit, level: str) -> Any:
    """A calibration with what a fit of its references' records identified
    (:func:`calibrate_records`): the device's preload and masses, the dashpot (the
    numerics' ``damping``) and the striker speed (the hits' mean) at the fit's values
    (fitted where freed, else the fit's start: the device's, or the global start's);
    the fit itself (level, freed parameters with their standard errors, the DAQ gain,
    chi^2 and its quantile, the model-error floor, the measured globals' priors, the freed
    globals' covariance in their scaled coordinates) in ``provenance["information"]``,
    where ``ssw measure --information`` reads the gain, the floor and the covariance; the
    priors also in a ``RECORDS`` line of ``warnings``. The TOF calibration's
    covariance stays the calibration term of a TOF measurement's budget.

    Parameters
    ----------
    cal : ssw.calibration.Calibration
        The TOF calibration of the same references.
    f : Fit
        The fit of their records.
    level : str
        Its level of information.

    Returns
    -------
    ssw.calibration.Calibration
        The updated calibration.
    """
    fitted = {c.name: (get(f.state, c), f.std(c)) for c in f.free if c.index < 0}
    speed = float(np.mean(f.state.striker_velocity))
    # the device of the fit: its freed globals fitted, the others at the fit's start
    changes: dict[str, float] = {k: float(f.state.globals[k])
                                 for k in ("preload", "sensor_mass", "striker_mass")}
    changes["striker_velocity"] = speed
    numerics = dict(cal.numerics)
    numerics["damping"] = float(f.state.globals["damping"])
    info = {"level": level, "freed": list(fitted),
            "values": {k: v for k, (v, _) in fitted.items()},
            "std_scaled": {k: s for k, (_, s) in fitted.items()},
            "gain": float(f.state.globals["gain"]),
            "start": [{**pt, "chi2": float(pt["chi2"]) if np.isfinite(pt["chi2"]) else None}
                      for pt in f.start],  # None: the point leaves observations unexplained
            "striker_velocity_per_hit": [float(v) for v in f.state.striker_velocity],
            "time_offset_per_hit": [float(v) for v in f.state.time_offset],
            "delay_per_hit": [float(v) for v in f.state.delay],
            "chi2": f.chi2, "chi2_dof": f.dof, "chi2_quantile": f.quantile,
            "flagged": f.flagged, "unexplained": f.unexplained, "converged": f.converged,
            "runs": f.runs, "floor": dict(f.floor),
            "prior": {k: [float(m), float(s)] for k, (m, s) in f.prior.items()},
            "discrepancy": None if f.discrepancy is None else f.discrepancy.to_dict()}
    names, cov = global_covariance(f, hits=len(f.state.striker_velocity) / len(f.state.E))
    info["covariance"] = {"names": names, "matrix": cov.tolist()}
    if "information" in cal.provenance:  # the level this one started from
        info["from"] = {k: v for k, v in cal.provenance["information"].items()
                        if k not in ("start", "from")}
    parameters = {**cal.parameters, **{k: v for k, v in changes.items()
                                       if k in cal.parameters}}
    warnings = [w for w in cal.warnings if not w.startswith("RECORDS")]
    warnings.append(f"RECORDS ({level}): the model-error floor of the records' fit, in the "
                    "weights of every measurement through the calibration at this level: "
                    + (", ".join(f"{k} {v:.2g}" for k, v in f.floor.items()) or "none"))
    if f.prior:
        warnings.append(f"RECORDS ({level}): measured globals held near the device file's "
                        "values by their priors (the file's striker.mass_std, else "
                        "ssw.calibration.hits.GLOBAL_PRIORS): "
                        + ", ".join(f"{k} {m:.4g} +- {s:.2g} {parameter(k).unit}"
                                    for k, (m, s) in f.prior.items()))
    if f.discrepancy is not None:
        warnings.append(f"MODEL ERROR ({level}): the references' features depart from every "
                        "model the fit reaches, smoothly in E: the model's features are "
                        "corrected by a line in (E / E_0)^(-2/5) fitted on the references (a model "
                        "discrepancy, Kennedy and O'Hagan 2001) at every measurement through "
                        "this calibration: " + f.discrepancy.describe())
    if f.flagged or not f.converged:
        warnings.append(f"RECORDS ({level}): the fit of the references' records "
                        + ("did not converge" if not f.converged else "")
                        + (" and " if f.flagged and not f.converged else "")
                        + (f"is flagged (chi2 {f.chi2:.4g} on {f.dof}, "
                           f"{f.unexplained} observation(s) unexplained)" if f.flagged else ""))
    return replace(cal, device=cal.device.with_(**changes), parameters=parameters,
                   numerics=numerics, provenance={**cal.provenance, "information": info},
                   warnings=warnings)
