"""The records of a calibration or a measurement of records and the parameters of their
model (:mod:`ssw.calibration.waveform`): the levels of information, every parameter's
range and scaled coordinate (:data:`PARAMETERS`), a sample's hits (:class:`Hits`),
the parameters' values (:class:`State`) and their columns (:class:`Column`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

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
#: The globals a lab measures before any calibration, each with the relative standard
#: uncertainty of the device file's value as a prior of the records' fit (``prior`` of
#: :class:`~ssw.calibration.observation.Setup`) where the file states none
#: (``striker.mass_std``, :func:`device_priors`). The striker is weighed (a balance reads it
#: to 0.1 %); 5 % also covers a striker the file states as a bead (``striker.mass`` unset)
#: that departs from one by a few %. Under model error a parameter the records cannot tell
#: from the model's discrepancy is known only from its prior (Brynjarsdottir and O'Hagan
#: 2014): without this one, a model that lacks the device's sensor contacts and
#: dissipation laws (the honesty study's device, ``tests/test_honesty.py``, its striker
#: 1.03x a bead) fits its references' features with the striker at 0.77x a bead and the
#: DAQ gain at 1.38, a pair that explains the references and misses 800 MPa by 18 %; with
#: it, 1.007x and 1.033, and 800 MPa within 3 % (2026-11-29).
GLOBAL_PRIORS = {"striker_mass": 0.05}
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


def device_priors(params: Any, stated: dict[str, float | None] | None = None
                  ) -> dict[str, tuple[float, float]]:
    """The measured globals' priors of a device (:data:`GLOBAL_PRIORS`): each its value in
    the device file (the chain ``params``), with the standard uncertainty the file states
    (``striker.mass_std``: a striker weighed to 0.1 % is held to 0.1 %), else the relative
    width of :data:`GLOBAL_PRIORS`.

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The device's chain (the priors' means, :func:`device_globals`).
    stated : dict or None
        Global -> its stated standard uncertainty (SI) or None (not stated), e.g.
        ``{"striker_mass": Device.striker_mass_std}``.

    Returns
    -------
    dict
        Global -> (mean, standard deviation), SI.
    """
    return _priors(device_globals(params), stated or {})


def _priors(glob: dict[str, float], stated: dict[str, float | None]
            ) -> dict[str, tuple[float, float]]:
    """Each measured global's (value in ``glob``, its ``stated`` standard uncertainty or
    :data:`GLOBAL_PRIORS`' relative width of the value), SI."""
    return {g: (glob[g], float(stated[g]) if stated.get(g) is not None else w * glob[g])
            for g, w in GLOBAL_PRIORS.items()}


def measured_priors(globals_: dict[str, float], free: tuple[str, ...],
                    prior: dict[str, Any] | None = None) -> dict[str, tuple[float, float]]:
    """The priors of the measured globals among ``free`` (:data:`GLOBAL_PRIORS`).

    Parameters
    ----------
    globals_ : dict
        The device's globals (SI; :func:`device_globals`): the priors' means.
    free : tuple of str
        The globals a fit frees (a held global needs no prior).
    prior : dict or None
        Global -> (mean, standard deviation), SI, a pair or its JSON list (a calibration's
        ``provenance["information"]["prior"]``: the device file's values another level was
        fitted with), in place of ``globals_``' values with :data:`GLOBAL_PRIORS`' relative
        widths.

    Returns
    -------
    dict
        Global -> (mean, standard deviation), SI, for each freed measured global.
    """
    if prior is None:
        prior = _priors(globals_, {})
    return {g: (float(m), float(s)) for g, (m, s) in prior.items() if g in free}


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
