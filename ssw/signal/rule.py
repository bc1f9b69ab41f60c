"""The peak rule: which two maxima of a sensor signal make its time of flight.

TOF (thesis, "peak-to-peak"; Yang et al. 2011) is the time between the incident and the
reflected wave peaks at the sensor particle. Stated once here for every signal ssw reads, a
simulated sensor force (:mod:`ssw.chain.tof`, :mod:`ssw.chain.dense`) and a measured record
(:mod:`ssw.signal.peaks`), so that the model and the measurement pick the same pulses. On a
sampled signal ``s`` (baseline removed), column by column:

1. **incident peak**: the first local maximum with ``s >= incident_fraction * max(s)``
   (and above the noise floor, for a record);
2. **end of the incident pulse**: the first later sample with
   ``s < gap_fraction * s_incident``;
3. **reflected peak**: from there on (or from a later start, for a record: the shortest
   physical round trip), the *first* local maximum with
   ``s >= split_fraction * max(s over that window)`` (for a record: above the noise floor,
   with a prominence above it).

Soft soils split the reflected wave into several pulses (Yang et al. 2011: a primary and
secondary reflected waves); rule 3 takes the primary one, the earliest pulse that is not a
ripple, even when a later one is larger, so TOF is the primary wave's (as Yang et al.'s
TOF_PSW) and does not jump from one pulse to another as E changes unless the primary pulse
falls below ``split_fraction`` of the largest. A local maximum is a sample above its left
neighbour and not below its right one (the first sample of a flat top).

The rules are assembled once, by :func:`assemble`, for every reader: the noiseless form
(:func:`select`: no floor, no prominence test, no later start) for the chain's TOF, and
the record's form (the noise floor, the prominence test and the shortest physical round
trip, whose straddle it flags) for recorded hits (:func:`ssw.signal.peaks.pick_peaks`) and
the features and waveform fits (:func:`ssw.signal.features.pulse_features`), so that one
record gives the same peaks to ``ssw measure`` and to the calibrations.

How each chosen sample is refined to a time is the reader's: the vertex of the parabola
through three samples (:func:`ssw.chain.tof.pick_peaks`), a band-limited upsampling first
for records (:func:`ssw.signal.peaks.refine_peak`), or the maximum of the integrator's own
dense output for a simulated run (:mod:`ssw.chain.dense`).

References
----------
Yang, J., Silvestro, C., Khatri, D., De Nardo, L. and Daraio, C. (2011). Interaction of
highly nonlinear solitary waves with linear elastic media. Phys. Rev. E 83, 046606.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PeakRule:
    """The rule's thresholds (dimensionless; module docstring).

    Parameters
    ----------
    incident_fraction : float
        Share of the signal's maximum a local maximum must reach to be the incident peak.
    gap_fraction : float
        Share of the incident peak below which the incident pulse has ended.
    split_fraction : float
        Share of the reflected window's maximum a local maximum must reach to count.
    noise_k : float
        Noise sigmas a measured record's peaks must exceed (height and prominence);
        simulated signals have no noise floor.
    """

    incident_fraction: float = 0.5
    gap_fraction: float = 0.25
    split_fraction: float = 0.2
    noise_k: float = 8.0


#: The rule every TOF of ssw uses.
RULE = PeakRule()


@dataclass(frozen=True)
class Selection:
    """Sample indices chosen by the rule, per column (n,) int, and what was found (bool).

    ``k_gap`` is the first sample of the reflected window (the end of the incident
    pulse, or the later start given); ``w_max`` (n,) the window's maximum; ``straddle``
    (n,) bool, the window opens on the falling flank of a significant pulse that peaked
    before the later start (:func:`assemble`; always False without one).

    Parameters
    ----------
    k_incident : numpy.ndarray
        The incident peak's sample, (n,) int.
    k_gap : numpy.ndarray
        The reflected window's first sample, (n,) int.
    k_reflected : numpy.ndarray
        The reflected peak's sample, (n,) int.
    w_max : numpy.ndarray
        The reflected window's maximum, (n,).
    has_incident : numpy.ndarray
        Whether an incident peak was found, (n,) bool.
    has_gap : numpy.ndarray
        Whether the incident pulse ended, (n,) bool.
    has_reflected : numpy.ndarray
        Whether a reflected peak was found, (n,) bool.
    straddle : numpy.ndarray
        Whether the window opens on a falling flank, (n,) bool.
    """

    k_incident: np.ndarray
    k_gap: np.ndarray
    k_reflected: np.ndarray
    w_max: np.ndarray
    has_incident: np.ndarray
    has_gap: np.ndarray
    has_reflected: np.ndarray
    straddle: np.ndarray

    @property
    def ok(self) -> np.ndarray:
        """(n,) bool: both peaks found."""
        return self.has_incident & self.has_gap & self.has_reflected


def local_maxima(s: np.ndarray) -> np.ndarray:
    """(n_t, n) bool: interior samples above their left neighbour and not below their right
    one; ``s`` (n_t, n).

    Parameters
    ----------
    s : numpy.ndarray
        The signals, (n_t, n), time along axis 0.

    Returns
    -------
    numpy.ndarray
        The mask, (n_t, n); first and last samples False.
    """
    out = np.zeros(s.shape, dtype=bool)
    out[1:-1] = (s[1:-1] > s[:-2]) & (s[1:-1] >= s[2:])
    return out


def incident(s: np.ndarray, rule: PeakRule = RULE, *, floor: float | np.ndarray = 0.0,
             maxima: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Rule 1: the incident peak's sample per column.

    Parameters
    ----------
    s : numpy.ndarray
        (n_t, n) signal, baseline removed (N or V).
    rule : PeakRule
        The thresholds.
    floor : float or numpy.ndarray
        Noise floor (same unit as ``s``; scalar or (n,)) the peak must exceed.
    maxima : numpy.ndarray or None
        (n_t, n) bool local maxima when already known (:func:`local_maxima`).

    Returns
    -------
    tuple of numpy.ndarray
        ``(k, found)``: (n,) sample index (0 where none) and (n,) bool.
    """
    m = local_maxima(s) if maxima is None else maxima
    top = s.max(axis=0)
    ok = m & (s >= rule.incident_fraction * top) & (s > floor) & (top > 0)
    return np.argmax(ok, axis=0), ok.any(axis=0)


def gap_end(s: np.ndarray, k_incident: np.ndarray, rule: PeakRule = RULE
            ) -> tuple[np.ndarray, np.ndarray]:
    """Rule 2: the first sample after the incident peak below ``gap_fraction`` of it.

    Parameters
    ----------
    s : numpy.ndarray
        (n_t, n) signal, baseline removed.
    k_incident : numpy.ndarray
        (n,) the incident peaks' samples.
    rule : PeakRule
        The thresholds.

    Returns
    -------
    tuple of numpy.ndarray
        ``(k, found)``: (n,) sample index and (n,) bool.
    """
    cols = np.arange(s.shape[1])
    idx = np.arange(s.shape[0])[:, None]
    after = (idx > k_incident) & (s < rule.gap_fraction * s[k_incident, cols])
    return np.argmax(after, axis=0), after.any(axis=0)


#: Rows of the signal per block of the reflected window's maximum (:func:`reflected`).
WINDOW_ROWS = 256


def _window_max(s: np.ndarray, window: np.ndarray) -> np.ndarray:
    """``max(s[window])`` per column (-inf where the window is empty), ``s`` and ``window``
    (n_t, n): block by block of :data:`WINDOW_ROWS` rows, so that no (n_t, n) array of
    floats is made (a long record of many scenes: 70 MB of memory to touch)."""
    out = np.full(s.shape[1:], -np.inf)
    for i in range(0, s.shape[0], WINDOW_ROWS):
        blk = np.where(window[i : i + WINDOW_ROWS], s[i : i + WINDOW_ROWS], -np.inf)
        np.maximum(out, blk.max(axis=0), out=out)
    return out


def reflected(s: np.ndarray, start: np.ndarray, rule: PeakRule = RULE, *,
              floor: float | np.ndarray = 0.0, allowed: np.ndarray | None = None,
              maxima: np.ndarray | None = None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rule 3: the first significant local maximum from sample ``start`` on.

    Parameters
    ----------
    s : numpy.ndarray
        (n_t, n) signal, baseline removed.
    start : numpy.ndarray
        (n,) first sample of the window.
    rule : PeakRule
        The thresholds.
    floor : float or numpy.ndarray
        Noise floor (scalar or (n,)) the peak must exceed.
    allowed : numpy.ndarray or None
        (n_t, n) bool, further maxima allowed (a record's prominence test); None: all.
    maxima : numpy.ndarray or None
        (n_t, n) bool local maxima when already known.

    Returns
    -------
    tuple of numpy.ndarray
        ``(k, found, w_max)``: (n,) sample index, (n,) bool and the window's maximum (n,).
    """
    m = local_maxima(s) if maxima is None else maxima
    window = np.arange(s.shape[0])[:, None] >= start
    w_max = _window_max(s, window)
    ok = m & window & (s >= rule.split_fraction * w_max) & (s > floor) & (w_max > 0)
    if allowed is not None:
        ok &= allowed
    return np.argmax(ok, axis=0), ok.any(axis=0), w_max


def prominent(s: np.ndarray, maxima: np.ndarray, floor: float | np.ndarray) -> np.ndarray:
    """(n_t, n) bool: the local maxima whose topographic prominence exceeds ``floor``.

    Parameters
    ----------
    s : numpy.ndarray
        (n_t, n) signal, baseline removed (N or V).
    maxima : numpy.ndarray
        (n_t, n) bool local maxima (:func:`local_maxima`).
    floor : float or numpy.ndarray
        Noise floor (same unit as ``s``; scalar or (n,)).

    Returns
    -------
    numpy.ndarray
        (n_t, n) bool. A step (a maximum of the rule that rises again after a flat sample)
        has prominence 0 and never passes.

    Notes
    -----
    The prominence is ``scipy.signal.peak_prominences`` (height over the higher of the
    lowest points either side before a higher sample), one call per column: a record is
    one column.
    """
    from scipy import signal

    out = np.zeros(s.shape, dtype=bool)
    fl = np.broadcast_to(np.asarray(floor, float), s.shape[1:])
    for c in range(s.shape[1]):
        idx = np.flatnonzero(maxima[:, c])
        if idx.size:
            with warnings.catch_warnings():
                warnings.filterwarnings("ignore", message="some peaks have a prominence of 0")
                prom = signal.peak_prominences(s[:, c], idx)[0]
            out[idx, c] = prom > fl[c]
    return out


def straddles(s: np.ndarray, k_gap: np.ndarray, start: np.ndarray, significant: np.ndarray,
              level: np.ndarray) -> np.ndarray:
    """(n,) bool: the reflected window, opened at ``start`` later than the incident pulse's
    end ``k_gap``, opens on the falling flank of a significant pulse.

    That is: a significant maximum lies strictly between ``k_gap`` and ``start``, the
    signal falls at ``start`` (``s[start - 1] > s[start] >= level``) and never dropped below
    ``level`` from that maximum on. The geometry that set ``start`` (the shortest physical
    round trip) and the record then disagree.

    Parameters
    ----------
    s : numpy.ndarray
        (n_t, n) signal, baseline removed.
    k_gap : numpy.ndarray
        (n,) the incident pulse's end (rule 2).
    start : numpy.ndarray
        (n,) the window's first sample (``>= k_gap``).
    significant : numpy.ndarray
        (n_t, n) bool, the maxima that count for rule 3.
    level : numpy.ndarray
        (n,) rule 3's height, ``split_fraction`` times the window's maximum.

    Returns
    -------
    numpy.ndarray
        (n,) bool.
    """
    n_t = s.shape[0]
    cols = np.arange(s.shape[1])
    idx = np.arange(n_t)[:, None]
    before = significant & (idx > k_gap) & (idx < start)
    has = before.any(axis=0)
    j = n_t - 1 - np.argmax(before[::-1], axis=0)  # the last one
    k0 = np.clip(start, 1, n_t - 1)
    falling = (s[k0 - 1, cols] > s[k0, cols]) & (s[k0, cols] >= level)
    span = (idx >= j) & (idx <= k0)
    low = np.where(span, s, np.inf).min(axis=0)
    return has & (start < n_t) & falling & (low >= level)


def assemble(s: np.ndarray, rule: PeakRule = RULE, *, floor: float | np.ndarray = 0.0,
             min_start: Callable[[np.ndarray], np.ndarray] | np.ndarray | None = None,
             prominence: bool = False) -> Selection:
    """Rules 1-3 (module docstring) on the columns of ``s``: the one assembly every reader
    of peaks calls (the chain's TOF, recorded hits, pulse features, waveform fits).

    Parameters
    ----------
    s : numpy.ndarray
        (n_t, n) signal, baseline removed (N or V); NaN samples (a stopped scene's) read
        as 0.
    rule : PeakRule
        The thresholds.
    floor : float or numpy.ndarray
        Noise floor (same unit as ``s``; scalar or (n,)) both peaks must exceed; 0 for a
        noiseless signal.
    min_start : callable, numpy.ndarray or None
        The earliest sample of the reflected window (rule 3 of a record: the incident
        peak's time plus the shortest physical round trip), (n,) int, or a function of the
        incident peaks' samples (n,) returning it (the reader refines the incident peak its
        own way). The window starts at the later of it and the incident pulse's end.
        ``None``: at the end.
    prominence : bool
        The reflected peak's prominence must exceed ``floor`` too (a record's test,
        :func:`prominent`).

    Returns
    -------
    Selection
        The chosen samples; ``k_gap`` is the window's first sample and ``straddle``
        (:func:`straddles`, with ``min_start`` only) flags a window opening on the
        falling flank of a significant pulse: readers of records reject such a TOF.

    References
    ----------
    Yang, J. et al. (2011), Phys. Rev. E 83, 046606 (the primary reflected wave).
    """
    if np.isnan(s.max(initial=0.0)):  # a NaN anywhere (no copy of a signal without one)
        s = np.where(np.isnan(s), 0.0, s)
    m = local_maxima(s)
    k_inc, has_inc = incident(s, rule, floor=floor, maxima=m)
    k_gap, has_gap = gap_end(s, k_inc, rule)
    start = k_gap
    if min_start is not None:
        later = min_start(k_inc) if callable(min_start) else min_start
        start = np.maximum(k_gap, np.asarray(later, dtype=k_gap.dtype))
    allowed = prominent(s, m, floor) if prominence else None
    k_ref, has_ref, w_max = reflected(s, start, rule, floor=floor, allowed=allowed, maxima=m)
    straddle = np.zeros(s.shape[1], dtype=bool)
    if min_start is not None:
        level = rule.split_fraction * w_max
        sig = m & (s >= level) & (s > floor)
        if allowed is not None:
            sig &= allowed
        straddle = straddles(s, k_gap, start, sig, level) & (start > k_gap)
    return Selection(k_inc, start, k_ref, w_max, has_inc, has_gap, has_ref & has_gap,
                     straddle)


def select(s: np.ndarray, rule: PeakRule = RULE) -> Selection:
    """:func:`assemble` on a noiseless signal: no floor, no prominence, no later start.

    Parameters
    ----------
    s : numpy.ndarray
        (n_t, n) signal, baseline removed; NaN samples read as 0.
    rule : PeakRule
        The thresholds.

    Returns
    -------
    Selection
        The chosen samples.
    """
    return assemble(s, rule)
