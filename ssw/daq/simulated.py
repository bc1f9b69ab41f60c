"""Simulated acquisition: the chain's sensor force seen through an NI 9234, hit by hit.

Signal path per hit (every random draw from one ``numpy.random.Generator`` seeded from
config ``seed``):

1. sensor force ``F(t)`` (N) from ``ssw.tof.api.sensor_signal`` (source ``chain``) or
   two sech^2 pulses with a known TOF (source ``analytic``, :func:`analytic_waveform`),
   minus its initial value: an IEPE sensor does not see the static preload; with
   ``daq.simulation.striker_velocity_cov > 0`` each hit reruns the chain with a striker
   speed drawn about the configured one (the only physical hit-to-hit scatter modelled);
2. AC coupling: first-order high-pass, -3 dB at 0.5 Hz (NI 9234 specs, AC cutoff);
3. the delta-sigma anti-alias filter, modelled as a linear-phase Kaiser FIR at
   ``OVERSAMPLE x f_s``: passband edge 0.45 f_s, stopband 0.55 f_s, 100 dB rejection
   (NI 9234 specs: alias-free bandwidth 0.45 f_s, rejection 100 dB [U]), plus a pure
   delay making the total input delay ``38.4/f_s + 4.5 us`` (NI 9234 specs [U]);
4. sampling at ``f_s`` with a uniform random sample-clock phase and a Gaussian trigger
   jitter (``daq.simulation.trigger_jitter``), white noise of rms
   ``daq.simulation.noise_rms`` (N);
5. 24-bit quantization over +-5 V (LSB = 10 V / 2^24 = 0.596 uV, i.e. 53 uN at
   11.24 mV/N) and clipping at the rails;
6. a software analog-edge reference trigger on the sampled record: the record starts
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
from ssw.daq.settings import NI9234_BITS, NI9234_RANGE_V, DaqSettings
from ssw.errors import ConfigError, DaqError

OVERSAMPLE = 16  # fine-grid rate / f_s for the analog signal and the FIR model
PASS_EDGE = 0.45  # x f_s, NI 9234 alias-free bandwidth
STOP_EDGE = 0.55  # x f_s, NI 9234 stopband start
STOP_DB = 100.0  # dB, stopband rejection
AC_CUTOFF = 0.5  # Hz, NI 9234 AC-coupling -3 dB frequency
DELAY_SAMPLES = 38.4  # input delay 38.4/f_s + DELAY_FIXED (NI 9234 specs [U])
DELAY_FIXED = 4.5e-6  # s
MARGIN = 64  # extra samples before/after the wave on the simulated grid


def lsb_volts() -> float:
    """Quantization step of the NI 9234: 10 V / 2^24, V."""
    return 2 * NI9234_RANGE_V / 2**NI9234_BITS


def input_delay(rate: float) -> float:
    """NI 9234 input delay ``38.4 / f_s + 4.5 us``, s."""
    return DELAY_SAMPLES / rate + DELAY_FIXED


def antialias_fir(oversample: int = OVERSAMPLE) -> np.ndarray:
    """Linear-phase FIR modelling the NI 9234 decimation filter, taps at ``oversample x f_s``.

    Kaiser design (``scipy.signal.kaiserord``/``firwin``): cutoff at f_s/2, transition
    0.45..0.55 f_s, ``STOP_DB`` ripple; unit DC gain. Group delay ``(len - 1) / 2`` fine
    samples.
    """
    from scipy import signal

    nyq = oversample / 2  # in units of f_s
    numtaps, beta = signal.kaiserord(STOP_DB, (STOP_EDGE - PASS_EDGE) / nyq)
    numtaps |= 1  # odd: integer group delay
    taps = signal.firwin(numtaps, 0.5 / nyq, window=("kaiser", beta))
    return taps / taps.sum()


def sech2(x: np.ndarray) -> np.ndarray:
    """``sech(x)^2 = 4 e^(-2|x|) / (1 + e^(-2|x|))^2``, without overflow for large ``|x|``."""
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
        ``(t, F)`` sensor force (s, N); or ``None`` to ask the chain for it
        (``ssw.tof.api.sensor_signal`` and ``ssw.tof.api.tof``).
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
            waveform = api.sensor_signal(soil_E, soil_nu, chain_params, wall, **opts)
            if true_tof is None:
                true_tof = float(api.tof(soil_E, soil_nu, chain_params, wall, **opts))
        self._chain = (chain_params, wall_options or {}) if soil_E is not None else None
        t, f = (np.asarray(a, dtype=np.float64) for a in waveform)
        if t.ndim != 1 or t.shape != f.shape or t.size < 4 or np.any(np.diff(t) <= 0):
            raise ConfigError("waveform", f"shapes {t.shape}, {f.shape}",
                              "1-D increasing times and forces of the same length")
        self.t, self.f = t, f - f[0]
        self.seed = seed
        self.true_tof = true_tof
        self.soil_E, self.soil_nu, self.wall = soil_E, soil_nu, wall

    def describe(self) -> dict[str, Any]:
        d: dict[str, Any] = {"model": "simulated NI 9234 (ssw.daq.simulated)",
                             "oversample": OVERSAMPLE}
        if self.soil_E is not None:
            from dataclasses import asdict, is_dataclass

            params = self._chain[0] if self._chain else None
            d.update(source="ssw.tof.api.sensor_signal", soil_E=self.soil_E,
                     soil_nu=self.soil_nu, wall=self.wall,
                     chain_params=asdict(params) if is_dataclass(params) else repr(params))
        else:
            d.update(source="waveform given by the caller")
        if self.true_tof is not None:
            d.update(true_tof=self.true_tof)
        return d

    def analog(self, settings: DaqSettings) -> tuple[np.ndarray, np.ndarray]:
        """The force after AC coupling and the anti-alias FIR on the fine grid, ``(t, y)``."""
        return analog(self.t, self.f, settings)

    def _varied(self, v: float) -> tuple[np.ndarray, np.ndarray, float]:
        """The chain's sensor force and TOF with striker speed ``v`` (m/s)."""
        from ssw.chain.tof import tof_from_signal
        from ssw.tof import api

        params, opts = self._chain  # type: ignore[misc]
        t, f = api.sensor_signal(self.soil_E, self.soil_nu, params.with_(striker_velocity=v),
                                 self.wall, **opts)
        return t, f - f[0], float(np.ravel(tof_from_signal(t, f[:, None]))[0])

    def hits(self, settings: DaqSettings, n_hits: int) -> Iterator[Hit]:
        """Records of ``n_hits`` hits; with ``striker_velocity_cov > 0`` (chain source) each
        hit's striker speed is drawn from a normal law about the chain's own."""
        rng = np.random.default_rng(self.seed)
        cov = settings.simulation.striker_velocity_cov
        base = self.analog(settings)
        for _ in range(n_hits):
            extra: dict[str, Any] = {}
            ana = base
            if cov > 0 and self._chain is not None:
                v = self._chain[0].striker_velocity * max(1.0 + cov * rng.normal(), 0.1)
                t, f, tof = self._varied(v)
                ana = analog(t, f, settings)
                extra = {"striker_velocity": v, "true_tof": tof}
            elif self.true_tof is not None:
                extra = {"true_tof": self.true_tof}
            yield sample_hit(ana, settings, rng, extra)


def analog(t: np.ndarray, f: np.ndarray, settings: DaqSettings) -> tuple[np.ndarray, np.ndarray]:
    """Force ``f(t)`` (N, s) after AC coupling and the anti-alias FIR on the fine grid.

    Returns ``(t_fine, y)``, delayed by the FIR's group delay plus the extra delay that
    makes the module's total input delay ``38.4/f_s + 4.5 us``.
    """
    from scipy import signal

    fs = settings.sample_rate
    dtf = 1.0 / (OVERSAMPLE * fs)
    pad = (settings.pretrigger_samples + MARGIN) / fs
    t_end = t[-1] + (settings.record_samples + MARGIN) / fs
    tf = np.arange(t[0] - pad, t_end, dtf)
    x = np.interp(tf, t, f, left=0.0, right=f[-1])
    b, a = signal.butter(1, AC_CUTOFF, btype="highpass", fs=1.0 / dtf)
    x = signal.lfilter(b, a, x)
    taps = antialias_fir()
    y = signal.fftconvolve(x, taps)[: x.size]
    fir_delay = (taps.size - 1) / 2 * dtf
    return tf + max(input_delay(fs) - fir_delay, 0.0), y

def sample_hit(ana: tuple[np.ndarray, np.ndarray], settings: DaqSettings,
               rng: np.random.Generator, extra: dict[str, Any]) -> Hit:
    """Sample, add noise, quantize and trigger one record from the analog signal ``ana``."""
    tf, y = ana
    fs = settings.sample_rate
    sim = settings.simulation
    lsb = lsb_volts()
    code_max = 2 ** (NI9234_BITS - 1)
    n_total = int((tf[-1] - tf[0]) * fs) - 1
    phase = rng.uniform(0.0, 1.0)
    jitter = rng.normal(0.0, sim.trigger_jitter) if sim.trigger_jitter > 0 else 0.0
    tk = tf[0] + (phase + np.arange(n_total)) / fs + jitter
    yk = np.interp(tk, tf, y) + rng.normal(0.0, sim.noise_rms, n_total)
    code = np.clip(np.round(yk * settings.sensitivity / lsb), -code_max, code_max - 1)
    yq = code * lsb / settings.sensitivity
    overloaded = bool(np.any(np.abs(code) >= code_max - 1))
    k = trigger_index(yq, settings)
    start = k - settings.pretrigger_samples
    rec = yq[start : start + settings.record_samples]
    info = {"sample_phase": phase, "trigger_jitter_s": jitter, "t_first_sample":
            float(tk[start]), "input_delay_s": input_delay(fs), **extra}
    return Hit(force=rec, trigger_index=settings.pretrigger_samples, overloaded=overloaded,
               extra=info)


def trigger_index(y: np.ndarray, settings: DaqSettings) -> int:
    """First sample index ``k >= pretrigger`` where ``y`` crosses the trigger level.

    Rising slope: ``y[k-1] < level <= y[k]``; falling: ``y[k-1] > level >= y[k]``
    (:mod:`ssw.daq.trigger`, the rule shared with long-channel splitting and the ring-buffer
    software trigger). Raises :class:`~ssw.errors.DaqError` (as the hardware times out) if no
    crossing
    leaves room for a whole record.
    """
    from ssw.daq.trigger import TriggerRule
    from ssw.daq.trigger import trigger_index as first_trigger

    return first_trigger(y, TriggerRule.of(settings))


register_backend("simulated", SimulatedBackend)
