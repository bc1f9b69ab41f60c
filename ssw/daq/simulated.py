"""Simulated acquisition: the chain's sensor force seen through an NI 9234, hit by hit.

Signal path per hit (every random draw from one ``numpy.random.Generator`` seeded from
config ``seed``), the measurement model of :mod:`ssw.daq.model` (one model for simulated
records and for the waveform fits):

1. sensor force ``F(t)`` (N) from ``ssw.tof.api.sensor_signal`` (source ``chain``) or
   two sech^2 pulses with a known TOF (source ``analytic``, :func:`analytic_waveform`),
   minus its initial value: an IEPE sensor does not see the static preload; with
   ``daq.simulation.striker_velocity_cov > 0`` each hit reruns the chain with a striker
   speed drawn about the configured one (the only physical hit-to-hit scatter modelled);
2. the module's linear front end (:func:`ssw.daq.model.acquire`): AC coupling (RC
   high-pass, -3 dB at 0.5 Hz), the anti-alias FIR on the fine grid (passband edge 0.45
   f_s, stopband 0.55 f_s, 100 dB rejection) and the input delay ``38.4/f_s + 4.5 us``;
3. sampling at ``f_s`` with a uniform random sample-clock phase and a Gaussian trigger
   jitter (``daq.simulation.trigger_jitter``), white noise of rms
   ``daq.simulation.noise_rms`` (N);
4. 24-bit quantization over +-5 V (LSB = 10 V / 2^24 = 0.596 uV, i.e. 53 uN at
   11.24 mV/N) and clipping at the rails (:func:`ssw.daq.model.digitize`);
5. a software analog-edge reference trigger on the sampled record: the record starts
   ``pretrigger_samples`` before the first crossing of ``trigger_level`` (the rule of
   :mod:`ssw.daq.trigger`).

The filter's delay is the same for the incident and the reflected peak, so it cancels in
the peak-to-peak TOF; the test suite checks this round trip.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from ssw.daq.backend import Hit, register_backend
from ssw.daq.model import (
    OVERSAMPLE,
    PASS_EDGE,
    STOP_DB,
    STOP_EDGE,
    Acquisition,
    acquire,
    antialias_fir,
    digitize,
    input_delay,
    lsb_volts,
    tabulated,
)
from ssw.daq.settings import DaqSettings
from ssw.errors import ConfigError, DaqError

__all__ = ["OVERSAMPLE", "PASS_EDGE", "STOP_DB", "STOP_EDGE", "SimulatedBackend",
           "analytic_waveform", "antialias_fir", "input_delay", "lsb_volts", "sample_hit",
           "sech2", "trigger_index"]

MARGIN = 64  # extra samples before/after the wave on the simulated grid


def sech2(x: np.ndarray) -> np.ndarray:
    """``sech(x)^2 = 4 e^(-2|x|) / (1 + e^(-2|x|))^2``, without overflow for large ``|x|``.

    Parameters
    ----------
    x : array_like
        The argument, dimensionless.

    Returns
    -------
    numpy.ndarray
        ``sech(x)^2``, float64, the shape of ``x``.
    """
    e = np.exp(-2.0 * np.abs(np.asarray(x, dtype=np.float64)))
    return 4.0 * e / (1.0 + e) ** 2


def analytic_waveform(
    tof: float, *, t_incident: float = 1.0e-3, width: float = 40e-6, f_incident: float = 60.0,
    f_reflected: float = 30.0, duration: float = 6e-3, dt: float = 1e-6,
    width_reflected: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Two sech^2 pulses: ``F = f_i sech^2((t - t_i)/w) + f_r sech^2((t - t_i - tof)/w_r)``.

    A stand-in for the chain's sensor force with an exactly known peak-to-peak TOF
    (s): each pulse is symmetric, so a linear-phase filter delays both peaks by its group
    delay. ``w_r`` (s) defaults to ``w``; forces in N, times in s. Returns ``(t, F)``.

    Parameters
    ----------
    tof : float
        The time between the two peaks, s.
    t_incident : float
        The incident peak's time, s.
    width : float
        The incident pulse's width ``w``, s.
    f_incident : float
        The incident peak force ``f_i``, N.
    f_reflected : float
        The reflected peak force ``f_r``, N.
    duration : float
        The waveform's length, s.
    dt : float
        The time step, s.
    width_reflected : float or None
        The reflected pulse's width ``w_r``, s (None: ``width``).

    Returns
    -------
    t : numpy.ndarray
        The times, s, from 0 in steps of ``dt``.
    F : numpy.ndarray
        The force, N.
    """
    t = np.arange(0.0, duration, dt)
    f = f_incident * sech2((t - t_incident) / width)
    f += f_reflected * sech2((t - t_incident - tof) / (width_reflected or width))
    return t, f


class SimulatedBackend:
    """The ``simulated`` backend: a sensor waveform seen through a modelled NI 9234.

    Parameters
    ----------
    waveform : tuple of numpy.ndarray or None
        ``(t, F)`` sensor force (s, N; its clock starts at ``t[0]``); or ``None`` to ask
        the chain for it (its dense output, ``ssw.tof.api.sensor_force``, and
        ``ssw.tof.api.tof``).
    soil_E : float or None
        The sample's Young's modulus, Pa (when ``waveform`` is None).
    soil_nu : float or None
        The sample's Poisson's ratio (when ``waveform`` is None).
    chain_params : ssw.chain.params.ChainParams or None
        The chain (when ``waveform`` is None).
    wall : str
        The wall law's name (when ``waveform`` is None).
    wall_options : dict or None
        The wall builder's options (when ``waveform`` is None).
    seed : int
        Seeds the noise, sample phase and jitter.
    true_tof : float or None
        The waveform's peak-to-peak TOF, s, stored with every hit if known.
    """

    name = "simulated"

    def __init__(
        self,
        waveform: tuple[np.ndarray, np.ndarray] | None = None,
        *,
        soil_E: float | None = None,
        soil_nu: float | None = None,
        chain_params: Any = None,
        wall: str = "hertz",
        wall_options: dict[str, Any] | None = None,
        seed: int = 0,
        true_tof: float | None = None,
    ) -> None:
        if waveform is None:
            if soil_E is None or soil_nu is None:
                raise ConfigError("simulated backend", "no waveform",
                                  "a (t, F) waveform or soil_E and soil_nu for the chain")
            try:
                from ssw.tof import api
            except ImportError as exc:
                raise DaqError("the chain model (ssw.tof.api) is not available; pass an "
                               "analytic waveform") from exc
            opts = wall_options or {}
            self._wave = api.sensor_force(soil_E, soil_nu, chain_params, wall, **opts)
            if true_tof is None:
                true_tof = float(api.tof(soil_E, soil_nu, chain_params, wall, **opts))
        else:
            t, f = (np.asarray(a, dtype=np.float64) for a in waveform)
            if t.ndim != 1 or t.shape != f.shape or t.size < 4 or np.any(np.diff(t) <= 0):
                raise ConfigError("waveform", f"shapes {t.shape}, {f.shape}",
                                  "1-D increasing times and forces of the same length")
            self._wave = (tabulated(t - t[0], f - f[0]), float(t[-1] - t[0]))
        self._chain = (chain_params, wall_options or {}) if soil_E is not None else None
        self.seed = seed
        self.true_tof = true_tof
        self.soil_E, self.soil_nu, self.wall = soil_E, soil_nu, wall

    def describe(self) -> dict[str, Any]:
        """The simulation the records go with: the model, its source and, for the chain source,
        the soil, the wall law and the chain's parameters.

        Returns
        -------
        dict
            ``model``, ``oversample``, ``source``; ``soil_E`` (Pa), ``soil_nu``, ``wall`` and
            ``chain_params`` for the chain source; ``true_tof`` (s) when known.
        """
        d: dict[str, Any] = {"model": "simulated NI 9234 (ssw.daq.simulated)",
                             "oversample": OVERSAMPLE}
        if self.soil_E is not None:
            from dataclasses import asdict, is_dataclass

            params = self._chain[0] if self._chain else None
            d.update(source="ssw.tof.api.sensor_force", soil_E=self.soil_E,
                     soil_nu=self.soil_nu, wall=self.wall,
                     chain_params=asdict(params) if is_dataclass(params) else repr(params))
        else:
            d.update(source="waveform given by the caller")
        if self.true_tof is not None:
            d.update(true_tof=self.true_tof)
        return d

    def analog(self, settings: DaqSettings) -> tuple[np.ndarray, np.ndarray]:
        """The noise-free band-limited signal the module samples, on its fine grid.

        The fine output of :func:`ssw.daq.model.acquire` for the backend's own wave (AC
        coupling and anti-alias filter, before sampling, noise and quantization): what a
        record's samples are taken from.

        Parameters
        ----------
        settings : DaqSettings
            The acquisition (rate, record length, pretrigger).

        Returns
        -------
        tuple of numpy.ndarray
            ``(t, y)``: s from the hit's start (the fine grid's step ``1 / (O f_s)``) and
            N (the force seen through the sensor's path, in force units).
        """
        force, t_end = self._wave
        fs = settings.sample_rate
        acq = Acquisition.of(settings)
        t0 = -(settings.pretrigger_samples + MARGIN) / fs
        n_total = int((t_end - t0) * fs) + settings.record_samples + MARGIN
        _, y = acquire(acq, lambda s: force(s)[..., None], np.array([t0]), n_total,
                       start=0.0, fine=True)
        return t0 + np.arange(y.shape[0]) * acq.fine_dt, y[:, 0, 0]

    def _varied(self, v: float) -> tuple[tuple[Any, float], float]:
        """The chain's sensor force (dense) and TOF with striker speed ``v`` (m/s)."""
        from ssw.tof import api

        params, opts = self._chain  # type: ignore[misc]
        p = params.with_(striker_velocity=v)
        wave = api.sensor_force(self.soil_E, self.soil_nu, p, self.wall, **opts)
        return wave, float(api.tof(self.soil_E, self.soil_nu, p, self.wall, **opts))

    def hits(self, settings: DaqSettings, n_hits: int) -> Iterator[Hit]:
        """Records of ``n_hits`` hits; with ``striker_velocity_cov > 0`` (chain source) each
        hit's striker speed is drawn from a normal law about the chain's own.

        Parameters
        ----------
        settings : ssw.daq.settings.DaqSettings
            The acquisition settings (``simulation``: noise, jitter, striker speed spread).
        n_hits : int
            How many hits.

        Yields
        ------
        ssw.daq.backend.Hit
            One record per hit (force in N), seeded by ``seed``.
        """
        rng = np.random.default_rng(self.seed)
        cov = settings.simulation.striker_velocity_cov
        for _ in range(n_hits):
            extra: dict[str, Any] = {}
            wave = self._wave
            if cov > 0 and self._chain is not None:
                v = self._chain[0].striker_velocity * max(1.0 + cov * rng.normal(), 0.1)
                wave, tof = self._varied(v)
                extra = {"striker_velocity": v, "true_tof": tof}
            elif self.true_tof is not None:
                extra = {"true_tof": self.true_tof}
            yield sample_hit(wave, settings, rng, extra)


def sample_hit(wave: tuple[Any, float], settings: DaqSettings, rng: np.random.Generator,
               extra: dict[str, Any]) -> Hit:
    """One triggered record of the force ``wave = (force, t_end)`` (``force(s)``: N at
    times s from the hit's start, 0 before it; ``t_end`` s, its last modelled time): samples
    at a random clock phase and jitter through the measurement model
    (:func:`ssw.daq.model.acquire`), noise, quantization and clipping
    (:func:`ssw.daq.model.digitize`), then the trigger's window.

    Parameters
    ----------
    wave : tuple of (callable, float)
        ``(force, t_end)``: the force function, N, and its last modelled time, s.
    settings : ssw.daq.settings.DaqSettings
        The acquisition settings.
    rng : numpy.random.Generator
        The random generator (phase, jitter, noise).
    extra : dict
        Metadata added to the hit's (SI units).

    Returns
    -------
    ssw.daq.backend.Hit
        The record, force in N; ``overloaded`` when a sample hit the rails.

    Raises
    ------
    ssw.errors.DaqError
        When the force never crosses the trigger level with room for a record.
    """
    force, t_end = wave
    fs = settings.sample_rate
    sim = settings.simulation
    acq = Acquisition.of(settings)
    t0 = -(settings.pretrigger_samples + MARGIN) / fs
    n_total = int((t_end - t0) * fs) + settings.record_samples + MARGIN
    phase = rng.uniform(0.0, 1.0)
    jitter = rng.normal(0.0, sim.trigger_jitter) if sim.trigger_jitter > 0 else 0.0
    first = t0 + phase / fs + jitter
    y = acquire(acq, lambda s: force(s)[..., None], np.array([first]), n_total,
                start=0.0)[:, 0, 0]
    yq, rails = digitize(acq, y, rng, noise=sim.noise_rms)
    k = trigger_index(yq, settings)
    start = k - settings.pretrigger_samples
    rec = yq[start : start + settings.record_samples]
    info = {"sample_phase": phase, "trigger_jitter_s": jitter,
            "t_first_sample": float(first + start / fs), "input_delay_s": input_delay(fs),
            **extra}
    return Hit(force=rec, trigger_index=settings.pretrigger_samples,
               overloaded=bool(np.any(rails)), extra=info)


def trigger_index(y: np.ndarray, settings: DaqSettings) -> int:
    """First sample index ``k >= pretrigger`` where ``y`` crosses the trigger level.

    Rising slope: ``y[k-1] < level <= y[k]``; falling: ``y[k-1] > level >= y[k]``
    (:mod:`ssw.daq.trigger`, the rule shared with long-channel splitting and the ring-buffer
    software trigger). Raises :class:`~ssw.errors.DaqError` (as the hardware times out) if no
    crossing
    leaves room for a whole record.

    Parameters
    ----------
    y : numpy.ndarray
        The sampled force, N.
    settings : ssw.daq.settings.DaqSettings
        The trigger's settings.

    Returns
    -------
    int
        The trigger sample's index.

    Raises
    ------
    ssw.errors.DaqError
        When no crossing leaves room for a record.
    """
    from ssw.daq.trigger import TriggerRule
    from ssw.daq.trigger import trigger_index as first_trigger

    return first_trigger(y, TriggerRule.of(settings))


register_backend("simulated", SimulatedBackend)
