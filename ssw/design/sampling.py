"""The TOF a DAQ reads from a device's sensor: the sampled peaks' error and the noise's.

The chain's TOF is located on its dense output (:mod:`ssw.chain.dense`). A measurement reads
the sensor through the DAQ instead: the module's anti-alias filter, samples at ``f_s`` with
an arbitrary sample-clock phase, white noise; each peak is then refined by band-limited
upsampling and the vertex of a parabola (:func:`ssw.signal.peaks.refine_peak`, what
``ssw measure`` does to a record). A pulse resolved by few samples costs resolution twice:

* **sampled peaks** (:func:`sampled_tof`): the device's own sensor signal, through the
  modelled NI 9234 filter (:func:`ssw.daq.simulated.antialias_fir`: passband 0.45 f_s,
  zero-phase here, its delay being common to both peaks), is sampled at ``phases``
  sample-clock phases (every ``OVERSAMPLE / phases``-th point of the filter's fine grid), and
  both peaks of each record are refined as ``ssw measure`` refines them. Against the dense
  TOF, the error's mean over the phases is a bias no averaging over hits removes (the
  filter reshapes a narrow incident pulse and a broad reflected one differently), its
  standard deviation over the phases a scatter from hit to hit (each hit falls at its own
  phase);
* **noise**: white noise of standard deviation ``sigma`` on the samples moves each refined
  peak linearly for a small noise, ``dt* = sum_k g_k n_k / f_s`` with ``g_k`` the peak
  picker's derivative with respect to sample ``k`` (in samples per unit of the signal,
  the exact derivative of :func:`ssw.signal.peaks.refine_peaks`, linear up to its parabola:
  :func:`picker_gain`, at the first clock phase), so::

      sigma_t = sigma ||g||_2 / f_s

  per peak; a hit's TOF has the two peaks' variances summed. For the ideal band-limited
  interpolant ``||g|| f_s`` would be ``pi f_s / (sqrt(3) |y''(t*)|)`` (the derivative of
  white samples' interpolant has the variance ``sigma^2 (pi f_s)^2 / 3``); the picker's
  Kaiser-windowed upsampling attenuates the band's top, where that variance lies, and its
  window is finite, so the picker's own derivative is used. The AC coupling (-3 dB at
  0.5 Hz) is left out: over the few ms of a hit it tilts the record by less than 1e-3 of a
  pulse.

References
----------
Smith, J. O. and Serra, X. (1987). PARSHL, appendix: quadratic interpolation of peaks.
Oppenheim, A. V. and Schafer, R. W. (2010). *Discrete-Time Signal Processing*, 3rd ed.,
sec. 4.2-4.6 (band-limited interpolation of sampled signals, the filtered white noise's
variance from its spectrum).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Samples each side of a peak kept for its refinement, beyond the refiner's own window.
EDGE = 2
#: The picker's interpolation matrices, by (window size, upsampling factor).
_MATRICES: dict[tuple[int, int], np.ndarray] = {}


@dataclass(frozen=True)
class SampledTof:
    """A device's TOF as a DAQ reads it, per scene. SI units; arrays (n,), NaN where the
    scene has no two peaks.

    Parameters
    ----------
    bias : numpy.ndarray
        s, the mean over the sample-clock phases of the sampled TOF minus the dense TOF.
    spread : numpy.ndarray
        s, its standard deviation over the phases (random from hit to hit).
    noise : numpy.ndarray
        s, one hit's TOF standard deviation from the DAQ's white noise.
    samples_per_pulse : numpy.ndarray
        The narrower pulse's width at half height, in samples.
    """

    bias: np.ndarray
    spread: np.ndarray
    noise: np.ndarray
    samples_per_pulse: np.ndarray


def _record(run: object, times: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """The run's sensor above its baseline at ``times`` (rows (k, m), s) of the scenes
    ``cols`` (k,): linear between the integrator's steps, 0 before the hit, the last value
    held after a scene's stop."""
    S = run.sensor  # (n_t, n)
    base = S[0]
    n_t = S.shape[0]
    valid = ~np.isnan(S)
    last = np.where(valid.any(axis=0), n_t - 1 - np.argmax(valid[::-1], axis=0), 0)
    pos = (times - run.t[0]) / run.dt
    i = np.floor(pos).astype(np.int64)
    f = pos - i
    lim = last[cols][:, None]
    i0 = np.clip(i, 0, lim)
    i1 = np.clip(i + 1, 0, lim)
    c = cols[:, None]
    x = (S[i0, c] * (1.0 - f) + S[i1, c] * f) - base[c]
    return np.where(pos < 0, 0.0, np.where(i >= lim, S[lim, c] - base[c], x))


def _filtered(run: object, t_peak: np.ndarray, cols: np.ndarray, rate: float,
              taps: np.ndarray, oversample: int, half_samples: int
              ) -> tuple[np.ndarray, np.ndarray]:
    """The filtered sensor on the fine grid (step ``1 / (oversample rate)``) around each
    peak: values (k, 2 W + 1) and the absolute fine index of each row's first point, with
    ``W = half_samples oversample``."""
    from scipy.signal import fftconvolve

    h = 1.0 / (oversample * rate)
    half = (taps.size - 1) // 2
    W = half_samples * oversample
    c = np.rint(t_peak / h).astype(np.int64)
    offsets = np.arange(-W - half, W + half + 1)
    x = _record(run, (c[:, None] + offsets[None]) * h, cols)
    y = fftconvolve(x, taps[None, :], mode="valid", axes=1)
    return y, c - W


def _interpolation_matrix(size: int, upsample: int) -> np.ndarray:
    """(size, upsample size) the linear map of the peak picker's band-limited upsampling of
    a window of ``size`` samples (:func:`ssw.signal.peaks.refine_peaks`: ``resample_poly``
    with its Kaiser window and ``padtype='line'``, linear in the samples): row ``k`` is the
    fine signal of a unit sample at ``k``. Kept per size (the windows have few sizes)."""
    from scipy import signal

    from ssw.signal.peaks import KAISER_BETA

    key = (size, upsample)
    if key not in _MATRICES:
        _MATRICES[key] = signal.resample_poly(np.eye(size), upsample, 1, axis=1,
                                              window=("kaiser", KAISER_BETA), padtype="line")
    return _MATRICES[key]


def picker_gain(s: np.ndarray, c: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """``||d pos / d s_k||_2`` (samples per unit of the signal) of the peak picker
    (:func:`ssw.signal.peaks.refine_peaks`) at each row of the samples ``s`` (m, n_s), its
    peak next to ``c`` at ``pos``.

    The picker is linear up to its parabola: the window ``w`` of samples
    ``c - HALF_WINDOW .. c + HALF_WINDOW`` is upsampled ``U`` times, ``f = w A``
    (``_interpolation_matrix``), and the vertex of the parabola through the fine values
    ``f_{j-1}, f_j, f_{j+1}`` at its largest one ``j`` gives ``pos = lo + (j + p) / U`` with
    ``p = (f_{j-1} - f_{j+1}) / (2 D)``, ``D = f_{j-1} - 2 f_j + f_{j+1} < 0``. So, exactly
    (the limit of a central difference of the picker; ``j`` recovered from ``pos``, as
    ``|p| <= 1/2``)::

        d pos / d w_k = (1 / U) sum_i (d p / d f_{j+i}) A[k, j + i],   i = -1, 0, 1,
        d p / d f_{j-1} = (D - N) / (2 D^2),  d p / d f_j = N / D^2,
        d p / d f_{j+1} = -(D + N) / (2 D^2),  N = f_{j-1} - f_{j+1};

    0 where the parabola is clipped (``|p| = 1/2``) or not concave, as the picker's ``p``
    is constant there.

    Parameters
    ----------
    s : numpy.ndarray
        (m, n_s) the sampled signals, one per row (the sensor's force, N).
    c : numpy.ndarray
        (m,) int, the index of each row's peak sample.
    pos : numpy.ndarray
        (m,) the picker's peak position of each row, in samples.

    Returns
    -------
    numpy.ndarray
        (m,) the gain, samples per unit of the signal (per N).

    References
    ----------
    Smith, J. O. and Serra, X. (1987). PARSHL, appendix: quadratic interpolation of peaks
    (the vertex ``p``).
    """
    from ssw.signal.peaks import HALF_WINDOW, UPSAMPLE

    s = np.asarray(s, float)
    c = np.asarray(c, np.int64)
    m, n_s = s.shape
    lo = np.maximum(c - HALF_WINDOW, 0)
    hi = np.minimum(c + HALF_WINDOW + 1, n_s)
    gain = np.zeros(m)
    for size in np.unique(hi - lo):  # the windows of one size: one matrix
        rows = np.flatnonzero(hi - lo == size)
        A = _interpolation_matrix(int(size), UPSAMPLE)
        win = s[rows[:, None], lo[rows, None] + np.arange(size)[None, :]]
        j = np.rint((pos[rows] - lo[rows]) * UPSAMPLE).astype(np.int64)
        j = np.clip(j, 1, A.shape[1] - 2)
        cols = A[:, j[:, None] + np.arange(-1, 2)[None, :]]  # (size, r, 3)
        fm, f0, fp = np.einsum("rk,krt->tr", win, cols)
        D, N = fm - 2.0 * f0 + fp, fm - fp
        live = (D < 0) & (np.abs(N) < -D)  # concave and |p| < 1/2
        D2 = np.where(live, 2.0 * D * D, 1.0)
        dp = np.where(live, np.stack([(D - N) / D2, 2.0 * N / D2, -(D + N) / D2]), 0.0)
        grad = np.einsum("krt,tr->rk", cols, dp) / UPSAMPLE
        gain[rows] = np.sqrt(np.sum(grad**2, axis=1))
    return gain


def sampled_tof(run: object, peaks: object, rate: float, noise_rms: float,
                phases: int = 4) -> SampledTof:
    """The sampled peaks' TOF error and the noise's (module docstring) for every scene of
    a run.

    Parameters
    ----------
    run : ssw.chain.integrate.Run
        The record (its sensor signal at the integrator's steps).
    peaks : ssw.chain.tof.Peaks
        Its dense peaks (flat, one per scene).
    rate : float
        S/s, the DAQ's sample rate.
    noise_rms : float
        N, the DAQ's white noise per sample.
    phases : int
        Sample-clock phases, a divisor of ``ssw.daq.simulated.OVERSAMPLE``.

    Returns
    -------
    SampledTof
        Per scene: bias, spread, noise (s) and the samples per pulse.
    """
    from ssw.daq.simulated import OVERSAMPLE, antialias_fir
    from ssw.errors import ConfigError
    from ssw.signal.peaks import HALF_WINDOW, UPSAMPLE, refine_peaks

    if OVERSAMPLE % phases:
        raise ConfigError("phases", phases, f"a divisor of {OVERSAMPLE}")
    t_inc = np.asarray(peaks.t_incident, float)
    t_ref = np.asarray(peaks.t_reflected, float)
    n = t_inc.size
    ok = np.isfinite(t_inc) & np.isfinite(t_ref)
    nan = np.full(n, np.nan)
    if not ok.any():
        return SampledTof(nan, nan.copy(), nan.copy(), nan.copy())
    cols = np.flatnonzero(ok)
    taps = antialias_fir(OVERSAMPLE)
    h = 1.0 / (OVERSAMPLE * rate)
    half_samples = HALF_WINDOW + EDGE
    times = np.empty((2, cols.size, phases))
    gain = np.empty((2, cols.size))
    width = np.empty((2, cols.size))
    rows, peaks_at, offsets = [], [], []  # every peak's samples at every phase: one pick
    for j, tp in enumerate((t_inc[cols], t_ref[cols])):
        y, start = _filtered(run, tp, cols, rate, taps, OVERSAMPLE, half_samples)
        mid = half_samples * OVERSAMPLE
        # the fine maximum next to the dense peak: the pulse's width
        lo, hi = mid - OVERSAMPLE, mid + OVERSAMPLE
        k = lo + np.argmax(y[:, lo:hi + 1], axis=1)
        r = np.arange(cols.size)
        above = y >= 0.5 * y[r, k][:, None]
        idx = np.arange(y.shape[1])[None]
        left = np.where(~above & (idx < k[:, None]), idx, -1).max(axis=1)
        right = np.where(~above & (idx > k[:, None]), idx, y.shape[1]).min(axis=1)
        width[j] = (right - left) * h
        n_s = (y.shape[1] - OVERSAMPLE) // OVERSAMPLE + 1  # samples every row holds
        for p in range(phases):
            # the samples of the clock phase p: the fine points at o + m OVERSAMPLE
            j0 = np.mod(p * (OVERSAMPLE // phases) - start, OVERSAMPLE)
            s = y[r[:, None], j0[:, None] + OVERSAMPLE * np.arange(n_s)[None, :]]
            c = np.rint((k - j0) / OVERSAMPLE).astype(np.int64)
            near = s[r[:, None], c[:, None] + np.arange(-1, 2)[None, :]]
            rows.append(s)
            peaks_at.append(np.clip(c - 1 + np.argmax(near, axis=1), 1, n_s - 2))
            offsets.append(start + j0)
    # (the picker's rows are independent: one call gives each row's own numbers)
    pos, _ = refine_peaks(np.concatenate(rows), np.concatenate(peaks_at), UPSAMPLE)
    pos = pos.reshape(2, phases, cols.size)
    for j in range(2):
        times[j] = ((np.stack(offsets[j * phases:(j + 1) * phases]) + pos[j] * OVERSAMPLE)
                    * h).T
        gain[j] = picker_gain(rows[j * phases], peaks_at[j * phases], pos[j, 0])
    err = (times[1] - times[0]) - (t_ref[cols] - t_inc[cols])[:, None]
    bias, spread, noise, samples = nan.copy(), nan.copy(), nan.copy(), nan.copy()
    bias[cols] = err.mean(axis=1)
    spread[cols] = err.std(axis=1)
    sigma = noise_rms * gain / rate
    noise[cols] = np.hypot(sigma[0], sigma[1])
    samples[cols] = np.min(width, axis=0) * rate
    return SampledTof(bias, spread, noise, samples)
