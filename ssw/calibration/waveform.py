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

Parameters (:data:`PARAMETERS`; SI, each with its scaled coordinate, ``ln x`` or ``x /
scale``):

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
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ssw.calibration.model_error import FLOOR_CONFIDENCE, floor_bound
from ssw.daq.model import Acquisition, filter_fine, fine_grid, trigger_time
from ssw.device import PARAMETERS as DEVICE_PARAMETERS
from ssw.device import Parameter
from ssw.errors import ConfigError, RecordingError
from ssw.signal.features import NAMES as FEATURES
from ssw.signal.features import pulse_features, upsample
from ssw.signal.peaks import UPSAMPLE

#: The levels of information.
LEVELS = ("tof", "features", "waveform")
#: Every parameter of a waveform model (module docstring) with its range and coordinate.
PARAMETERS: dict[str, Parameter] = {
    "E": Parameter("E", "Pa", "continuous", 1.0e5, 1.0e12, True, 1.0e8,
                   "the sample's Young's modulus"),
    "nu": Parameter("nu", "1", "continuous", 0.0, 0.5, False, 0.5,
                    "the sample's Poisson's ratio"),
    **{k: DEVICE_PARAMETERS[k] for k in ("striker_velocity", "preload", "sensor_mass",
                                         "striker_mass")},
    "damping": Parameter("damping", "N s/m", "continuous", 0.0, 100.0, False, 5.0,
                         "the dashpot of every closed contact"),
    "gain": Parameter("gain", "1", "continuous", 0.2, 5.0, True, 1.0,
                      "the DAQ gain: the sensor's true sensitivity over the stated one"),
    "time_offset": Parameter("time_offset", "s", "continuous", -1.0, 1.0, False, 1.0 / 51200,
                             "the chain time of a record's trigger sample"),
    "delay": Parameter("delay", "s", "continuous", -2.0e-3, 2.0e-3, False, 1.53e-5,
                       "a shift of a hit's reflected waves"),
}
#: The device's global parameters a waveform calibration may identify.
GLOBALS = ("preload", "sensor_mass", "striker_mass", "damping", "gain")
#: The chain's parameters among them (its forward sensitivities).
CHAIN_GLOBALS = ("preload", "sensor_mass", "striker_mass", "damping")
#: Per-hit parameters.
PER_HIT = ("striker_velocity", "time_offset", "delay")
#: Samples kept before a record's trigger sample (the incident pulse's foot).
LEAD = 16
#: Reflected pulse widths (FWHM) kept after the secondary reflected peak (or the primary
#: one, when there is none), and samples beyond them (the upsampler's edge).
TAIL_WIDTHS, TAIL_SAMPLES = 3.0, 16
#: A record sample at or beyond this share of the full scale is at a rail (left out).
RAIL_SHARE = 0.999


def device_globals(params: Any, gain: float = 1.0) -> dict[str, float]:
    """The global parameters (:data:`GLOBALS`, SI) of a chain ``params`` and a DAQ gain.

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The device's chain.
    gain : float
        -, the DAQ gain.

    Returns
    -------
    dict of str to float
        ``preload`` (N), ``sensor_mass``, ``striker_mass`` (kg), ``damping`` (the law's
        unit), ``gain`` (-).
    """
    return {"preload": float(params.preload),
            "sensor_mass": float(params.masses[params.sensor_index]),
            "striker_mass": float(params.masses[0]), "damping": float(params.damping),
            "gain": float(gain)}


def parameter(name: str, law: str | None = None) -> Parameter:
    """The parameter ``name`` of :data:`PARAMETERS` (ConfigError listing them otherwise);
    ``damping`` under the dissipation ``law`` when given (its unit, range and scale:
    :func:`ssw.chain.dissipation.parameter`).

    Parameters
    ----------
    name : str
        A key of :data:`PARAMETERS`.
    law : str or None
        The contacts' dissipation law (:data:`ssw.chain.dissipation.LAWS`) for ``damping``.

    Returns
    -------
    ssw.device.Parameter
        The parameter's unit, kind, range, log flag and scale.

    Raises
    ------
    ssw.errors.ConfigError
        An unknown name.
    """
    if name == "damping" and law is not None:
        from ssw.chain.dissipation import parameter as dissipation_parameter

        return dissipation_parameter(law)
    if name not in PARAMETERS:
        raise ConfigError("parameter", name, f"one of {', '.join(PARAMETERS)}")
    return PARAMETERS[name]


@dataclass(frozen=True)
class Hits:
    """The records of one sample, ready for a waveform fit. SI units.

    Parameters
    ----------
    id : str
        The sample's name.
    E : float or None
        Pa, known (a reference) or None (measured).
    nu : float
        Its Poisson's ratio.
    force : numpy.ndarray
        (n_h, N) N, each record with its pretrigger baseline removed.
    trigger_index : numpy.ndarray
        (n_h,) the trigger sample of each record.
    rate : float
        S/s.
    noise : float
        N rms, the records' noise (pretrigger, robust; the weights of the samples).
    rails : numpy.ndarray
        (n_h, N) bool, samples at a rail (left out of the residuals).
    window : numpy.ndarray
        (n_h, 2) the samples ``[a, b)`` each record's observations use.
    features : numpy.ndarray
        (n_h, 7) the records' features in the window (:mod:`ssw.signal.features`).
    feature_sigma : numpy.ndarray
        (n_h, 7) their standard deviations from the noise.
    split : numpy.ndarray
        (n_h,) s after the trigger sample: the midpoint between the incident and the
        reflected peak (where a ``delay`` begins).
    """

    id: str
    E: float | None
    nu: float
    force: np.ndarray
    trigger_index: np.ndarray
    rate: float
    noise: float
    rails: np.ndarray
    window: np.ndarray
    features: np.ndarray
    feature_sigma: np.ndarray
    split: np.ndarray

    @property
    def n(self) -> int:
        """Hits."""
        return int(self.force.shape[0])

    @classmethod
    def of(cls, forces: Any, trigger_index: Any, rate: float, *, E: float | None, nu: float,
           id: str = "", full_scale: float | None = None, noise: float | None = None,
           lead: int = LEAD) -> Hits:
        """The hits of one sample from its records.

        Parameters
        ----------
        forces : array_like
            (n_h, N) N, the records (as recorded: baseline included).
        trigger_index : array_like
            (n_h,) or a scalar: each record's trigger sample.
        rate : float
            S/s.
        E : float or None
            Pa, the sample's modulus if known.
        nu : float
            Its Poisson's ratio.
        id : str
            Its name.
        full_scale : float or None
            N, the rails (None: none).
        noise : float or None
            N rms (default: the pretrigger samples' robust sigma, the median over hits).
        lead : int
            Samples kept before the trigger sample.

        Returns
        -------
        Hits
            With each record's window and features.

        Raises
        ------
        RecordingError
            A record without an incident and a reflected peak, or too short.
        """
        from ssw.signal.filters import baseline, noise_sigma

        F = np.atleast_2d(np.asarray(forces, float))
        n_h, N = F.shape
        kt = np.broadcast_to(np.asarray(trigger_index, int), (n_h,)).copy()
        rails = (np.zeros(F.shape, bool) if full_scale is None
                 else np.abs(F) >= RAIL_SHARE * full_scale)
        y = np.stack([F[h] - baseline(F[h], kt[h]) for h in range(n_h)])
        sig = float(np.median([noise_sigma(y[h], kt[h]) for h in range(n_h)])) \
            if noise is None else float(noise)
        sig = max(sig, 1e-12)
        window = np.zeros((n_h, 2), int)
        feats = np.full((n_h, len(FEATURES)), np.nan)
        fsig = np.full((n_h, len(FEATURES)), np.nan)
        split = np.full(n_h, np.nan)
        for h in range(n_h):
            a = max(int(kt[h]) - lead, 0)
            first = _record_features(y[h, a:], rate, sig)
            if not np.isfinite(first.values[0]):
                raise RecordingError(f"{id or 'sample'}: hit {h} has no incident and "
                                     "reflected peak for a waveform fit")
            t_end = (first.times["secondary"] if np.isfinite(first.times["secondary"])
                     else first.times["reflected"])
            width = first.values[5] if np.isfinite(first.values[5]) else first.values[4]
            b = min(N, a + int(np.ceil((t_end + TAIL_WIDTHS * width) * rate)) + TAIL_SAMPLES)
            f = _record_features(y[h, a:b], rate, sig)
            window[h] = a, b
            feats[h], fsig[h] = f.values, f.sigma
            split[h] = (a - kt[h]) / rate + 0.5 * (f.times["incident"] + f.times["reflected"])
        return cls(id, E, float(nu), y, kt, float(rate), sig, rails, window, feats, fsig,
                   split)

    @classmethod
    def from_recording(cls, rec: Any, *, E: float | None, nu: float,
                       full_scale: float | None = None, id: str = "") -> Hits:
        """The hits of a :class:`ssw.daq.recording.Recording` (every hit kept by its
        reader).

        Parameters
        ----------
        rec : ssw.daq.recording.Recording
            The recording.
        E : float or None
            Pa, the sample's modulus if known.
        nu : float
            -, its Poisson's ratio.
        full_scale : float or None
            N, the rails (None: none).
        id : str
            The sample's name (default the file's stem).

        Returns
        -------
        Hits
            As :meth:`of`.
        """
        from pathlib import Path

        forces = np.stack([h.force for h in rec.hits])
        kt = np.array([h.trigger_index for h in rec.hits])
        return cls.of(forces, kt, rec.sample_rate, E=E, nu=nu,
                      id=id or Path(rec.path).stem, full_scale=full_scale)


def _record_features(y: np.ndarray, rate: float, noise: float) -> Any:
    """The features of a record's samples (upsampled as the model's are)."""
    return pulse_features(upsample(y), 1.0 / (UPSAMPLE * rate), noise=noise, rate=rate)


@dataclass
class State:
    """Values of every parameter of a waveform model (SI).

    Parameters
    ----------
    E : numpy.ndarray
        (n_s,) Pa, per sample.
    striker_velocity : numpy.ndarray
        (n_hits,) m/s, per hit (the samples' hits in order).
    time_offset : numpy.ndarray
        (n_hits,) s.
    delay : numpy.ndarray
        (n_hits,) s.
    globals : dict
        ``preload`` (N), ``sensor_mass``, ``striker_mass`` (kg), ``damping`` (N s/m),
        ``gain`` (-).
    """

    E: np.ndarray
    striker_velocity: np.ndarray
    time_offset: np.ndarray
    delay: np.ndarray
    globals: dict[str, float]

    def copy(self) -> State:
        """A deep copy.

        Returns
        -------
        State
            The copy (its own arrays and globals).
        """
        return State(self.E.copy(), self.striker_velocity.copy(), self.time_offset.copy(),
                     self.delay.copy(), dict(self.globals))


@dataclass(frozen=True)
class Column:
    """One parameter of a fit: its name and which sample (``E``) or hit (per-hit) it is.

    Parameters
    ----------
    name : str
        The parameter (``E``, a :data:`PER_HIT` or a :data:`GLOBALS` name).
    index : int
        The sample or hit it belongs to; -1 for a global.
    """

    name: str
    index: int = -1

    @property
    def label(self) -> str:
        """``name`` or ``name[index]``."""
        return self.name if self.index < 0 else f"{self.name}[{self.index}]"


def columns_of(n_samples: int, n_hits: int) -> list[Column]:
    """Every parameter of a model of ``n_samples`` samples and ``n_hits`` hits: the
    samples' E, the hits' speeds, time offsets and delays, the globals.

    Parameters
    ----------
    n_samples : int
        Samples of the model.
    n_hits : int
        Hits of all samples.

    Returns
    -------
    list of Column
        The columns in that order.
    """
    out = [Column("E", i) for i in range(n_samples)]
    for name in PER_HIT:
        out += [Column(name, h) for h in range(n_hits)]
    return out + [Column(g) for g in GLOBALS]


def get(state: State, col: Column) -> float:
    """The value of ``col`` in ``state``.

    Parameters
    ----------
    state : State
        The parameter values.
    col : Column
        The parameter.

    Returns
    -------
    float
        Its value, SI.
    """
    if col.index < 0:
        return float(state.globals[col.name])
    return float(getattr(state, col.name)[col.index])


def put(state: State, col: Column, value: float) -> None:
    """Set ``col`` in ``state``.

    Parameters
    ----------
    state : State
        The parameter values (changed in place).
    col : Column
        The parameter.
    value : float
        Its new value, SI.
    """
    if col.index < 0:
        state.globals[col.name] = float(value)
    else:
        getattr(state, col.name)[col.index] = float(value)


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


def observe(setup: Setup, state: State, wanted: set[str] | None = None) -> Observed:
    """The model's observations of every sample's records and their derivatives, in ONE
    chain run of all hits (module docstring).

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
        then its ``trigger`` and ``delay`` priors.
    """
    from ssw.tof import api

    wanted = set(PARAMETERS) if wanted is None else set(wanted)
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
    names = _names(wanted)
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
    k = len(names)
    # the model's trigger crossing, on the fine output (chain clock)
    L = acq.taps.size
    t_fine = grid.s[grid.lead + L - 1:][: fine.shape[0]] + acq.pure_delay
    t_c, j = trigger_time(t_fine, g * fine[:, :, 0], setup.trigger_level)
    cols_h = np.arange(n_h)
    slope = g * (fine[j, cols_h, 0] - fine[j - 1, cols_h, 0]) * (acq.oversample * fs)
    d_fine = 0.5 * (fine[j, cols_h] + fine[j - 1, cols_h])  # (n_h, channels)
    columns = setup.columns
    index = {c: i for i, c in enumerate(columns)}
    rows_model, rows_data, rows_sigma, rows_kind, rows_hit, rows_jac = [], [], [], [], [], []

    def jac_block(h: int, d_chain: np.ndarray, d_tau: np.ndarray, d_delay: np.ndarray,
                  d_gain: np.ndarray) -> np.ndarray:
        """Rows of hit ``h``: chain sensitivities (m, k), the time offset's, the delay's
        and the gain's derivatives (m,) -> the parameters' columns."""
        m = d_gain.shape[0]
        J = np.zeros((m, len(columns)))
        for c, name in enumerate(names):
            if name == "E":
                i = hit_sample[h]
                if setup.samples[i].E is None or "E" in wanted:
                    J[:, index[Column("E", int(i))]] = d_chain[:, c]
            elif name == "striker_velocity":
                J[:, index[Column("striker_velocity", h)]] = d_chain[:, c]
            else:
                J[:, index[Column(name)]] = d_chain[:, c]
        J[:, index[Column("time_offset", h)]] = d_tau
        J[:, index[Column("delay", h)]] = d_delay
        J[:, index[Column("gain")]] = d_gain
        return J

    for h in range(n_h):
        i = hit_sample[h]
        smp = setup.samples[i]
        hh = h - setup._starts[i]
        a, b = smp.window[hh]
        m = b - a
        y = g * samples[:m, h]  # (m, channels)
        if setup.level == "waveform":
            keep = ~smp.rails[hh, a:b]
            val = y[keep, 0]
            J = jac_block(h, y[keep, 1:1 + k], y[keep, 1 + k], y[keep, 2 + k], val / g)
            rows_model.append(val)
            rows_data.append(smp.force[hh, a:b][keep])
            top = float(np.max(np.abs(smp.force[hh, a:b])))
            rows_sigma.append(np.full(val.size, np.hypot(
                smp.noise, setup.floor.get("waveform", 0.0) * top)))
            rows_kind += ["waveform"] * val.size
        else:
            up = upsample(y)
            f = pulse_features(up[:, 0], 1.0 / (UPSAMPLE * fs),
                               dy=np.concatenate([up[:, 1:], up[:, :1] / g], axis=1),
                               noise=smp.noise, rate=fs)
            val = f.values
            J = jac_block(h, f.jacobian[:, :k], f.jacobian[:, k], f.jacobian[:, k + 1],
                          f.jacobian[:, k + 2])
            if setup.discrepancy is not None:
                val, J = _corrected(setup, val, J, E[h], index.get(Column("E", int(i))),
                                    smp.E is None or "E" in wanted)
            rows_model.append(val)
            rows_data.append(smp.features[hh])
            rel = np.array([setup.floor.get(n, 0.0) for n in FEATURES])
            rows_sigma.append(np.hypot(smp.feature_sigma[hh],
                                       rel * np.abs(smp.features[hh])))
            rows_kind += list(FEATURES)
        rows_hit.append(np.full(val.size, h))
        rows_jac.append(J)
        # the trigger: time_offset - t_c ~ 1/(2 f_s) +- trigger_sigma
        Jt = np.zeros((1, len(columns)))
        dtc = -g * d_fine[h, 1:1 + k] / slope[h]
        Jt[0] -= jac_block(h, dtc[None, :], np.zeros(1), np.zeros(1), np.zeros(1))[0]
        Jt[0, index[Column("gain")]] = setup.trigger_level / (g * slope[h])
        Jt[0, index[Column("time_offset", h)]] = 1.0
        rows_model.append(np.array([tau[h] - t_c[h] - 0.5 / fs]))
        rows_data.append(np.zeros(1))
        rows_sigma.append(np.array([setup.trigger_sigma]))
        rows_kind.append("trigger")
        rows_hit.append(np.array([h]))
        rows_jac.append(Jt)
        # the delay's prior
        Jd = np.zeros((1, len(columns)))
        Jd[0, index[Column("delay", h)]] = 1.0
        rows_model.append(np.array([state.delay[h]]))
        rows_data.append(np.zeros(1))
        rows_sigma.append(np.array([setup.tof_scatter]))
        rows_kind.append("delay")
        rows_hit.append(np.array([h]))
        rows_jac.append(Jd)
    return Observed(np.concatenate(rows_model), np.concatenate(rows_data),
                    np.concatenate(rows_sigma), np.array(rows_kind),
                    np.concatenate(rows_hit), np.concatenate(rows_jac), columns)


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
        (q, q) their covariance in the scaled coordinates (:func:`coordinate`), from the
        Gauss-Newton curvature at the optimum (unscaled by the misfit).
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
        The global start's grid (:func:`global_start`) with each point's chi^2, if any.
    unexplained : int
        Observations the record has a value for and the model, at the optimum, none.
    floor : dict
        The model-error floor of the fit's weights (``floor`` of :class:`Setup`).
    discrepancy : ssw.calibration.discrepancy.Discrepancy or None
        The model's discrepancy the fit corrects its features by (``discrepancy`` of
        :class:`Setup`).
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
    coordinates, each parameter within its range (:data:`PARAMETERS`). A trial point where
    the model loses observations that the current point explains (a hit's pulse or trigger
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
               discrepancy=setup.discrepancy)


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
    (:func:`coordinate`), scaled by the misfit (:attr:`Fit.misfit`), every per-hit
    parameter marginalized; with a model-error floor (``floor`` of :class:`Fit`), times ``hits``:
    the model's error is the same on every hit of a sample and does not average down
    over them as the weights assume (conservative: the noise's share, far smaller, is
    scaled with it).

    Parameters
    ----------
    f : Fit
        A fit (a calibration of records, :func:`calibrate_records`).
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
        The globals (:data:`GLOBALS`).
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
#: Fits of the global parameters with the floor re-estimated from their residuals
#: (:func:`model_floor`) after the first, at most; they stop when the floor settles
#: (every kind within :data:`FLOOR_RTOL` of the last pass's).
FLOOR_PASSES = 4
#: The floor's relative change that counts as settled.
FLOOR_RTOL = 0.1


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


def _bounds(setup: Setup, free: list[Column]) -> tuple[np.ndarray, np.ndarray]:
    """The scaled coordinates' bounds of ``free`` (each parameter's range)."""
    lo, hi = np.empty(len(free)), np.empty(len(free))
    for j, c in enumerate(free):
        p = parameter(c.name, setup.params.damping_law if c.name == "damping" else None)
        log, scale = coordinate(setup, c)
        lo[j], hi[j] = ((np.log(p.lower), np.log(p.upper)) if log
                        else (p.lower / scale, p.upper / scale))
    return lo, hi


def calibrate_records(samples: list[Hits], params: Any, wall: str,
                      wall_options: dict[str, Any], acq: Acquisition, level: str,
                      trigger_level: float, tof_scatter: float,
                      free_globals: tuple[str, ...] = GLOBALS, scan: bool = True,
                      gain: float = 1.0,
                      start_grid: tuple[tuple[float, ...], tuple[float, ...]] | None = None,
                      refine_levels: int = REFINE_LEVELS, discrepancy: bool = True) -> Fit:
    """Fit the device's global parameters to reference records (every sample's E known):
    every one of ``free_globals`` with each hit's striker speed, time offset and delay.

    1. The start: when the sensor's mass and the dashpot may be freed, the best point of
       a grid of them (:func:`global_start`, weights with the floor
       :data:`START_FLOOR`) refined around it (:func:`refine_start`); else (or with
       ``scan`` False) the device's values, each hit's parameters fitted to the records
       with the globals held, and the model-error floor those residuals call for
       (:func:`model_floor`) in the weights of what follows (so that a first fit of the
       globals is not drawn by the noise's weights alone where the model cannot reach
       the records: a calibration of the waveform from the features' one).
    2. A fit of every free parameter; then the model-error floor estimated from its
       residuals (:func:`model_floor`: each kind's chi^2 brought to its share of the
       degrees of freedom) and the fit again with it, until the floor settles
       (:data:`FLOOR_RTOL`, at most :data:`FLOOR_PASSES` times). The chi^2 of a
       calibration is then its degrees of freedom by construction; what it says about the
       model is the floor (stated in the result, and the weights of every measurement
       through the calibration, :func:`ssw.measure.measure_information`).
    3. If some global is not identified (its standard error, scaled by the misfit, beyond
       :data:`ssw.calibration.information.IDENTIFIED_U` in its scaled coordinate), the fit
       again with only the identified ones free, the others at their start's values.
    4. Under model error at the features level (a kind's floor above
       :data:`START_FLOOR`, a few times the chain's own error; two references or more;
       ``discrepancy``): the model's discrepancy, a line in ``(E / E_0)^(-2/5)`` per feature
       (:mod:`ssw.calibration.discrepancy`), estimated with the hits refitted, then the
       floor its corrected residuals leave and the fit of step 2 with it.

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
        The globals that may be freed (:data:`GLOBALS`).
    scan : bool
        Start from :func:`global_start` when the sensor's mass and the dashpot may be
        freed; False: from ``params`` (a calibration of the same records at another level,
        e.g. the waveform's from the features').
    gain : float
        The DAQ gain's start (another level's calibration's).
    start_grid : tuple or None
        The global start's sensor masses (multiples of the device's) and contact
        dissipation coefficients (the unit of ``params.damping_law``; N s/m for the
        dashpot); None: :data:`START_SENSOR_MASS` by :func:`start_damping` of the law.
    refine_levels : int
        Refinements of the global start (:func:`refine_start`).
    discrepancy : bool
        Step 4 where the features' floor says the model departs (False: the floor alone).

    Returns
    -------
    Fit
        The last fit (its ``free`` lists the globals it identified first; its ``floor``
        the model-error floor; its ``discrepancy`` the correction, if any; its ``start``
        the grid).

    Raises
    ------
    ConfigError
        A reference without its E.
    """
    from ssw.calibration.information import IDENTIFIED_U

    if any(s.E is None for s in samples):
        raise ConfigError("reference", [s.id for s in samples if s.E is None],
                          "references with a known E")
    setup = Setup(params, wall, dict(wall_options), acq, level, samples, trigger_level,
                  tof_scatter=tof_scatter)
    glob = device_globals(params, gain)
    E = np.array([s.E for s in samples], float)
    v0 = float(params.striker_velocity)
    n_h = setup.n_hits
    setup.fix_step(State(E, np.full(n_h, 1.5 * v0), np.zeros(n_h), np.zeros(n_h), glob))
    per_hit = [Column(name, h) for name in PER_HIT for h in range(n_h)]
    free = [Column(g) for g in free_globals]
    kinds = FEATURES if level == "features" else ("waveform",)
    if scan and {"sensor_mass", "damping"} <= set(free_globals):
        setup.floor = dict.fromkeys(kinds, START_FLOOR)
        state, scan = refine_start(setup, glob, E, v0, *global_start(
            setup, glob, E, v0, *(start_grid or (None, None))), levels=refine_levels)
    else:  # the device's globals; each hit's own parameters, and the floor they leave
        hits_only = fit(setup, initial_state(setup, glob, E, v0), per_hit)
        state, scan = hits_only.state, []
        setup.floor = model_floor(setup, hits_only)
    f = fit(setup, state, free + per_hit)
    for _ in range(FLOOR_PASSES):  # the floor: the start's, then the residuals' own
        floor = model_floor(setup, f)
        settled = all(abs(v - setup.floor.get(k, 0.0)) <= FLOOR_RTOL * v
                      for k, v in floor.items())
        setup.floor = floor
        f = fit(setup, f.state, free + per_hit)
        if settled:
            break
    while True:
        kept = [c for c in free if f.std(c) <= IDENTIFIED_U]
        if len(kept) == len(free):
            break
        free = kept
        st = f.state.copy()  # what is not identified goes back to its start's value
        st.globals.update({g: state.globals[g] for g in GLOBALS if Column(g) not in free})
        f = fit(setup, st, free + per_hit)
    if (discrepancy and level == "features" and len(samples) >= 2
            and max(f.floor.values(), default=0.0) > START_FLOOR):
        f = _with_discrepancy(setup, f.state, free, per_hit)
    return replace(f, start=scan)


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
    chi^2 and its quantile, the model-error floor, the freed globals' covariance in their
    scaled coordinates) in ``provenance["information"]``, where ``ssw measure
    --information`` reads the gain, the floor and the covariance. The TOF calibration's
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
