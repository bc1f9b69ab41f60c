"""The model-error floor and the global start of a calibration of records
(:mod:`ssw.calibration.waveform`): the floor the residuals call for
(:func:`model_floor`), the grid of sensor masses by contact dissipation coefficients
(:func:`global_start`, :func:`start_damping`) and its refinements
(:func:`refine_start`), each point its own least-squares problem of the hits'
parameters.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ssw.calibration.hits import PER_HIT, Column, State, get, parameter, put
from ssw.calibration.model_error import FLOOR_CONFIDENCE, floor_bound
from ssw.calibration.observation import (
    Setup,
    _bounds,
    from_x,
    initial_state,
    observe,
    to_x,
)
from ssw.calibration.waveform_fit import Fit, _Explained, _weighted
from ssw.errors import RecordingError
from ssw.signal.features import NAMES as FEATURES


def model_floor(setup: Setup, f: Fit) -> dict[str, float]:
    """The model-error floor the references' residuals call for: per observation kind (each
    feature; the samples of a waveform) the relative standard deviation ``phi`` that, added
    in quadrature to the noise's, brings that kind's chi^2 at the fit ``f`` down to the
    lower ``FLOOR_CONFIDENCE`` quantile of a chi^2 of its share of the degrees of
    freedom: the upper confidence bound of ``phi`` (the Birge ratio of each kind, Birge
    1932, made 1 at the bound rather than at the point estimate: a kind with a handful of
    observations per reference gives a floor that samples outside the references' range
    exceed; the estimator of every level, :mod:`ssw.calibration.model_error`, which the TOF
    level's ``tau`` also uses)::

        sum_i r_i^2 / (sigma_i^2 + phi^2 s_i^2) = chi2.ppf(1 - FLOOR_CONFIDENCE, n_k dof / n)

    with ``r_i`` the residuals, ``sigma_i`` the noise's standard deviations, ``s_i`` the
    observation's scale (a feature's value; a record's largest sample), ``n_k`` the kind's
    observations of ``n``. ``phi = 0`` where the noise alone explains the kind.

    Parameters
    ----------
    setup : Setup
        The model and the records of the fit.
    f : Fit
        The fit (of reference records).

    Returns
    -------
    dict
        Kind -> ``phi`` (``floor`` of :class:`Setup`).

    References
    ----------
    Birge, R. T. (1932). The calculation of errors by the method of least squares. Phys.
    Rev. 40, 207-227.
    """
    bare = replace(setup, floor={}, runs=0)
    obs = observe(bare, f.state, set())
    setup.runs += bare.runs
    r = obs.model - obs.data
    ok = np.isfinite(r)
    kinds = FEATURES if setup.level == "features" else ("waveform",)
    scale = np.abs(obs.data)
    if setup.level == "waveform":  # a sample's scale: its record's largest sample
        top = {h: float(np.max(np.abs(obs.data[(obs.hit == h) & (obs.kind == "waveform")])))
               for h in np.unique(obs.hit)}
        scale = np.array([top[h] for h in obs.hit])
    share = f.dof / max(int(np.count_nonzero(ok)), 1)
    out = {}
    for k in kinds:
        s = ok & (obs.kind == k)
        if np.any(s):
            out[k] = floor_bound(r[s], obs.sigma[s], scale[s], share * np.count_nonzero(s),
                                 FLOOR_CONFIDENCE)
    return out


#: The global start of a calibration of records (:func:`global_start`): the sensor
#: particle's mass as a multiple of the device's, and the contact dashpot (N s/m). The
#: chain's TOF, amplitudes and pulse widths are far from linear in them (a heavier sensor
#: delays and widens its pulse; a dashpot damps the reflections): the features' chi^2 is
#: so sharp in them (a device whose sensor is 1.5x a bead with a 5 N s/m dashpot: chi^2 per
#: degree of freedom ~300 at its own values, ~1e5 at 1.3x and 3 N s/m, the hits' speeds,
#: time offsets and delays fitted) that a local fit from a point 0.2 bead or 2 N s/m away
#: stops in a basin of its own (measured: from the nominal device, 1.0x and 6.4 N s/m;
#: from 1.3x and 3 N s/m, 1.25x and 7.8 N s/m), hence a grid of 0.1 bead by 1 N s/m.
START_SENSOR_MASS = tuple(np.round(np.arange(1.0, 2.0 + 1e-9, 0.1), 1))
#: The contact dashpots of the global start's grid, N s/m; under another dissipation law
#: the same grid in that law's scale (:func:`start_damping`).
START_DAMPING = tuple(float(c) for c in range(11))
#: Model runs of each grid point's fit of the per-hit parameters.
START_ITERATIONS = 8
#: The relative model-error floor of the global start's and the first global fit's
#: weights (every kind, ``floor`` of :class:`Setup`): a few times the chain's own error on the
#: features at a device's true values (a discrete chain against DOP853: 3e-5 of the TOF,
#: 2e-4 of the amplitude, 1.7e-3 of the secondary ratio), so that the grid ranks its points
#: by the model's distance from the records rather than by the noise.
START_FLOOR = 3e-3
#: Refinements of the global start (:func:`refine_start`): each a grid of
#: :data:`REFINE_POINTS` sensor masses by as many dashpots around the best point so far,
#: its spacing a third of the last one's (0.1 bead and 1 N s/m, then 0.033 and 0.33, 0.011
#: and 0.11, 0.0037 and 0.037). The features' chi^2 is so sharp in the sensor's mass (a
#: device of 1.45 x a bead, 4.5 N s/m: chi^2 ~1e4 at 1.4x, 5 N s/m with the hits'
#: parameters fitted, 3 at its own values) that the Levenberg-Marquardt from a point of
#: the first grid crawls (damping 1e4-1e5, a step predicted to gain 5e3 of chi^2 gaining
#: nothing) and stops far from the optimum; from within ~0.005 bead it converges.
REFINE_LEVELS = 3
#: Points per parameter of a refinement (offsets -2..2 of its spacing: the neighbours'
#: halfway points are inside).
REFINE_POINTS = 5


def start_damping(law: str) -> tuple[float, ...]:
    """The global start's contact dissipation coefficients under the dissipation ``law``:
    :data:`START_DAMPING` (dashpots, N s/m) times the law's typical coefficient over the
    dashpot's (:data:`ssw.chain.dissipation.LAWS`: the same damping forces at the thesis
    chain's impact, so the grid spans the same dissipation under every law; the dashpot's
    own grid unchanged).

    Parameters
    ----------
    law : str
        A dissipation law's name (:data:`ssw.chain.dissipation.LAWS`).

    Returns
    -------
    tuple of float
        The coefficients, in the law's unit.
    """
    from ssw.chain.dissipation import DEFAULT_LAW, LAWS, law_of

    if law == DEFAULT_LAW:
        return START_DAMPING
    ratio = law_of(law).scale / LAWS[DEFAULT_LAW].scale
    return tuple(float(c * ratio) for c in START_DAMPING)


def global_start(setup: Setup, globals_: dict[str, float], E: Any, speed: float,
                 sensor_mass: tuple[float, ...] | None = None,
                 damping: tuple[float, ...] | None = None) -> tuple[State, list[dict]]:
    """A start for a calibration of records in the basin of their best fit: on a grid of
    the sensor's mass and the contact dashpot, each point's per-hit parameters (striker
    speed, time offset, delay) from :func:`initial_state` and a short fit
    (:data:`START_ITERATIONS` runs, each point its own least-squares problem), the
    weights with ``setup``'s floor; the point of least chi^2 is the start. Every sensor
    mass of one dashpot is one chain run (the hits of every point batched,
    ``scene_sensor_mass`` of :class:`Setup`).

    Parameters
    ----------
    setup : Setup
        The model and the records.
    globals_ : dict
        The device's global parameters (SI); the grid replaces ``sensor_mass`` and
        ``damping``.
    E : array_like
        (n_s,) Pa, the samples' moduli.
    speed : float
        m/s, the device's striker speed.
    sensor_mass : tuple of float or None
        The sensor masses of the grid, multiples of ``globals_["sensor_mass"]`` (default
        :data:`START_SENSOR_MASS`).
    damping : tuple of float or None
        The contact dissipation coefficients of the grid, in the unit of the device's law
        (``setup.params.damping_law``; default :func:`start_damping` of it: the dashpot's
        :data:`START_DAMPING`, N s/m).

    Returns
    -------
    tuple of (State, list of dict)
        The best point's state (its per-hit parameters fitted) and every point's
        ``sensor_mass``, ``damping`` and ``chi2``.
    """
    masses = np.asarray(START_SENSOR_MASS if sensor_mass is None else sensor_mass, float)
    masses = masses * globals_["sensor_mass"]
    n_g, n_h = masses.size, setup.n_hits
    E = np.asarray(E, float).ravel()
    tiled = replace(setup, samples=list(setup.samples) * n_g, runs=0,
                    scene_sensor_mass=np.repeat(masses, n_h))
    replica = np.arange(tiled.n_hits) // n_h
    best, best_chi2, scan = None, np.inf, []
    for c in (start_damping(setup.params.damping_law) if damping is None else damping):
        g = {**globals_, "damping": float(c)}
        f = _fit_points(tiled, initial_state(tiled, g, np.tile(E, n_g), speed), n_g,
                        START_ITERATIONS)
        obs = observe(tiled, f, set())
        r2 = ((obs.model - obs.data) / obs.sigma) ** 2
        ok = np.isfinite(r2)
        chi2 = np.bincount(replica[obs.hit[ok]], weights=r2[ok], minlength=n_g)
        # a point whose model lacks observations the records have does not fit them
        lost = np.bincount(replica[obs.hit], weights=~ok & np.isfinite(obs.data),
                           minlength=n_g)
        chi2 = np.where(lost > 0, np.inf, chi2)
        scan += [{"sensor_mass": float(m), "damping": float(c), "chi2": float(x)}
                 for m, x in zip(masses, chi2, strict=True)]
        i = int(np.argmin(chi2))
        if chi2[i] < best_chi2:
            hits = slice(i * n_h, (i + 1) * n_h)
            best_chi2 = float(chi2[i])
            best = State(E.copy(), f.striker_velocity[hits].copy(),
                         f.time_offset[hits].copy(), f.delay[hits].copy(),
                         {**g, "sensor_mass": float(masses[i])})
    setup.runs += tiled.runs
    if best is None:
        raise RecordingError("no point of the global start's grid explains the records")
    return best, scan


def refine_start(setup: Setup, globals_: dict[str, float], E: Any, speed: float,
                 state: State, scan: list[dict], levels: int = REFINE_LEVELS
                 ) -> tuple[State, list[dict]]:
    """A global start (:func:`global_start`) refined: ``levels`` times a grid of
    :data:`REFINE_POINTS` sensor masses by as many dashpots around the best point so far,
    its spacing a third of the last one's (the first: the start grid's), the best point of
    all kept (a continuation towards the optimum that a local fit from the coarse grid does
    not reach, :data:`REFINE_LEVELS`).

    Parameters
    ----------
    setup : Setup
        The model and the records.
    globals_ : dict
        The device's global parameters (SI).
    E : array_like
        (n_s,) Pa, the samples' moduli.
    speed : float
        m/s, the device's striker speed.
    state : State
        The best point so far (:func:`global_start`).
    scan : list of dict
        Its grid's points (``sensor_mass``, ``damping``, ``chi2``).
    levels : int
        Refinements.

    Returns
    -------
    tuple of (State, list of dict)
        The best point's state and every point's ``sensor_mass``, ``damping`` and
        ``chi2`` (the start grid's and the refinements').
    """
    m0 = float(globals_["sensor_mass"])
    masses = sorted({p["sensor_mass"] for p in scan})
    dampings = sorted({p["damping"] for p in scan})
    if len(masses) < 2 or len(dampings) < 2:
        return state, scan
    dm = (masses[1] - masses[0]) / m0
    dc = dampings[1] - dampings[0]
    best = min(p["chi2"] for p in scan)
    offsets = np.arange(REFINE_POINTS) - (REFINE_POINTS - 1) // 2
    lo, hi = (parameter("damping", setup.params.damping_law).lower,
              parameter("damping", setup.params.damping_law).upper)
    scan = list(scan)
    for _ in range(levels):
        dm, dc = dm / 3.0, dc / 3.0
        ms = state.globals["sensor_mass"] / m0 + dm * offsets
        cs = np.unique(np.clip(state.globals["damping"] + dc * offsets, lo, hi))
        try:
            new, points = global_start(setup, globals_, E, speed, tuple(ms[ms > 0]),
                                       tuple(float(c) for c in cs))
        except RecordingError:  # no point of this grid explains the records
            continue
        scan += points
        chi2 = min(p["chi2"] for p in points)
        if chi2 < best:
            state, best = new, chi2
    return state, scan


def _fit_points(tiled: Setup, state: State, n_g: int, iterations: int) -> State:
    """The per-hit parameters of every point of a global start's grid (``tiled``: the
    records repeated ``n_g`` times, a sensor mass per point) fitted, each point its own
    least-squares problem (its own damping and steps: one point's hard start holds back no
    other), every iteration's trial points in ONE chain run
    (:func:`ssw.calibration.lm.levenberg_marquardt`). A trial where a point's model loses
    observations its current state explains is rejected (:class:`_Explained`, as in :func:`fit`).

    Parameters
    ----------
    tiled : Setup
        The records of every point.
    state : State
        The start (every point's hits).
    n_g : int
        Points.
    iterations : int
        At most this many chain runs.

    Returns
    -------
    State
        Every point's hits fitted.
    """
    from ssw.calibration.lm import Problem, levenberg_marquardt

    n_h = tiled.n_hits // n_g
    cols = [[Column(name, i * n_h + h) for name in PER_HIT for h in range(n_h)]
            for i in range(n_g)]
    lo, hi = _bounds(tiled, cols[0])
    work = state.copy()
    x = [np.clip(to_x(tiled, cs, np.array([get(work, c) for c in cs])), lo, hi)
         for cs in cols]

    def at(trial: dict[int, np.ndarray]) -> State:
        st = work.copy()
        for i, cs in enumerate(cols):
            for c, v in zip(cs, from_x(tiled, cs, trial.get(i, x[i])), strict=True):
                put(st, c, v)
        return st

    def split(trial: dict[int, np.ndarray]) -> dict[int, tuple[np.ndarray, np.ndarray, int]]:
        st = at(trial)
        obs = observe(tiled, st, set(PER_HIT))
        point = obs.hit // n_h
        return {i: _weighted(tiled, obs, st, cols[i], point == i) for i in trial}

    first = split(dict(enumerate(x)))
    problems = [Problem(x[i], r, J, float(r @ r), np.eye(lo.size))
                for i, (r, J, _) in first.items()]
    explained = [_Explained(x[i], first[i][2]) for i in range(n_g)]

    def evaluate(trial: dict[int, np.ndarray]) -> dict[int, tuple[np.ndarray, np.ndarray,
                                                                  float]]:
        for i, pr in enumerate(problems):
            x[i] = pr.x
        return {i: (r, J, explained[i].cost(problems[i].x, trial[i], r, n_lost))
                for i, (r, J, n_lost) in split(trial).items()}

    levenberg_marquardt(problems, evaluate, lo, hi, iterations)
    return at({i: pr.x for i, pr in enumerate(problems)})
