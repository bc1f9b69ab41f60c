"""Incident and reflected peaks of a sensor record, refined on a band-limited upsampled grid.

Rule: :mod:`ssw.signal.rule` (stated once for measured records and simulated signals, so
that a simulated recording and the model pick the same pulses), with its noise thresholds
and the physical bound for measured records, assembled by :func:`ssw.signal.rule.assemble`
(the assembly :func:`ssw.signal.features.pulse_features` calls too).
With ``s`` the conditioned record:

1. **incident** peak: the first local maximum with ``s >= incident_fraction x max(s)``
   and above ``noise_k`` noise sigmas;
2. **end of the incident pulse**: the first later sample with ``s < gap_fraction x s_inc``;
3. **earliest possible reflection**: the reflected wave cannot reach the sensor before
   ``t_inc + min_tof``, the shortest physical round trip sensor -> wall -> sensor
   (:func:`ssw.signal.tof.shortest_round_trip`); the search window starts at the later of
   (2) and that time. A pulse that straddles the bound (the window opens on the falling
   flank of a significant pulse) or a refined TOF below it is a :class:`PeakError` naming
   both numbers, never a TOF: the geometry and the record disagree;
4. **reflected** peak: in the window, the first local maximum with
   ``s >= split_fraction x max(s over the window)``, above ``noise_k`` noise sigmas and
   with a prominence of at least ``noise_k`` sigmas (the primary reflected wave; soft
   media split the reflection into several pulses, Yang et al. 2011);
5. both are refined on the record upsampled ``upsample`` times by band-limited
   interpolation (``scipy.signal.resample_poly``, a Kaiser-windowed sinc: exact for a
   record band-limited below its Nyquist frequency, which the NI 9234's anti-alias filter
   guarantees up to 0.45 f_s), then by the vertex of the parabola through the upsampled
   maximum and its two neighbours (Smith & Serra 1987, quadratic interpolation of
   peaks): ``p = (y[k-1] - y[k+1]) / (2 (y[k-1] - 2 y[k] + y[k+1]))``, ``|p| <= 1/2``.

Why upsample. A solitary-wave pulse at 51.2 kS/s is ~3.5 samples wide at half height; the
parabola through three such samples is not the pulse's shape, and its vertex error, of
either sign per sample phase for a symmetric pulse, becomes one-sided for the asymmetric
pulses of the chain (the reflected one off a soft wall is broader on one side): the
parabola alone biased TOFs by -2 to -5 us (``ssw bench tof --upsample 1``). On a grid 16
times finer the parabola's error scales as ``(dt / 16)^3``.

A record without a reflected peak (a single peak), or whose peaks touch its ends, gives
:class:`PeakError` naming the reason.

References
----------
Smith, J. O. and Serra, X. (1987). PARSHL: an analysis/synthesis program for non-harmonic
sounds based on a sinusoidal representation. Proc. ICMC, appendix: quadratic peak
interpolation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.errors import ConfigError, RecordingError
from ssw.signal.rule import PeakRule, Selection, assemble, local_maxima, prominent

__all__ = ["PeakError", "PeakPair", "PeakRule", "check_tof", "parabolic_vertex", "pick_peaks",
           "refine_peak", "refine_peaks"]

#: Default upsampling factor before the parabolic vertex.
UPSAMPLE = 16
#: Samples each side of a peak fed to the band-limited interpolator (the resample_poly
#: filter reaches 10 input samples each side; the rest keeps its edge transient away).
HALF_WINDOW = 24
#: Kaiser window of the interpolation filter (resample_poly's default design).
KAISER_BETA = 5.0


class PeakError(RecordingError):
    """A record's peaks cannot be picked (the message gives the reason)."""


def parabolic_vertex(y: np.ndarray, k: int | np.ndarray, cols: np.ndarray | None = None,
                     *, near: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Sub-sample offset ``p`` and height of the parabola through ``y[k-1], y[k], y[k+1]``.

    Parameters
    ----------
    y : numpy.ndarray
        (n_t,) samples, or (n_t, n) with ``cols``; with ``near``, (3, m): only the samples
        ``k - 1``, ``k``, ``k + 1`` of each ``k``.
    k : int or numpy.ndarray
        Sample indices, each ``1 <= k <= n_t - 2``.
    cols : numpy.ndarray or None
        Column of each ``k`` in a 2-d ``y``.
    near : bool
        ``y`` holds only the three samples of each ``k`` (``cols`` unused).

    Returns
    -------
    tuple of numpy.ndarray
        ``(k + p, y_peak)`` with ``y_peak = y[k] - (y[k-1] - y[k+1]) p / 4`` (``|p| <=
        1/2``).
    """
    k = np.asarray(k)
    if near:
        ym, y0, yp = y
    else:
        at = (lambda j: y[j]) if cols is None else (lambda j: y[j, cols])
        ym, y0, yp = at(k - 1), at(k), at(k + 1)
    den = ym - 2 * y0 + yp
    safe = np.where(den < 0, den, -1.0)
    p = np.where(den < 0, 0.5 * (ym - yp) / safe, 0.0)
    p = np.clip(p, -0.5, 0.5)
    return k + p, y0 - 0.25 * (ym - yp) * p


def refine_peak(y: np.ndarray, k: int, upsample: int = UPSAMPLE) -> tuple[float, float]:
    """Position (in samples of ``y``) and height of the peak at or next to sample ``k``.

    ``upsample = 1`` is the plain parabola through ``y[k-1..k+1]``. Otherwise the samples
    ``k - HALF_WINDOW .. k + HALF_WINDOW`` are upsampled ``upsample`` times
    (``scipy.signal.resample_poly``, ``padtype='line'``), the largest upsampled value within
    one original sample of ``k`` is taken and refined by the parabola on the fine grid
    (:func:`refine_peaks` on one record).

    Parameters
    ----------
    y : numpy.ndarray
        The record (any unit).
    k : int
        The sample at or next to the peak.
    upsample : int
        The upsampling factor, >= 1.

    Returns
    -------
    position : float
        The peak's position, samples of ``y``.
    height : float
        The peak's height, in the unit of ``y``.

    Raises
    ------
    ssw.errors.ConfigError
        When ``upsample`` < 1.
    """
    pos, h = refine_peaks(np.asarray(y)[None, :], np.array([k]), upsample)
    return float(pos[0]), float(h[0])


def refine_peaks(Y: np.ndarray, k: np.ndarray, upsample: int = UPSAMPLE
                 ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`refine_peak` of many records at once: the peak of row ``i`` of ``Y`` (m, n_t)
    at or next to sample ``k[i]``; positions (m,) in samples and heights (m,). Rows whose
    windows have one length share one interpolation call (row by row the same numbers).

    Parameters
    ----------
    Y : numpy.ndarray
        The records, (m, n_t).
    k : numpy.ndarray
        The sample at or next to each row's peak, (m,).
    upsample : int
        The upsampling factor, >= 1.

    Returns
    -------
    position : numpy.ndarray
        The peaks' positions, samples, (m,).
    height : numpy.ndarray
        The peaks' heights, in the unit of ``Y``, (m,).

    Raises
    ------
    ssw.errors.ConfigError
        When ``upsample`` < 1.
    """
    if upsample < 1:
        raise ConfigError("upsample", upsample, "an integer >= 1 (1: parabola on the samples)")
    Y = np.asarray(Y)
    k = np.asarray(k, dtype=np.int64)
    if upsample == 1:
        pos, h = parabolic_vertex(Y.T, k, np.arange(k.size))
        return np.asarray(pos, float), np.asarray(h, float)
    from scipy import signal

    lo = np.maximum(k - HALF_WINDOW, 0)
    hi = np.minimum(k + HALF_WINDOW + 1, Y.shape[1])
    pos = np.empty(k.size)
    height = np.empty(k.size)
    for size in np.unique(hi - lo):
        rows = np.flatnonzero(hi - lo == size)
        win = Y[rows[:, None], lo[rows, None] + np.arange(size)[None, :]]
        fine = signal.resample_poly(win, upsample, 1, axis=1, window=("kaiser", KAISER_BETA),
                                    padtype="line")
        c = (k[rows] - lo[rows]) * upsample
        a = np.maximum(c - upsample, 1)
        b = np.minimum(c + upsample, fine.shape[1] - 2)
        idx = np.arange(fine.shape[1])[None, :]
        masked = np.where((idx >= a[:, None]) & (idx <= b[:, None]), fine, -np.inf)
        j = np.argmax(masked, axis=1)
        p, h = parabolic_vertex(fine.T, j, np.arange(rows.size))
        pos[rows] = lo[rows] + p / upsample
        height[rows] = h
    return pos, height


@dataclass(frozen=True)
class PeakPair:
    """Incident and reflected peaks: times (s from the first sample) and heights (N).

    Parameters
    ----------
    t_incident : float
        The incident peak's time, s from the first sample.
    t_reflected : float
        The reflected peak's time, s from the first sample.
    f_incident : float
        The incident peak's height, N.
    f_reflected : float
        The reflected peak's height, N.
    """

    t_incident: float
    t_reflected: float
    f_incident: float
    f_reflected: float

    @property
    def tof(self) -> float:
        """Peak-to-peak time of flight, s."""
        return self.t_reflected - self.t_incident


def pick_peaks(
    y: np.ndarray, rate: float, noise: float, rule: PeakRule, *, min_tof: float | None = None,
    upsample: int = UPSAMPLE,
) -> PeakPair:
    """Incident and reflected peaks of the conditioned record ``y`` (N) at ``rate`` (S/s).

    Parameters
    ----------
    y : numpy.ndarray
        (n,) record, N, baseline removed.
    rate : float
        Sample rate, S/s.
    noise : float
        The record's noise sigma, N.
    rule : PeakRule
        The thresholds (:data:`ssw.signal.rule.RULE`).
    min_tof : float or None
        s, the shortest physical round trip (rule 3); ``None``: no bound.
    upsample : int
        Interpolation factor before the parabolic vertex (1: none).

    Returns
    -------
    PeakPair
        The two peaks' times (s from the first sample) and heights (N).

    Raises
    ------
    PeakError
        No peak, a single peak, a peak on the record's edge, or a reflection earlier than
        ``min_tof``.
    """
    y = np.asarray(y, dtype=np.float64)
    top = float(np.max(y))
    floor = rule.noise_k * noise
    if top <= floor:
        raise PeakError(f"no peak: maximum {top:.4g} N is within {rule.noise_k} noise sigmas "
                        f"({floor:.4g} N)")
    refined: dict[str, tuple[float, float]] = {}

    def later(k_inc: np.ndarray) -> np.ndarray:
        # rule 3's bound from the refined incident peak (kept for the pair below)
        refined["incident"] = refine_peak(y, int(k_inc[0]), upsample)
        return np.array([int(np.ceil(refined["incident"][0] + min_tof * rate))])

    sel = assemble(y[:, None], rule, floor=floor, prominence=True,
                   min_start=None if min_tof is None else later)
    if not sel.has_incident[0]:  # the maximum sits on the record's edge
        raise PeakError("no incident peak inside the record (maximum on an end sample)")
    ki = int(sel.k_incident[0])
    if not sel.has_gap[0]:
        raise PeakError(f"single peak: the incident pulse at sample {ki} never ends "
                        f"(stays above {rule.gap_fraction} of its height)")
    pi, fi = refined["incident"] if refined else refine_peak(y, ki, upsample)
    k0 = int(sel.k_gap[0])
    if k0 >= y.size - 1:
        why = (f"before the shortest physical round trip {min_tof * 1e3:.4f} ms"
               if min_tof is not None else "with the incident pulse")
        raise PeakError(f"single peak: the record ends {(y.size - 1 - pi) / rate * 1e3:.4f} ms "
                        f"after the incident peak, {why}")
    if sel.straddle[0]:
        j = _last_significant_before(y, sel, rule, floor)
        raise PeakError(
            f"a pulse peaks at TOF {(j - pi) / rate * 1e3:.4f} ms, just before the "
            f"shortest physical round trip {min_tof * 1e3:.4f} ms (the reflected-peak "
            "window opens on its falling flank): the chain numbers (beads below the "
            "sensor, bead size and material) do not fit this record"
        )
    if not sel.has_reflected[0]:
        raise PeakError(
            f"single peak: no reflected peak after the incident one at sample {ki} (largest "
            f"later value {float(sel.w_max[0]):.4g} N, noise floor {floor:.4g} N)"
        )
    k_ref = sel.k_reflected
    kr = int(k_ref[0])
    pr, fr = refine_peak(y, kr, upsample)
    pair = PeakPair(pi / rate, pr / rate, fi, fr)
    if min_tof is not None:
        check_tof(pair.tof, min_tof)
    return pair


def _last_significant_before(y: np.ndarray, sel: Selection, rule: PeakRule, floor: float
                             ) -> int:
    """The sample of the last significant maximum of ``y`` between the incident pulse's
    end and the reflected window's start (the pulse a straddle error names)."""
    col = y[:, None]
    m = local_maxima(col)
    level = rule.split_fraction * sel.w_max
    sig = m & (col >= level) & (col > floor) & prominent(col, m, floor)
    k = np.flatnonzero(sig[:, 0])
    return int(k[k < sel.k_gap[0]][-1])


def check_tof(tof: float, min_tof: float) -> float:
    """``tof`` (s) if it is at least the shortest physical round trip ``min_tof`` (s).

    Raises :class:`PeakError` naming both numbers otherwise: a wave cannot come back from
    the wall sooner, so such a TOF is a wrong peak (a ripple, a split incident pulse), a
    wrong device description, or a damaged record.

    Parameters
    ----------
    tof : float
        The TOF, s.
    min_tof : float
        The shortest physical round trip, s.

    Returns
    -------
    float
        ``tof``.

    Raises
    ------
    PeakError
        When ``tof < min_tof`` (or is NaN).
    """
    if not tof >= min_tof:
        raise PeakError(
            f"TOF {tof * 1e3:.4f} ms is shorter than the shortest physical round trip "
            f"sensor -> wall -> sensor, {min_tof * 1e3:.4f} ms: not a reflection"
        )
    return tof
