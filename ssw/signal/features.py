"""Features of a hit's signal beyond its TOF, with their derivatives.

A hit's record holds three pulses the chain model describes well: the incident solitary
wave, the primary wave reflected from the wall and the secondary reflected wave (Yang et
al. 2011: both reflected waves' amplitudes and speeds depend on the wall), then a rattle of
the chain that is chaotic (its forward sensitivities grow without bound) and is not used.
From a uniformly sampled signal ``y`` (N, baseline 0) and optionally its derivatives ``dy``
with respect to ``k`` parameters, :func:`pulse_features` gives (:data:`NAMES`):

* ``tof`` (s): reflected minus incident peak time (the peak rule of
  :mod:`ssw.signal.rule`: the primary reflected wave);
* ``amplitude_ratio``: reflected over incident peak height (Deng et al. 2016);
* ``secondary_tof`` (s): the secondary reflected peak's time minus the incident one's; the
  secondary peak is the rule's reflected peak searched again after the primary reflected
  pulse ended (below ``gap_fraction`` of its height), up to one more TOF;
* ``secondary_ratio``: its height over the incident peak's;
* ``width_incident``, ``width_reflected`` (s): full widths at half maximum, between the
  half-height crossings (linear between samples) either side of each peak;
* ``amplitude`` (N): the incident peak's height (the only feature that sees the DAQ
  gain and the striker speed's scale).

Peaks are the vertex of the parabola through the largest sample and its neighbours
(:func:`ssw.signal.peaks.parabolic_vertex`) on a signal band-limited and upsampled
``ssw.signal.peaks.UPSAMPLE`` times (:func:`upsample`, the record's own interpolation
for measured records and, applied to the model's samples, for the model: both go through
the same steps, so a feature compares like with like). Every feature is a smooth function
of the samples between changes of the chosen sample (the vertex's error on the fine grid,
``(dt/16)^3``, keeps those jumps at ~1 ns), so its derivative with respect to the model's
parameters is the chain rule through the vertex and the crossings: ``dt*/dp = dt (dp_v /
dy) . dy/dp`` with ``p_v`` the vertex's offset (exact for this extractor).

Noise. With white noise of rms ``sigma`` on the samples (rate ``f_s``, band-limited by the
module to ``f_s / 2``), the features' standard deviations to first order
(:func:`feature_sigma`): a peak height ``sigma``; a peak time ``sigma_d / |y''|`` with
``sigma_d = 2 pi (f_s / 2) sigma / sqrt 3`` the rms of the noise's time derivative; a
crossing time ``sigma / |y'|``; differences and ratios combine them as independent.

References
----------
Yang, J., Silvestro, C., Khatri, D., De Nardo, L. and Daraio, C. (2011). Interaction of
highly nonlinear solitary waves with linear elastic media. Phys. Rev. E 83, 046606.
Deng, W., Nasrollahi, A., Rizzo, P. and Li, K. (2016). On the reliability of a solitary
wave based transducer to determine the characteristics of some materials. Sensors 16(1), 5.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.signal.peaks import KAISER_BETA, UPSAMPLE, parabolic_vertex
from ssw.signal.rule import RULE, PeakRule, assemble, gap_end, local_maxima, prominent, reflected

#: The features, in order (module docstring).
NAMES = ("tof", "amplitude_ratio", "secondary_tof", "secondary_ratio", "width_incident",
         "width_reflected", "amplitude")
#: Their units.
UNITS = {"tof": "s", "amplitude_ratio": "1", "secondary_tof": "s", "secondary_ratio": "1",
         "width_incident": "s", "width_reflected": "s", "amplitude": "N"}
#: The features a shift of the reflected waves (a per-hit delay) moves, by that shift.
DELAYED = ("tof", "secondary_tof")


def upsample(y: np.ndarray, factor: int = UPSAMPLE) -> np.ndarray:
    """Band-limited interpolation of samples along axis 0 (``scipy.signal.resample_poly``,
    Kaiser window, the interpolator of :func:`ssw.signal.peaks.refine_peak`): linear, so it
    applies to a signal's derivatives alike.

    Parameters
    ----------
    y : numpy.ndarray
        (n, ...) samples.
    factor : int
        Upsampling factor.

    Returns
    -------
    numpy.ndarray
        (n factor, ...): row ``j`` at ``j / factor`` samples.
    """
    from scipy import signal

    return signal.resample_poly(np.asarray(y, float), factor, 1, axis=0,
                                window=("kaiser", KAISER_BETA), padtype="line")


@dataclass(frozen=True)
class Features:
    """The features of one signal (module docstring). SI units.

    Parameters
    ----------
    values : numpy.ndarray
        (7,) in :data:`NAMES` order; NaN where a pulse is missing.
    jacobian : numpy.ndarray or None
        (7, k) derivatives with respect to the signal's parameters.
    sigma : numpy.ndarray
        (7,) standard deviations from the noise (:func:`feature_sigma`).
    times : dict
        ``incident``, ``reflected``, ``secondary``: the peaks' times, s.
    """

    values: np.ndarray
    jacobian: np.ndarray | None
    sigma: np.ndarray
    times: dict[str, float]

    def as_dict(self) -> dict[str, float]:
        """Name -> value.

        Returns
        -------
        dict of str to float
            Feature name -> value, in ``NAMES``' order.
        """
        return {n: float(v) for n, v in zip(NAMES, self.values, strict=True)}


def _vertex(y: np.ndarray, dy: np.ndarray | None, k: int, h: float
            ) -> tuple[float, float, np.ndarray | None, np.ndarray | None, float]:
    """Offset-time, height and their derivatives of the parabolic vertex at sample ``k``,
    and the curvature ``y''`` there (N/s^2)."""
    pos, top = parabolic_vertex(y, k)
    ym, y0, yp = y[k - 1], y[k], y[k + 1]
    den = ym - 2 * y0 + yp
    p = float(pos) - k
    if dy is None or not den < 0 or abs(p) >= 0.5:
        return float(pos) * h, float(top), None, None, den / h**2
    dm, d0, dp_ = dy[k - 1], dy[k], dy[k + 1]
    dnum = dm - dp_
    dden = dm - 2 * d0 + dp_
    dpv = 0.5 * (dnum * den - (ym - yp) * dden) / den**2
    dtop = d0 - 0.25 * dnum * p - 0.25 * (ym - yp) * dpv
    return float(pos) * h, float(top), h * dpv, dtop, den / h**2


def _crossing(y: np.ndarray, dy: np.ndarray | None, k: int, level: float,
              dlevel: np.ndarray | None, h: float, step: int
              ) -> tuple[float, np.ndarray | None, float]:
    """The first crossing of ``level`` from sample ``k`` walking by ``step`` (-1: left,
    +1: right): its time (in samples times ``h``), derivative and slope ``y'`` (N/s)."""
    j = k
    n = y.size
    while 0 < j < n - 1 and y[j] >= level:
        j += step
    a, b = (j, j + 1) if step < 0 else (j - 1, j)
    ya, yb = y[a], y[b]
    if not (ya - level) * (yb - level) <= 0 or ya == yb:
        return np.nan, None, np.nan
    frac = (level - ya) / (yb - ya)
    t = (a + frac) * h
    slope = (yb - ya) / h
    if dy is None:
        return t, None, slope
    dl = 0.0 if dlevel is None else dlevel
    dfrac = ((dl - dy[a]) * (yb - ya) - (level - ya) * (dy[b] - dy[a])) / (yb - ya) ** 2
    return t, h * dfrac, slope


def pulse_features(y: np.ndarray, h: float, *, dy: np.ndarray | None = None,
                   noise: float = 0.0, rate: float | None = None, rule: PeakRule = RULE,
                   prominence: bool = True, min_tof: float | None = None) -> Features:
    """The features of one signal (module docstring).

    The incident and reflected peaks are :func:`ssw.signal.rule.assemble`'s, with the
    record's noise floor and prominence test: the samples :func:`ssw.signal.peaks.pick_peaks`
    chooses on the same record (``ssw measure``), on this finer grid.

    Parameters
    ----------
    y : numpy.ndarray
        (m,) N, the signal, baseline 0, on a uniform grid of step ``h`` (an upsampled
        record, :func:`upsample`); times are from its first point.
    h : float
        s, the grid's step.
    dy : numpy.ndarray or None
        (m, k) its derivatives with respect to ``k`` parameters.
    noise : float
        N rms of the record's noise (the rule's floor ``noise_k * noise``, and
        :func:`feature_sigma`).
    rate : float or None
        S/s, the record's sample rate (the noise's bandwidth); default ``1 / h``.
    rule : PeakRule
        The peak rule.
    prominence : bool
        The reflected peaks' prominence must exceed the floor (the record's test of
        :func:`ssw.signal.peaks.pick_peaks`); False: the noiseless rule.
    min_tof : float or None
        s, the shortest physical round trip (:func:`ssw.signal.tof.shortest_round_trip`):
        the reflected window opens no earlier; a window that opens on a pulse's falling
        flank gives no reflected peak. ``None``: no bound.

    Returns
    -------
    Features
        Values, derivatives and noise of every feature; NaN for a pulse not found.
    """
    y = np.asarray(y, float)
    k_par = 0 if dy is None else dy.shape[1]
    nan = np.full(len(NAMES), np.nan)
    jac = None if dy is None else np.full((len(NAMES), k_par), np.nan)
    col = y[:, None]
    floor = rule.noise_k * noise
    times = {"incident": np.nan, "reflected": np.nan, "secondary": np.nan}

    def later(k_inc: np.ndarray) -> np.ndarray:
        pos, _ = parabolic_vertex(y, int(k_inc[0]))
        return np.array([int(np.ceil(float(pos) + min_tof / h))])

    sel = assemble(col, rule, floor=floor, prominence=prominence,
                   min_start=None if min_tof is None else later)
    if not (sel.ok[0] and not sel.straddle[0]):
        return Features(nan, jac, nan.copy(), times)
    k_inc, k_ref = sel.k_incident, sel.k_reflected
    ki, kr = int(k_inc[0]), int(k_ref[0])
    ti, fi, dti, dfi, ci = _vertex(y, dy, ki, h)
    tr, fr, dtr, dfr, cr = _vertex(y, dy, kr, h)
    times.update(incident=ti, reflected=tr)
    vals = nan.copy()
    vals[0], vals[1], vals[6] = tr - ti, fr / fi, fi
    # the secondary reflected wave: the rule's reflected peak after the primary's end,
    # within one more TOF
    k_gap2, ended2 = gap_end(col, k_ref, rule)
    end = min(y.size, kr + (kr - ki))
    ts = fs_ = cs = np.nan
    dts = dfs = None
    if ended2[0] and k_gap2[0] < end - 2:
        part = col[:end]
        maxima = local_maxima(col)[:end]
        allowed = prominent(part, maxima, floor) if prominence else None
        k_sec, has_sec, _ = reflected(part, k_gap2, rule, floor=floor, allowed=allowed,
                                      maxima=maxima)
        if has_sec[0]:
            ts, fs_, dts, dfs, cs = _vertex(y, dy, int(k_sec[0]), h)
            times["secondary"] = ts
            vals[2], vals[3] = ts - ti, fs_ / fi
    # full widths at half maximum
    widths = []
    for k, top, dtop in ((ki, fi, dfi), (kr, fr, dfr)):
        dl = None if dtop is None else 0.5 * dtop
        t1, d1, s1 = _crossing(y, dy, k, 0.5 * top, dl, h, -1)
        t2, d2, s2 = _crossing(y, dy, k, 0.5 * top, dl, h, +1)
        widths.append((t2 - t1, d1, d2, s1, s2))
    vals[4], vals[5] = widths[0][0], widths[1][0]
    if dy is not None and dti is not None and dtr is not None:
        jac[0] = dtr - dti
        jac[1] = dfr / fi - fr * dfi / fi**2
        jac[6] = dfi
        if dts is not None:
            jac[2] = dts - dti
            jac[3] = dfs / fi - fs_ * dfi / fi**2
        for j, (_, d1, d2, _, _) in zip((4, 5), widths, strict=True):
            if d1 is not None and d2 is not None:
                jac[j] = d2 - d1
    sigma = feature_sigma(vals, noise, rate or 1.0 / h, (ci, cr, cs),
                          [(w[3], w[4]) for w in widths])
    return Features(vals, jac, sigma, times)


def feature_sigma(values: np.ndarray, noise: float, rate: float,
                  curvatures: tuple[float, float, float],
                  slopes: list[tuple[float, float]]) -> np.ndarray:
    """First-order standard deviations of the features under white noise (module
    docstring).

    Parameters
    ----------
    values : numpy.ndarray
        (7,) the features.
    noise : float
        N rms on the samples.
    rate : float
        S/s, the samples' rate (the noise is band-limited to half of it).
    curvatures : tuple of float
        ``y''`` (N/s^2) at the incident, reflected and secondary peaks.
    slopes : list of tuple
        ``y'`` (N/s) at the half-height crossings (left, right) of the incident and the
        reflected pulse.

    Returns
    -------
    numpy.ndarray
        (7,) in :data:`NAMES` order (NaN where the feature is).
    """
    sd = 2 * np.pi * (rate / 2) * noise / np.sqrt(3.0)
    st = [sd / abs(c) if c else np.inf for c in curvatures]
    fi, fr_ratio, fs_ratio = values[6], values[1], values[3]
    out = np.empty(len(NAMES))
    out[0] = np.hypot(st[0], st[1])
    out[1] = abs(fr_ratio) * np.hypot(noise / (fr_ratio * fi), noise / fi)
    out[2] = np.hypot(st[0], st[2])
    out[3] = abs(fs_ratio) * np.hypot(noise / (fs_ratio * fi), noise / fi)
    for j, (a, b) in zip((4, 5), slopes, strict=True):
        out[j] = np.hypot(noise / abs(a), noise / abs(b))
    out[6] = noise
    return np.where(np.isfinite(values), out, np.nan)
