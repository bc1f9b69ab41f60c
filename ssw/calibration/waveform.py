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

import itertools
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

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
    """The global parameters (:data:`GLOBALS`, SI) of a chain ``params`` and a DAQ gain."""
    return {"preload": float(params.preload),
            "sensor_mass": float(params.masses[params.sensor_index]),
            "striker_mass": float(params.masses[0]), "damping": float(params.damping),
            "gain": float(gain)}


def parameter(name: str) -> Parameter:
    """The parameter ``name`` of :data:`PARAMETERS` (ConfigError listing them otherwise)."""
    if name not in PARAMETERS:
        raise ConfigError("parameter", name, f"one of {', '.join(PARAMETERS)}")
    return PARAMETERS[name]


@dataclass(frozen=True)
class Hits:
    """The records of one sample, ready for a waveform fit. SI units.

    Attributes
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
        reader)."""
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

    Attributes
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
        """A deep copy."""
        return State(self.E.copy(), self.striker_velocity.copy(), self.time_offset.copy(),
                     self.delay.copy(), dict(self.globals))


@dataclass(frozen=True)
class Column:
    """One parameter of a fit: its name and which sample (``E``) or hit (per-hit) it is."""

    name: str
    index: int = -1

    @property
    def label(self) -> str:
        """``name`` or ``name[index]``."""
        return self.name if self.index < 0 else f"{self.name}[{self.index}]"


def columns_of(n_samples: int, n_hits: int) -> list[Column]:
    """Every parameter of a model of ``n_samples`` samples and ``n_hits`` hits: the
    samples' E, the hits' speeds, time offsets and delays, the globals."""
    out = [Column("E", i) for i in range(n_samples)]
    for name in PER_HIT:
        out += [Column(name, h) for h in range(n_hits)]
    return out + [Column(g) for g in GLOBALS]


def get(state: State, col: Column) -> float:
    """The value of ``col`` in ``state``."""
    if col.index < 0:
        return float(state.globals[col.name])
    return float(getattr(state, col.name)[col.index])


def put(state: State, col: Column, value: float) -> None:
    """Set ``col`` in ``state``."""
    if col.index < 0:
        state.globals[col.name] = float(value)
    else:
        getattr(state, col.name)[col.index] = float(value)


@dataclass(frozen=True)
class Observed:
    """The model's observations of the samples' records and their derivatives.

    Attributes
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

    Attributes
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
    dt : float or None
        s, the chain's step for every run (fixed by :meth:`fix_step`).
    runs : int
        Chain runs so far (a cost counter).
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
        """(n_hits,) the sample of each hit."""
        return np.repeat(np.arange(len(self.samples)), [s.n for s in self.samples])

    def fix_step(self, state: State, margin: float = 1.25) -> float:
        """Fix the chain's step for every later run: the integrator's step for ``margin``
        times the fastest striker of ``state`` and its lightest masses (one
        discretization for a whole fit: its model is smooth in the parameters)."""
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
    t_last = float(np.max(first + (n_win - 1) / fs)) - acq.pure_delay
    vary = {"striker_velocity": state.striker_velocity}
    grid = fine_grid(acq, first, n_win, start=0.0)
    s_split = tau + split - acq.delay  # chain (input) time of each hit's split
    after = grid.s > s_split[None, :]
    shifted = grid.s - np.where(after, state.delay[None, :], 0.0)
    dt = setup.dt
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
            rows_sigma.append(np.full(val.size, smp.noise))
            rows_kind += ["waveform"] * val.size
        else:
            up = upsample(y)
            f = pulse_features(up[:, 0], 1.0 / (UPSAMPLE * fs),
                               dy=np.concatenate([up[:, 1:], up[:, :1] / g], axis=1),
                               noise=smp.noise, rate=fs)
            val = f.values
            J = jac_block(h, f.jacobian[:, :k], f.jacobian[:, k], f.jacobian[:, k + 1],
                          f.jacobian[:, k + 2])
            rows_model.append(val)
            rows_data.append(smp.features[hh])
            rows_sigma.append(smp.feature_sigma[hh])
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
    a time offset in sample periods, a delay in units of the prior's width)."""
    if col.name == "time_offset":
        return False, 1.0 / setup.acq.sample_rate
    if col.name == "delay":
        return False, setup.tof_scatter
    p = parameter(col.name)
    return p.log, p.scale


def to_x(setup: Setup, cols: list[Column], values: np.ndarray) -> np.ndarray:
    """Scaled coordinates (:func:`coordinate`) of SI values, one per column."""
    out = np.empty(len(cols))
    for j, c in enumerate(cols):
        log, scale = coordinate(setup, c)
        out[j] = np.log(values[j]) if log else values[j] / scale
    return out


def from_x(setup: Setup, cols: list[Column], x: np.ndarray) -> np.ndarray:
    """SI values of scaled coordinates, one per column."""
    out = np.empty(len(cols))
    for j, c in enumerate(cols):
        log, scale = coordinate(setup, c)
        out[j] = np.exp(x[j]) if log else x[j] * scale
    return out


def dtheta_dx(setup: Setup, cols: list[Column], values: np.ndarray) -> np.ndarray:
    """``d value / d x`` per column (the value for a log coordinate, else the scale)."""
    return np.array([values[j] if coordinate(setup, c)[0] else coordinate(setup, c)[1]
                     for j, c in enumerate(cols)])


#: The chi^2 quantile beyond which a fit says the model does not explain the records.
FLAG_QUANTILE = 0.999


@dataclass(frozen=True)
class Fit:
    """A fit of a waveform model's free parameters to the records. SI units.

    Attributes
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
        coordinate), times ``sqrt(misfit)`` when ``scaled``."""
        j = self.free.index(col)
        s = float(np.sqrt(max(self.cov_x[j, j], 0.0)))
        return s * np.sqrt(self.misfit) if scaled else s


def _residuals(setup: Setup, state: State, free: list[Column], wanted: set[str]
               ) -> tuple[np.ndarray, np.ndarray, int]:
    """Weighted residuals and their Jacobian in the scaled coordinates of ``free`` (rows
    where the model or the data has no value, a feature not found, count 0), and how many
    rows the record has a value for but the model none (unexplained)."""
    obs = observe(setup, state, wanted)
    index = {c: j for j, c in enumerate(obs.columns)}
    vals = np.array([get(state, c) for c in free])
    J = obs.jacobian[:, [index[c] for c in free]] * dtheta_dx(setup, free, vals)[None, :]
    r = (obs.model - obs.data) / obs.sigma
    ok = np.isfinite(r) & np.all(np.isfinite(J), axis=1)
    unexplained = int(np.count_nonzero(~ok & np.isfinite(obs.data)))
    return (np.where(ok, r, 0.0), np.where(ok[:, None], J / obs.sigma[:, None], 0.0),
            unexplained)


def fit(setup: Setup, state: State, free: list[Column], iterations: int | None = None
        ) -> Fit:
    """Fit the ``free`` parameters of ``state`` to the records by the one bounded
    Levenberg-Marquardt (:func:`ssw.calibration.lm.levenberg_marquardt`), in the scaled
    coordinates, each parameter within its range (:data:`PARAMETERS`).

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
    lo, hi = np.empty(len(free)), np.empty(len(free))
    for j, c in enumerate(free):
        p = parameter(c.name)
        log, scale = coordinate(setup, c)
        lo[j], hi[j] = ((np.log(p.lower), np.log(p.upper)) if log
                        else (p.lower / scale, p.upper / scale))
    x0 = np.clip(x0, lo, hi)

    def at(x: np.ndarray) -> State:
        st = work.copy()
        for c, v in zip(free, from_x(setup, free, x), strict=True):
            put(st, c, v)
        return st

    r, J, lost = _residuals(setup, at(x0), free, wanted)
    pr = Problem(x0, r, J, float(r @ r), np.eye(len(free)))
    unexplained = {x0.tobytes(): lost}  # per point: rows the model has no value for

    def evaluate(trial: dict[int, np.ndarray]) -> dict[int, tuple[np.ndarray, np.ndarray,
                                                                  float]]:
        out = {}
        for i, x in trial.items():
            rr, JJ, unexplained[x.tobytes()] = _residuals(setup, at(x), free, wanted)
            out[i] = (rr, JJ, float(rr @ rr))
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
               unexplained=unexplained[pr.x.tobytes()])


#: The global start of a calibration of records (:func:`global_start`): the sensor
#: particle's mass as a multiple of the device's, and the contact dashpot (N s/m). The
#: chain's TOF, amplitudes and pulse widths are far from linear in them (a heavier sensor
#: delays and widens its pulse; a dashpot damps the reflections), so a local fit from the
#: device's nominal values stops in a basin of its own (a conservative chain of nominal
#: masses with the hits' speeds and delays bent to it).
START_SENSOR_MASS = (1.0, 1.3, 1.7)
#: The contact dashpots of the global start's grid, N s/m.
START_DAMPING = (0.0, 3.0, 9.0)
#: Model runs of each grid point's fit of the per-hit parameters.
START_ITERATIONS = 20


def global_start(setup: Setup, globals_: dict[str, float], E: Any, speed: float,
                 sensor_mass: tuple[float, ...] | None = None,
                 damping: tuple[float, ...] | None = None) -> tuple[State, list[dict]]:
    """A start for a calibration of records in the basin of their best fit: on a coarse
    grid of the sensor's mass and the contact dashpot, each point's per-hit parameters
    (striker speed, time offset, delay) from :func:`initial_state` and a short fit
    (:data:`START_ITERATIONS` runs); the point of least chi^2 is the start.

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
        N s/m, the dashpots of the grid (default :data:`START_DAMPING`).

    Returns
    -------
    tuple of (State, list of dict)
        The best point's state (its per-hit parameters fitted) and every point's
        ``sensor_mass``, ``damping`` and ``chi2``.
    """
    per_hit = [Column(name, h) for name in PER_HIT for h in range(setup.n_hits)]
    best, scan = None, []
    grid = itertools.product(START_SENSOR_MASS if sensor_mass is None else sensor_mass,
                             START_DAMPING if damping is None else damping)
    for m, c in grid:
        g = {**globals_, "sensor_mass": m * globals_["sensor_mass"], "damping": float(c)}
        f = fit(setup, initial_state(setup, g, E, speed), per_hit, START_ITERATIONS)
        scan.append({"sensor_mass": g["sensor_mass"], "damping": g["damping"],
                     "chi2": f.chi2})
        if best is None or f.chi2 < best.chi2:
            best = f
    return best.state, scan


def calibrate_records(samples: list[Hits], params: Any, wall: str,
                      wall_options: dict[str, Any], acq: Acquisition, level: str,
                      trigger_level: float, tof_scatter: float,
                      free_globals: tuple[str, ...] = GLOBALS, scan: bool = True) -> Fit:
    """Fit the device's global parameters to reference records (every sample's E known):
    first every one of ``free_globals`` with each hit's striker speed, time offset and
    delay; then, if some global is not identified (its standard error, scaled by the
    misfit, beyond :data:`ssw.calibration.information.IDENTIFIED_U` in its scaled
    coordinate), again with only the identified ones free, the others at their start's
    values. When the sensor's mass and the dashpot may be freed, the start is the best
    point of a coarse grid of them (:func:`global_start`), else the device's values.

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

    Returns
    -------
    Fit
        The last fit (its ``free`` lists the globals it identified first).

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
    glob = device_globals(params)
    E = np.array([s.E for s in samples], float)
    v0 = float(params.striker_velocity)
    n_h = setup.n_hits
    setup.fix_step(State(E, np.full(n_h, 1.5 * v0), np.zeros(n_h), np.zeros(n_h), glob))
    per_hit = [Column(name, h) for name in PER_HIT for h in range(n_h)]
    free = [Column(g) for g in free_globals]
    if scan and {"sensor_mass", "damping"} <= set(free_globals):
        state, scan = global_start(setup, glob, E, v0)
    else:
        state, scan = initial_state(setup, glob, E, v0), []
    while True:
        f = replace(fit(setup, state, free + per_hit), start=scan)
        kept = [c for c in free if f.std(c) <= IDENTIFIED_U]
        if len(kept) == len(free):
            return f
        free = kept


def with_fit(cal: Any, f: Fit, level: str) -> Any:
    """A calibration with what a fit of its references' records identified
    (:func:`calibrate_records`): the device's preload and masses, the dashpot (the
    numerics' ``damping``) and the striker speed (the hits' mean) at the fit's values
    (fitted where freed, else the fit's start: the device's, or the global start's);
    the fit itself (level, freed parameters with their standard errors, the DAQ gain,
    chi^2 and its quantile) in ``provenance["information"]``, where ``ssw measure
    --information`` reads the gain. The TOF calibration's covariance stays the
    calibration term of a TOF measurement's budget.

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
            "start": f.start,
            "striker_velocity_per_hit": [float(v) for v in f.state.striker_velocity],
            "chi2": f.chi2, "chi2_dof": f.dof, "chi2_quantile": f.quantile,
            "flagged": f.flagged, "unexplained": f.unexplained, "converged": f.converged,
            "runs": f.runs}
    parameters = {**cal.parameters, **{k: v for k, v in changes.items()
                                       if k in cal.parameters}}
    return replace(cal, device=cal.device.with_(**changes), parameters=parameters,
                   numerics=numerics, provenance={**cal.provenance, "information": info})
