"""The model of a record and its observations (:mod:`ssw.calibration.waveform`): the
model and the records (:class:`Setup`), one chain run of every hit through the
measurement model to each level's rows and their exact derivatives (:func:`observe`,
:class:`Observed`), a fit's start (:func:`initial_state`) and the parameters' scaled
coordinates and bounds.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ssw.calibration.hits import (
    CHAIN_GLOBALS,
    PARAMETERS,
    Column,
    Hits,
    State,
    columns_of,
    parameter,
)
from ssw.daq.model import Acquisition, filter_fine, fine_grid, trigger_time
from ssw.errors import ConfigError
from ssw.signal.features import NAMES as FEATURES
from ssw.signal.features import pulse_features, upsample
from ssw.signal.peaks import UPSAMPLE


@dataclass(frozen=True)
class Observed:
    """The model's observations of the samples' records and their derivatives.

    Parameters
    ----------
    model : numpy.ndarray
        (n,) the model's values.
    data : numpy.ndarray
        (n,) the records' values (0 for a prior: its mean is in ``model``).
    sigma : numpy.ndarray
        (n,) standard deviations (the noise; a prior's width).
    kind : numpy.ndarray
        (n,) str: ``waveform``, a feature's name, ``trigger`` or ``delay``.
    hit : numpy.ndarray
        (n,) the hit each row belongs to.
    jacobian : numpy.ndarray
        (n, p) d model / d parameter (SI) for the ``columns``.
    columns : list of Column
        The parameters.
    """

    model: np.ndarray
    data: np.ndarray
    sigma: np.ndarray
    kind: np.ndarray
    hit: np.ndarray
    jacobian: np.ndarray
    columns: list[Column]


@dataclass
class Setup:
    """The model of a set of samples' records at one level of information.

    Parameters
    ----------
    params : ChainParams
        The device's chain (its numerics; the globals of a :class:`State` replace its
        preload, masses and damping).
    wall : str
        The wall law (:data:`ssw.walls.WALLS`).
    wall_options : dict
        Its builder's options.
    acq : Acquisition
        The measurement model.
    level : str
        ``features`` or ``waveform``.
    samples : list of Hits
        The records.
    trigger_level : float
        N, the analog-edge trigger's level (rising).
    trigger_jitter : float
        s, the trigger's jitter beyond the sample phase.
    tof_scatter : float
        s, the prior standard deviation of a hit's ``delay``.
    floor : dict
        The model-error floor: observation kind (a feature's name, or ``waveform``) ->
        a relative standard deviation added in quadrature to the noise's (a feature's
        ``floor * |value|``; a sample's ``floor`` times its record's largest sample).
        Empty: the noise alone.
    scene_sensor_mass : numpy.ndarray or None
        (n_hits,) kg, a sensor mass per hit in place of the global one (the global
        start's grid, every point's hits in one chain run); None: the global.
    discrepancy : ssw.calibration.discrepancy.Discrepancy or None
        The model's features corrected by this line in ``(E / E_0)^(-2/5)`` (features level; None:
        uncorrected).
    prior : dict
        Global -> (mean, standard deviation), SI: a measured global's prior, one
        observation of kind ``prior`` (:data:`~ssw.calibration.hits.GLOBAL_PRIORS`). Empty:
        none.
    dt : float or None
        s, the chain's step for every run (fixed by :meth:`fix_step`).
    runs : int
        Chain runs so far (a cost counter).

    Other Parameters
    ----------------
    _starts : numpy.ndarray
        Internal: each sample's first hit (set from ``samples``; leave the default).

    Raises
    ------
    ssw.errors.ConfigError
        A level other than ``features`` | ``waveform``, or a TOF scatter <= 0 s.
    """

    params: Any
    wall: str
    wall_options: dict[str, Any]
    acq: Acquisition
    level: str
    samples: list[Hits]
    trigger_level: float
    trigger_jitter: float = 0.0
    tof_scatter: float = 1.53e-5
    floor: dict[str, float] = field(default_factory=dict)
    scene_sensor_mass: np.ndarray | None = None
    discrepancy: Any = None
    prior: dict[str, tuple[float, float]] = field(default_factory=dict)
    dt: float | None = None
    runs: int = 0
    _starts: np.ndarray = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.level not in ("features", "waveform"):
            raise ConfigError("--information", self.level,
                              "features | waveform for a fit of records")
        if not self.tof_scatter > 0:
            raise ConfigError("tof scatter", self.tof_scatter, "a time > 0 s")
        self._starts = np.concatenate([[0], np.cumsum([s.n for s in self.samples])])

    @property
    def n_hits(self) -> int:
        """Hits of every sample."""
        return int(self._starts[-1])

    @property
    def columns(self) -> list[Column]:
        """Every parameter (:func:`columns_of`)."""
        return columns_of(len(self.samples), self.n_hits)

    @property
    def trigger_sigma(self) -> float:
        """s, the trigger prior's standard deviation (module docstring)."""
        return float(np.hypot(1.0 / (self.acq.sample_rate * np.sqrt(12.0)),
                              self.trigger_jitter))

    def hit_of(self) -> np.ndarray:
        """(n_hits,) the sample of each hit.

        Returns
        -------
        numpy.ndarray
            (n_hits,) int, the index into ``samples`` of each hit.
        """
        return np.repeat(np.arange(len(self.samples)), [s.n for s in self.samples])

    def fix_step(self, state: State, margin: float = 1.25) -> float:
        """Fix the chain's step for every later run: the integrator's step for ``margin``
        times the fastest striker of ``state`` and its lightest masses (one
        discretization for a whole fit: its model is smooth in the parameters).

        Parameters
        ----------
        state : State
            The parameter values (its fastest striker and its globals).
        margin : float
            -, factor on the fastest striker speed.

        Returns
        -------
        float
            s, the step kept in ``dt``.
        """
        from ssw.chain.integrate import time_step
        from ssw.chain.params import Batch
        from ssw.walls import build_wall

        p = self._params(state)
        E = np.array([s.E if s.E is not None else state.E[i]
                      for i, s in enumerate(self.samples)], float)
        nu = np.array([s.nu for s in self.samples])
        w = build_wall(self.wall, p, E, nu, **self.wall_options)
        b = Batch.of(p, w.n, {"striker_velocity": np.full(w.n, margin * float(np.max(
            state.striker_velocity)))})
        self.dt = float(time_step(b, w))
        return self.dt

    def _params(self, state: State) -> Any:
        g = state.globals
        return self.params.with_(damping=float(g["damping"]), preload=float(g["preload"]),
                                 sensor_mass=float(g["sensor_mass"]),
                                 striker_mass=float(g["striker_mass"]))


def _names(wanted: set[str]) -> tuple[str, ...]:
    """The chain's sensitivities a set of wanted parameters needs (always the speed)."""
    return tuple(n for n in ("E", "striker_velocity", *CHAIN_GLOBALS)
                 if n in wanted or n == "striker_velocity")


@dataclass(frozen=True)
class _Run:
    """One chain run of every hit through the measurement model (:func:`_measured`).

    Parameters
    ----------
    samples : numpy.ndarray
        (n, n_hits, channels) the filtered record samples of every hit before the gain:
        channel 0 the sensor force (N per unit gain), then its derivatives by the chain's
        parameters, by the time offset and by the delay.
    E : numpy.ndarray
        (n_hits,) each hit's sample's Young's modulus, Pa.
    t_c : numpy.ndarray
        (n_hits,) the model's trigger crossing, chain time, s.
    slope : numpy.ndarray
        (n_hits,) the gained fine output's slope at the crossing, N/s.
    d_fine : numpy.ndarray
        (n_hits, channels) the fine output and its derivatives at the crossing.
    """

    samples: np.ndarray
    E: np.ndarray
    t_c: np.ndarray
    slope: np.ndarray
    d_fine: np.ndarray


def _measured(setup: Setup, state: State, names: tuple[str, ...]) -> _Run:
    """The chain run of every hit (:func:`ssw.tof.api.sensor_derivatives`, its forward
    sensitivities ``names`` and its time derivative) through the measurement model
    (:mod:`ssw.daq.model`) at the records' sample times, the reflected waves shifted by
    each hit's delay, and the model's trigger crossing on the fine output.

    Parameters
    ----------
    setup : Setup
        The model and the records (its ``runs`` counts the run).
    state : State
        The parameters' values.
    names : tuple of str
        The chain's sensitivities to compute (:func:`_names`).

    Returns
    -------
    _Run
        The samples, the hits' moduli and the trigger crossing.
    """
    from ssw.tof import api

    acq, fs = setup.acq, setup.acq.sample_rate
    hit_sample = setup.hit_of()
    n_h = setup.n_hits
    kt = np.concatenate([s.trigger_index for s in setup.samples])
    win = np.concatenate([s.window for s in setup.samples])
    split = np.concatenate([s.split for s in setup.samples])
    n_win = int(np.max(win[:, 1] - win[:, 0]))
    tau = state.time_offset
    first = tau + (win[:, 0] - kt) / fs
    E = np.array([state.E[i] for i in hit_sample], float)
    nu = np.array([setup.samples[i].nu for i in hit_sample], float)
    p = setup._params(state)
    vary = {"striker_velocity": state.striker_velocity}
    if setup.scene_sensor_mass is not None:
        vary["sensor_mass"] = setup.scene_sensor_mass
    grid = fine_grid(acq, first, n_win, start=0.0)
    s_split = tau + split - acq.delay  # chain (input) time of each hit's split
    after = grid.s > s_split[None, :]
    shifted = grid.s - np.where(after, state.delay[None, :], 0.0)
    dt = setup.dt
    # the run covers the last sample's inputs and, for a negative delay, the later chain
    # times the split's samples read: a record that ends before them leaves those rows
    # unexplained (NaN), and a fit would fall into dropping them
    t_last = max(float(np.max(grid.s)), float(np.max(shifted)))
    sd = api.sensor_derivatives(E, nu, p, setup.wall, times=np.clip(shifted, 0.0, None),
                                derivatives=names, t_end=t_last + 8 * (dt or 1e-6),
                                vary=vary, rate=True, dt=dt, **setup.wall_options)
    setup.runs += 1
    run = sd.run
    valid = shifted > 4 * run.dt  # before: the static state (the wave has not come)
    x = np.where(valid, sd.sensor - run.sensor[0][None, :], 0.0)
    dx = np.where(valid[..., None], sd.dsensor - run.dsensor[0][None, :, :], 0.0)
    rate = np.where(valid, sd.rate, 0.0)
    stack = np.concatenate([x[..., None], dx, rate[..., None],
                            (-rate * after)[..., None]], axis=2)
    samples, fine = filter_fine(acq, grid, stack, fine=True)
    g = float(state.globals["gain"])
    # the model's trigger crossing, on the fine output (chain clock)
    L = acq.taps.size
    t_fine = grid.s[grid.lead + L - 1:][: fine.shape[0]] + acq.pure_delay
    t_c, j = trigger_time(t_fine, g * fine[:, :, 0], setup.trigger_level)
    cols_h = np.arange(n_h)
    slope = g * (fine[j, cols_h, 0] - fine[j - 1, cols_h, 0]) * (acq.oversample * fs)
    d_fine = 0.5 * (fine[j, cols_h] + fine[j - 1, cols_h])  # (n_h, channels)
    return _Run(samples, E, t_c, slope, d_fine)


@dataclass(frozen=True)
class _Rows:
    """Where a hit's derivatives go among the parameters' columns (:func:`observe`).

    Parameters
    ----------
    setup : Setup
        The model and the records.
    names : tuple of str
        The chain's sensitivities, in the order of the run's channels.
    wanted : set of str
        The parameters whose derivatives are needed.
    index : dict
        Each :class:`Column`'s index among ``setup.columns``.
    hit_sample : numpy.ndarray
        (n_hits,) each hit's sample.
    """

    setup: Setup
    names: tuple[str, ...]
    wanted: set[str]
    index: dict[Column, int]
    hit_sample: np.ndarray

    def jacobian(self, h: int, d_chain: np.ndarray, d_tau: np.ndarray, d_delay: np.ndarray,
                 d_gain: np.ndarray) -> np.ndarray:
        """Rows of hit ``h`` in the parameters' columns.

        Parameters
        ----------
        h : int
            The hit.
        d_chain : numpy.ndarray
            (m, k) the rows' chain sensitivities (SI per parameter's unit).
        d_tau : numpy.ndarray
            (m,) their derivatives by the hit's time offset (per s).
        d_delay : numpy.ndarray
            (m,) by the hit's delay (per s).
        d_gain : numpy.ndarray
            (m,) by the DAQ gain.

        Returns
        -------
        numpy.ndarray
            (m, n_columns) the Jacobian's rows.
        """
        setup, index = self.setup, self.index
        m = d_gain.shape[0]
        J = np.zeros((m, len(index)))
        for c, name in enumerate(self.names):
            if name == "E":
                i = self.hit_sample[h]
                if setup.samples[i].E is None or "E" in self.wanted:
                    J[:, index[Column("E", int(i))]] = d_chain[:, c]
            elif name == "striker_velocity":
                J[:, index[Column("striker_velocity", h)]] = d_chain[:, c]
            else:
                J[:, index[Column(name)]] = d_chain[:, c]
        J[:, index[Column("time_offset", h)]] = d_tau
        J[:, index[Column("delay", h)]] = d_delay
        J[:, index[Column("gain")]] = d_gain
        return J


#: A block of observations: model, data, sigma, kinds, Jacobian.
_Block = tuple[np.ndarray, np.ndarray, np.ndarray, list[str], np.ndarray]


def _waveform_rows(rows: _Rows, h: int, y: np.ndarray, g: float) -> _Block:
    """A hit's waveform rows: its window's samples not at a rail, their noise with the
    waveform's model-error floor times the record's largest sample.

    Parameters
    ----------
    rows : _Rows
        The columns.
    h : int
        The hit.
    y : numpy.ndarray
        (m, channels) the gained model samples of its window and their derivatives.
    g : float
        The DAQ gain.

    Returns
    -------
    tuple
        The rows' model (N), data (N), sigma (N), kinds and Jacobian.
    """
    setup = rows.setup
    k = len(rows.names)
    i = rows.hit_sample[h]
    smp = setup.samples[i]
    hh = h - setup._starts[i]
    a, b = smp.window[hh]
    keep = ~smp.rails[hh, a:b]
    val = y[keep, 0]
    J = rows.jacobian(h, y[keep, 1:1 + k], y[keep, 1 + k], y[keep, 2 + k], val / g)
    top = float(np.max(np.abs(smp.force[hh, a:b])))
    sigma = np.full(val.size, np.hypot(smp.noise, setup.floor.get("waveform", 0.0) * top))
    return val, smp.force[hh, a:b][keep], sigma, ["waveform"] * val.size, J


def _feature_rows(rows: _Rows, h: int, y: np.ndarray, g: float, E: float) -> _Block:
    """A hit's feature rows: the upsampled model's features (:mod:`ssw.signal.features`)
    with their chain rule, the model's discrepancy where the setup carries one
    (:func:`_corrected`), their noise with each feature's model-error floor.

    Parameters
    ----------
    rows : _Rows
        The columns.
    h : int
        The hit.
    y : numpy.ndarray
        (m, channels) the gained model samples of its window and their derivatives.
    g : float
        The DAQ gain.
    E : float
        The hit's sample's Young's modulus, Pa.

    Returns
    -------
    tuple
        The rows' model, data, sigma (each feature's unit), kinds and Jacobian.
    """
    setup = rows.setup
    k = len(rows.names)
    i = rows.hit_sample[h]
    smp = setup.samples[i]
    hh = h - setup._starts[i]
    fs = setup.acq.sample_rate
    up = upsample(y)
    f = pulse_features(up[:, 0], 1.0 / (UPSAMPLE * fs),
                       dy=np.concatenate([up[:, 1:], up[:, :1] / g], axis=1),
                       noise=smp.noise, rate=fs)
    val = f.values
    J = rows.jacobian(h, f.jacobian[:, :k], f.jacobian[:, k], f.jacobian[:, k + 1],
                      f.jacobian[:, k + 2])
    if setup.discrepancy is not None:
        val, J = _corrected(setup, val, J, E, rows.index.get(Column("E", int(i))),
                            smp.E is None or "E" in rows.wanted)
    rel = np.array([setup.floor.get(n, 0.0) for n in FEATURES])
    sigma = np.hypot(smp.feature_sigma[hh], rel * np.abs(smp.features[hh]))
    return val, smp.features[hh], sigma, list(FEATURES), J


def _prior_rows(rows: _Rows, h: int, run: _Run, state: State) -> list[_Block]:
    """A hit's two priors (module docstring of :mod:`ssw.calibration.waveform`): the
    trigger, ``time_offset - t_c ~ 1/(2 f_s) +- trigger_sigma``, and the delay's zero mean
    with the TOF's scatter.

    Parameters
    ----------
    rows : _Rows
        The columns.
    h : int
        The hit.
    run : _Run
        The chain run (its trigger crossing).
    state : State
        The parameters' values.

    Returns
    -------
    list of tuple
        The trigger's row (s) and the delay's (s), each model, data, sigma, kinds and
        Jacobian.
    """
    setup, index = rows.setup, rows.index
    k = len(rows.names)
    fs = setup.acq.sample_rate
    g = float(state.globals["gain"])
    Jt = np.zeros((1, len(index)))
    dtc = -g * run.d_fine[h, 1:1 + k] / run.slope[h]
    Jt[0] -= rows.jacobian(h, dtc[None, :], np.zeros(1), np.zeros(1), np.zeros(1))[0]
    Jt[0, index[Column("gain")]] = setup.trigger_level / (g * run.slope[h])
    Jt[0, index[Column("time_offset", h)]] = 1.0
    trigger = (np.array([state.time_offset[h] - run.t_c[h] - 0.5 / fs]), np.zeros(1),
               np.array([setup.trigger_sigma]), ["trigger"], Jt)
    Jd = np.zeros((1, len(index)))
    Jd[0, index[Column("delay", h)]] = 1.0
    delay = (np.array([state.delay[h]]), np.zeros(1), np.array([setup.tof_scatter]),
             ["delay"], Jd)
    return [trigger, delay]


def observe(setup: Setup, state: State, wanted: set[str] | None = None) -> Observed:
    """The model's observations of every sample's records and their derivatives, in ONE
    chain run of all hits (module docstring of :mod:`ssw.calibration.waveform`).

    Parameters
    ----------
    setup : Setup
        The model and the records.
    state : State
        The parameters' values.
    wanted : set of str or None
        Parameter names whose derivatives are needed (default: all); the others' columns
        are 0.

    Returns
    -------
    Observed
        Rows: per hit its data (the features, or the window's samples not at a rail),
        then its ``trigger`` and ``delay`` priors; last, one row per measured global's
        ``prior`` (``setup.prior``, counted with the first hit).
    """
    wanted = set(PARAMETERS) if wanted is None else set(wanted)
    names = _names(wanted)
    run = _measured(setup, state, names)
    g = float(state.globals["gain"])
    columns = setup.columns
    rows = _Rows(setup, names, wanted, {c: i for i, c in enumerate(columns)}, setup.hit_of())
    blocks: list[_Block] = []
    hits: list[np.ndarray] = []
    for h in range(setup.n_hits):
        i = rows.hit_sample[h]
        a, b = setup.samples[i].window[h - setup._starts[i]]
        y = g * run.samples[:b - a, h]  # (m, channels)
        data = (_waveform_rows(rows, h, y, g) if setup.level == "waveform"
                else _feature_rows(rows, h, y, g, run.E[h]))
        blocks += [data, *_prior_rows(rows, h, run, state)]
        hits += [np.full(data[0].size, h), np.array([h]), np.array([h])]
    for name, (mean, std) in setup.prior.items():
        Jp = np.zeros((1, len(columns)))
        Jp[0, rows.index[Column(name)]] = 1.0
        blocks.append((np.array([state.globals[name] - mean]), np.zeros(1),
                       np.array([std]), ["prior"], Jp))
        hits.append(np.zeros(1, int))
    return Observed(np.concatenate([b[0] for b in blocks]),
                    np.concatenate([b[1] for b in blocks]),
                    np.concatenate([b[2] for b in blocks]),
                    np.array([kind for b in blocks for kind in b[3]]),
                    np.concatenate(hits), np.concatenate([b[4] for b in blocks]), columns)


def _corrected(setup: Setup, val: np.ndarray, J: np.ndarray, E: float, col_E: int | None,
               free_E: bool) -> tuple[np.ndarray, np.ndarray]:
    """A hit's model features and their Jacobian with the model's discrepancy
    (:mod:`ssw.calibration.discrepancy`): ``m (1 + delta(E))``, its derivative
    ``(1 + delta) dm/dp`` and, for E, ``+ m d delta / d ln E / E``."""
    d, slope = setup.discrepancy.at([E])
    out = val * (1.0 + d[0])
    J = J * (1.0 + d[0])[:, None]
    if free_E and col_E is not None:
        J[:, col_E] += val * slope[0] / E
    return out, J


def initial_state(setup: Setup, globals_: dict[str, float], E: Any, speed: float) -> State:
    """A start for a fit: every hit at ``speed`` scaled by its incident amplitude (``F_m ~
    v^(6/5)``, Nesterenko 2001, against the model's at ``speed``), its time offset from the
    trigger (its prior's mean), its delay the record's TOF minus the model's (the
    reflected waves moved onto the record's; 0 where a TOF is missing).

    Parameters
    ----------
    setup : Setup
        The model and the records.
    globals_ : dict
        The globals' values (SI).
    E : array_like
        (n_s,) Pa, the samples' moduli (a measured sample's first guess).
    speed : float
        m/s, the device's striker speed.

    Returns
    -------
    State
        The start.
    """
    n_h = setup.n_hits
    E = np.asarray(E, float).ravel()
    # the trigger's first guess: the module's delay after an incident pulse at the sensor
    # ~0.3 ms after the strike; the crossing on the model then places it
    state = State(E.copy(), np.full(n_h, float(speed)),
                  np.full(n_h, setup.acq.delay + 3e-4), np.zeros(n_h), dict(globals_))
    for _ in range(2):  # the time offsets follow the model's crossing; then the amplitudes
        obs = observe(setup, state, wanted={"striker_velocity"})
        trig = obs.kind == "trigger"
        state.time_offset = state.time_offset - obs.model[trig]
        amp = _features(setup, state, "amplitude")
        state.striker_velocity = state.striker_velocity * (
            _recorded(setup, "amplitude") / amp) ** (5.0 / 6.0)
        state.striker_velocity = np.clip(state.striker_velocity, 0.11, 1.9)
    obs = observe(setup, state, wanted={"striker_velocity"})
    state.time_offset = state.time_offset - obs.model[obs.kind == "trigger"]
    lo, hi = parameter("delay").lower, parameter("delay").upper
    shift = _recorded(setup, "tof") - _features(setup, state, "tof")
    state.delay = np.clip(np.where(np.isfinite(shift), shift, 0.0), lo, hi)
    return state


def _features(setup: Setup, state: State, name: str) -> np.ndarray:
    """(n_hits,) the model's feature ``name`` (:data:`ssw.signal.features.NAMES`) at
    ``state``."""
    feat = replace(setup, level="features", runs=0)
    obs = observe(feat, state, wanted={"striker_velocity"})
    setup.runs += feat.runs
    return obs.model[obs.kind == name]


def _recorded(setup: Setup, name: str) -> np.ndarray:
    """(n_hits,) the records' feature ``name``."""
    return np.concatenate([s.features[:, FEATURES.index(name)] for s in setup.samples])


def coordinate(setup: Setup, col: Column) -> tuple[bool, float]:
    """The scaled coordinate of a parameter: ``(log, scale)`` (``ln x``, or ``x / scale``;
    a time offset in sample periods, a delay in units of the prior's width).

    Parameters
    ----------
    setup : Setup
        The waveform model (the sample rate, the delay prior's width, the damping law).
    col : Column
        The parameter.

    Returns
    -------
    tuple
        ``(log, scale)``: bool, and the scale in the parameter's SI unit.
    """
    if col.name == "time_offset":
        return False, 1.0 / setup.acq.sample_rate
    if col.name == "delay":
        return False, setup.tof_scatter
    p = parameter(col.name, setup.params.damping_law if col.name == "damping" else None)
    return p.log, p.scale


def to_x(setup: Setup, cols: list[Column], values: np.ndarray) -> np.ndarray:
    """Scaled coordinates (:func:`coordinate`) of SI values, one per column.

    Parameters
    ----------
    setup : Setup
        The waveform model (the sample rate, the delay prior's width, the damping law).
    cols : list of Column
        The parameters, in order.
    values : numpy.ndarray
        (q,) their values, SI.

    Returns
    -------
    numpy.ndarray
        (q,) ``ln(value)`` or ``value / scale``.
    """
    out = np.empty(len(cols))
    for j, c in enumerate(cols):
        log, scale = coordinate(setup, c)
        out[j] = np.log(values[j]) if log else values[j] / scale
    return out


def from_x(setup: Setup, cols: list[Column], x: np.ndarray) -> np.ndarray:
    """SI values of scaled coordinates, one per column.

    Parameters
    ----------
    setup : Setup
        The waveform model (the sample rate, the delay prior's width, the damping law).
    cols : list of Column
        The parameters, in order.
    x : numpy.ndarray
        (q,) scaled coordinates.

    Returns
    -------
    numpy.ndarray
        (q,) ``exp(x)`` or ``x scale``, SI.
    """
    out = np.empty(len(cols))
    for j, c in enumerate(cols):
        log, scale = coordinate(setup, c)
        out[j] = np.exp(x[j]) if log else x[j] * scale
    return out


def dtheta_dx(setup: Setup, cols: list[Column], values: np.ndarray) -> np.ndarray:
    """``d value / d x`` per column (the value for a log coordinate, else the scale).

    Parameters
    ----------
    setup : Setup
        The waveform model (the sample rate, the delay prior's width, the damping law).
    cols : list of Column
        The parameters, in order.
    values : numpy.ndarray
        (q,) their values, SI.

    Returns
    -------
    numpy.ndarray
        (q,) SI per scaled unit.
    """
    return np.array([values[j] if coordinate(setup, c)[0] else coordinate(setup, c)[1]
                     for j, c in enumerate(cols)])



def _bounds(setup: Setup, free: list[Column]) -> tuple[np.ndarray, np.ndarray]:
    """The scaled coordinates' bounds of ``free`` (each parameter's range)."""
    lo, hi = np.empty(len(free)), np.empty(len(free))
    for j, c in enumerate(free):
        p = parameter(c.name, setup.params.damping_law if c.name == "damping" else None)
        log, scale = coordinate(setup, c)
        lo[j], hi[j] = ((np.log(p.lower), np.log(p.upper)) if log
                        else (p.lower / scale, p.upper / scale))
    return lo, hi
