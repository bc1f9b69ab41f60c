"""The measurement model: a sensor force seen through the sensor and the NI 9234, sample by
sample.

What a record holds (one hit; ``F(t)`` the chain's sensor force, N, on the chain's clock,
``t = 0`` at the striker's first contact; ``F_0`` its static value)::

    y_k = clip(Q(S g [A (F - F_0)](t_k) + S n_k)) / S,      t_k = tau + (k - k_trig) / f_s

1. **sensor**: an IEPE force sensor of sensitivity ``S`` (V/N; PCB 208C02 ~11.24 mV/N,
   REFERENCE.md [U]) that does not see the static load ``F_0`` (its discharge time
   constant, minutes, is far longer than a hit); ``g`` the DAQ gain, the ratio of the true
   sensitivity to the nominal one (1 when the sensor is as stated: a calibratable
   parameter, :mod:`ssw.calibration.waveform`);
2. ``A``, the module's linear front end, three linear time-invariant filters:

   * **AC coupling** (``coupling: AC``, needed by IEPE): a single-pole RC high-pass
     (NI-DAQmx Device Considerations, "Input Coupling": a single-pole resistor-capacitor
     high-pass filter), -3 dB at :data:`AC_CORNER` (NI 9234 specifications, AC cutoff
     frequency [U]: 0.5 Hz), ``H(f) = j f / (j f + f_c)``; discretized by the bilinear
     transform on the fine grid (``scipy.signal.butter``, prewarped at ``f_c``);
   * **anti-alias filter**: the delta-sigma converter's linear-phase decimation filter
     (NI 9234: alias-free bandwidth 0.45 ``f_s``, stopband from 0.55 ``f_s``, 100 dB
     rejection [U]), modelled by a Kaiser-window FIR at :data:`OVERSAMPLE` x ``f_s``
     (:func:`antialias_fir`) applied to the force on that fine grid and decimated: the
     converter's own structure (a modulator oversampling the input, a digital filter, a
     decimator), with our taps;
   * **input delay**: the module's fixed group delay ``38.4 / f_s + 4.5 us`` (NI 9234
     specifications [U]), the FIR's own ``(L - 1) / 2`` fine steps plus a pure delay;

3. **sampling** at ``t_k``: the record's sample ``k`` on the chain's clock, ``tau`` the
   time of the trigger sample ``k_trig`` (the trigger's time offset: where the hit began
   relative to the record; the analog-edge trigger puts ``tau`` within one sample after
   the model's crossing of the trigger level, :func:`trigger_time`);
4. **noise floor** ``n_k``: white, rms :attr:`Acquisition.noise` (N): the module's idle
   channel noise, :data:`NOISE_V` = 50 uV rms at 51.2 kS/s (NI 9234 specifications, 97 dB
   dynamic range [U]), over the sensitivity: 4.4 mN at 11.24 mV/N;
5. **quantization** ``Q``: 24 bits over +-5 V (LSB 0.596 uV), and **clipping** at the
   rails (:func:`digitize`).

Steps 1-3 are linear in the force: the derivative of a record with respect to any
parameter of the force (the chain's forward sensitivities, ``dF/dp`` on its dense output)
is the same chain applied to ``dF/dp`` (:func:`acquire` filters any stack of inputs at
once); the derivative with respect to ``tau`` is the chain applied to ``dF/dt`` (the dense
output's time derivative); with respect to the gain, the record over ``g``. Steps 4-5 are
what a recording adds; a fit weights its residuals by the noise and leaves clipped samples
out (their derivative is 0).

The linear part is stated as data (:class:`Acquisition`: rate, sensitivity, coupling,
corner, filter design) so that :func:`frequency_response` gives its closed form for the
tests, and the simulated backend (:mod:`ssw.daq.simulated`) and the waveform fits
(:mod:`ssw.calibration.waveform`) use this one model: a simulated record and a recorded
one are the same kind of object, sample for sample.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from ssw.daq.settings import NI9234_BITS, NI9234_RANGE_V
from ssw.errors import ConfigError

#: Fine-grid rate over ``f_s``: the modelled converter's oversampling.
OVERSAMPLE = 16
#: Passband edge over ``f_s``: the NI 9234's alias-free bandwidth (REFERENCE.md).
PASS_EDGE = 0.45
#: Stopband start over ``f_s`` (NI 9234 specifications [U]).
STOP_EDGE = 0.55
#: Stopband rejection, dB (NI 9234 specifications [U]).
STOP_DB = 100.0
#: Hz, the AC coupling's -3 dB frequency (NI 9234 specifications, AC cutoff [U]).
AC_CORNER = 0.5
#: The input delay ``DELAY_SAMPLES / f_s + DELAY_FIXED`` (NI 9234 specifications [U]).
DELAY_SAMPLES = 38.4
DELAY_FIXED = 4.5e-6  # s
#: V rms, the NI 9234's idle channel noise at 51.2 kS/s (specifications: 97 dBFS [U]).
NOISE_V = 50e-6


def lsb_volts() -> float:
    """Quantization step of the NI 9234: 10 V / 2^24, V.

    Returns
    -------
    float
        The step, V.
    """
    return 2 * NI9234_RANGE_V / 2**NI9234_BITS


def input_delay(rate: float) -> float:
    """NI 9234 input delay ``38.4 / f_s + 4.5 us``, s, at the sample rate ``rate`` (S/s).

    Parameters
    ----------
    rate : float
        The sample rate, S/s.

    Returns
    -------
    float
        The delay, s.

    References
    ----------
    NI 9234 specifications, input delay (REFERENCE.md [U]).
    """
    return DELAY_SAMPLES / rate + DELAY_FIXED


@lru_cache(maxsize=8)
def _fir(oversample: int) -> np.ndarray:
    from scipy import signal

    nyq = oversample / 2  # in units of f_s
    numtaps, beta = signal.kaiserord(STOP_DB, (STOP_EDGE - PASS_EDGE) / nyq)
    numtaps |= 1  # odd: integer group delay
    taps = signal.firwin(numtaps, 0.5 / nyq, window=("kaiser", beta))
    taps = taps / taps.sum()
    taps.setflags(write=False)
    return taps


def antialias_fir(oversample: int = OVERSAMPLE) -> np.ndarray:
    """Linear-phase FIR modelling the NI 9234's decimation filter, taps at ``oversample x
    f_s``.

    Kaiser design (``scipy.signal.kaiserord``/``firwin``): cutoff at ``f_s / 2``,
    transition :data:`ssw.daq.model.PASS_EDGE` .. :data:`ssw.daq.model.STOP_EDGE` ``f_s``,
    :data:`ssw.daq.model.STOP_DB` ripple; unit
    DC gain; odd length ``L``, group delay ``(L - 1) / 2`` fine samples.

    Parameters
    ----------
    oversample : int
        The fine grid's rate over ``f_s``.

    Returns
    -------
    numpy.ndarray
        (L,) taps (a read-only copy of a cached design).
    """
    return _fir(int(oversample)).copy()


@dataclass(frozen=True)
class Acquisition:
    """One force channel of an NI 9234 as the measurement model sees it. SI units.

    Parameters
    ----------
    sample_rate : float
        S/s (``51200 / n``).
    sensitivity : float
        V/N, the sensor's stated sensitivity (records are in N at it).
    coupling : str
        ``AC`` (the RC high-pass) or ``DC`` (none).
    ac_corner : float
        Hz, the AC coupling's -3 dB frequency.
    noise_rms : float or None
        N rms of the noise floor; None: the module's, ``NOISE_V / sensitivity``.
    oversample : int
        The fine grid's rate over the sample rate.
    """

    sample_rate: float = 51200.0
    sensitivity: float = 11.24e-3
    coupling: str = "AC"
    ac_corner: float = AC_CORNER
    noise_rms: float | None = None
    oversample: int = OVERSAMPLE

    def __post_init__(self) -> None:
        if self.coupling not in ("AC", "DC"):
            raise ConfigError("daq.coupling", self.coupling, "AC or DC")
        for name in ("sample_rate", "sensitivity", "ac_corner"):
            if not getattr(self, name) > 0:
                raise ConfigError(f"acquisition {name}", getattr(self, name), "> 0")
        if self.noise_rms is not None and not self.noise_rms >= 0:
            raise ConfigError("noise_rms", self.noise_rms, "a force >= 0 N rms")
        if self.oversample < 2:
            raise ConfigError("oversample", self.oversample, "an integer >= 2")

    @classmethod
    def of(cls, settings: Any, **changes: Any) -> Acquisition:
        """The model of a :class:`ssw.daq.settings.DaqSettings` (rate, sensitivity,
        coupling), with ``changes``.

        Parameters
        ----------
        settings : ssw.daq.settings.DaqSettings
            The acquisition settings.
        **changes
            Fields of :class:`Acquisition` to replace (None values are ignored).

        Returns
        -------
        Acquisition
            The model.
        """
        values = {"sample_rate": float(settings.sample_rate),
                  "sensitivity": float(settings.sensitivity), "coupling": settings.coupling}
        values.update({k: v for k, v in changes.items() if v is not None})
        return cls(**values)

    @property
    def noise(self) -> float:
        """N rms, the noise floor (``noise_rms``, else the module's idle noise)."""
        return float(NOISE_V / self.sensitivity if self.noise_rms is None else self.noise_rms)

    @property
    def full_scale(self) -> float:
        """N, the force at the +-5 V rails."""
        return NI9234_RANGE_V / self.sensitivity

    @property
    def dt(self) -> float:
        """s, the sample period."""
        return 1.0 / self.sample_rate

    @property
    def fine_dt(self) -> float:
        """s, the fine grid's step."""
        return 1.0 / (self.oversample * self.sample_rate)

    @property
    def taps(self) -> np.ndarray:
        """The anti-alias FIR (:func:`antialias_fir`)."""
        return _fir(self.oversample)

    @property
    def delay(self) -> float:
        """s, the module's input delay (:func:`input_delay`)."""
        return input_delay(self.sample_rate)

    @property
    def pure_delay(self) -> float:
        """s, the input delay beyond the FIR's group delay."""
        return self.delay - (self.taps.size - 1) / 2 * self.fine_dt


def frequency_response(acq: Acquisition, f: np.ndarray) -> np.ndarray:
    """The linear front end's response at frequencies ``f`` (Hz): the closed form
    ``H(f) = H_AC(f) H_FIR(f) exp(-2 pi j f D_pure)``, ``H_AC = j f / (j f + f_c)`` (analog
    RC), ``H_FIR`` the taps' transfer function at the fine rate, ``D_pure``
    (:attr:`Acquisition.pure_delay`) the delay beyond the FIR's.

    Parameters
    ----------
    acq : Acquisition
        The model.
    f : numpy.ndarray
        Hz.

    Returns
    -------
    numpy.ndarray
        Complex, the shape of ``f``: an input ``cos(2 pi f t)`` comes out as
        ``|H| cos(2 pi f t + arg H)``.
    """
    f = np.asarray(f, float)
    taps = acq.taps
    w = 2 * np.pi * f * acq.fine_dt
    h_fir = np.exp(-1j * np.multiply.outer(w, np.arange(taps.size))) @ taps
    h_ac = 1j * f / (1j * f + acq.ac_corner) if acq.coupling == "AC" else np.ones_like(f)
    return h_ac * h_fir * np.exp(-2j * np.pi * f * acq.pure_delay)


@dataclass(frozen=True)
class FineGrid:
    """The fine input grid that produces samples at ``t_first + k / f_s`` (per column).

    Parameters
    ----------
    s : numpy.ndarray
        (M, n) s, the input times (chain clock) of each column (hit).
    lead : int
        Fine points before the first one the first sample needs (a start at rest, for the
        AC coupling's memory).
    n_samples : int
        Samples produced per column.
    """

    s: np.ndarray
    lead: int
    n_samples: int


def fine_grid(acq: Acquisition, t_first: np.ndarray, n_samples: int, *,
              start: float | None = None) -> FineGrid:
    """The input times for ``n_samples`` samples from ``t_first`` (s, (n,), one per hit).

    Sample ``k`` at ``t_k = t_first + k / f_s`` is the FIR's output over the inputs at
    ``t_k - D_pure - j dt_f``, ``j = 0 .. L - 1``; the grid runs from the first one of
    sample 0 to the last of sample ``n - 1`` in steps ``dt_f``, extended back to ``start``
    (s; the time before which the input is 0: the AC coupling starts at rest there).

    Parameters
    ----------
    acq : Acquisition
        The model.
    t_first : numpy.ndarray
        (n,) s, each column's first sample time.
    n_samples : int
        Samples per column.
    start : float or None
        s, where the input starts (None: at the grid's own first point).

    Returns
    -------
    FineGrid
        The times and the lead.
    """
    t_first = np.atleast_1d(np.asarray(t_first, float))
    L, over = acq.taps.size, acq.oversample
    first = t_first - acq.pure_delay - (L - 1) * acq.fine_dt
    lead = 0 if start is None else max(int(np.ceil((np.max(first) - start) / acq.fine_dt)), 0)
    m = np.arange(-lead, (n_samples - 1) * over + L)
    return FineGrid(first[None, :] + m[:, None] * acq.fine_dt, lead, int(n_samples))


def filter_fine(acq: Acquisition, grid: FineGrid, x: np.ndarray, *, fine: bool = False
                ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """The front end ``A`` (AC coupling, anti-alias FIR, decimation) applied to inputs on a
    fine grid.

    Parameters
    ----------
    acq : Acquisition
        The model.
    grid : FineGrid
        The grid of :func:`fine_grid`.
    x : numpy.ndarray
        (M, n, ...) inputs at ``grid.s`` (any trailing axes: the force, its derivatives),
        at rest before the grid's first point.
    fine : bool
        Also return the FIR's output on the fine grid (the band-limited signal between
        samples).

    Returns
    -------
    numpy.ndarray or tuple
        (n_samples, n, ...) the samples; with ``fine`` also the fine output (M', n, ...)
        whose row ``j`` is the output at ``grid.s[grid.lead + j + L - 1] + D_pure`` (the
        sample ``k`` is row ``k O``).
    """
    from scipy import signal

    x = np.asarray(x, float)
    if acq.coupling == "AC":
        b, a = signal.butter(1, acq.ac_corner, btype="highpass", fs=1.0 / acq.fine_dt)
        x = signal.lfilter(b, a, x, axis=0)
    taps = acq.taps
    x = x[grid.lead:]
    shape = (taps.size,) + (1,) * (x.ndim - 1)
    y = signal.fftconvolve(x, taps.reshape(shape), mode="valid", axes=0)
    samples = y[:: acq.oversample][: grid.n_samples]
    return (samples, y) if fine else samples


#: ``force(s) -> x``: the input (N, any trailing axes) at fine times ``s`` (M, n).
Force = Callable[[np.ndarray], np.ndarray]


def acquire(acq: Acquisition, force: Force, t_first: np.ndarray, n_samples: int, *,
            gain: float = 1.0, start: float | None = None, fine: bool = False
            ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Noise-free samples of the linear measurement model (module docstring, steps 1-3):
    ``g [A x](t_first + k / f_s)``.

    Parameters
    ----------
    acq : Acquisition
        The model.
    force : callable
        ``force(s)`` the input at fine times ``s`` (M, n) s: (M, n, ...) N (the force
        minus its static value, or a stack of it with its derivatives).
    t_first : numpy.ndarray
        (n,) s, the first sample's time per column (hit).
    n_samples : int
        Samples per column.
    gain : float
        The DAQ gain ``g``.
    start : float or None
        s, the time before which the input is 0 (the AC coupling at rest there).
    fine : bool
        Also return the fine output (:func:`filter_fine`).

    Returns
    -------
    numpy.ndarray or tuple
        (n_samples, n, ...) N; with ``fine`` also the fine output.
    """
    grid = fine_grid(acq, t_first, n_samples, start=start)
    out = filter_fine(acq, grid, force(grid.s), fine=fine)
    if fine:
        return gain * out[0], gain * out[1]
    return gain * out


def tabulated(t: np.ndarray, f: np.ndarray) -> Force:
    """A force given on samples ``(t, f)`` (s, N; increasing ``t``) as a function of time:
    linear between the samples, 0 before the first, the last value after it.

    Parameters
    ----------
    t : numpy.ndarray
        The sample times, s, increasing.
    f : numpy.ndarray
        The forces at ``t``, N.

    Returns
    -------
    callable
        ``force(s)``: the force, N, at the times ``s`` (s), any shape.
    """
    t = np.asarray(t, float)
    f = np.asarray(f, float)

    def force(s: np.ndarray) -> np.ndarray:
        return np.interp(s, t, f, left=0.0, right=f[-1])

    return force


def digitize(acq: Acquisition, y: np.ndarray, rng: np.random.Generator | None = None,
             noise: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """What the converter delivers of a noise-free record ``y`` (N): white noise, 24-bit
    quantization at the sensitivity, clipping at the +-5 V rails (module docstring, steps
    4-5).

    Parameters
    ----------
    acq : Acquisition
        The model.
    y : numpy.ndarray
        N, any shape.
    rng : numpy.random.Generator or None
        Draws the noise (None: no noise).
    noise : float or None
        N rms (default :attr:`Acquisition.noise`).

    Returns
    -------
    tuple of numpy.ndarray
        The record (N, the shape of ``y``) and a bool mask of the samples at a rail.
    """
    sigma = acq.noise if noise is None else float(noise)
    y = np.asarray(y, float)
    if rng is not None and sigma > 0:
        y = y + rng.normal(0.0, sigma, y.shape)
    lsb = lsb_volts()
    code_max = 2 ** (NI9234_BITS - 1)
    code = np.clip(np.round(y * acq.sensitivity / lsb), -code_max, code_max - 1)
    return code * lsb / acq.sensitivity, np.abs(code) >= code_max - 1


def trigger_time(t_fine: np.ndarray, y_fine: np.ndarray, level: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Where each column's fine output first rises through ``level`` (N), by linear
    interpolation on the fine grid, and the row it rises at.

    Parameters
    ----------
    t_fine : numpy.ndarray
        (M, n) s, the fine output's times.
    y_fine : numpy.ndarray
        (M, n) N, the fine output.
    level : float
        N, the trigger level (rising).

    Returns
    -------
    tuple of numpy.ndarray
        ``t_c`` (n,) s (NaN where it never rises through it) and the row ``j`` (n,) with
        ``y[j - 1] < level <= y[j]``.
    """
    up = (y_fine[:-1] < level) & (y_fine[1:] >= level)
    found = up.any(axis=0)
    j = np.argmax(up, axis=0) + 1
    cols = np.arange(y_fine.shape[1])
    y0, y1 = y_fine[j - 1, cols], y_fine[j, cols]
    t0, t1 = t_fine[j - 1, cols], t_fine[j, cols]
    frac = (level - y0) / np.where(y1 > y0, y1 - y0, 1.0)
    return np.where(found, t0 + frac * (t1 - t0), np.nan), j
