"""Incident and reflected peaks of a sensor record, with parabolic sub-sample interpolation.

Rule (stated once, applied to every hit; the chain stage's rule of
:mod:`ssw.chain.tof`, so that a simulated recording and the model pick the same pulses,
plus noise thresholds for measured records). With ``s`` the conditioned record:

1. **incident** peak: the first local maximum with ``s >= incident_fraction x max(s)``
   and above ``noise_k`` noise sigmas;
2. **end of the incident pulse**: the first later sample with ``s < gap_fraction x s_inc``;
3. **reflected** peak: from there on, the first local maximum with
   ``s >= split_fraction x max(s over that window)``, above ``noise_k`` noise sigmas and
   with a prominence of at least ``noise_k`` sigmas (the primary reflected wave; soft
   media split the reflection into several pulses, Yang et al. 2011);
4. both are refined by the vertex of the parabola through the maximum sample and its two
   neighbours (Smith & Serra 1987, quadratic interpolation of peaks):
   ``p = (y[k-1] - y[k+1]) / (2 (y[k-1] - 2 y[k] + y[k+1]))``, ``t = (k + p) / f_s``,
   ``|p| <= 1/2``.

A record without a reflected peak (a single peak), or whose peaks touch its ends, gives
:class:`PeakError` naming the reason.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.errors import RecordingError


class PeakError(RecordingError):
    """A record's peaks cannot be picked (the message gives the reason)."""


@dataclass(frozen=True)
class PeakRule:
    """Peak-picking thresholds (dimensionless; defaults are ssw.chain.tof's shares)."""

    incident_fraction: float = 0.5
    gap_fraction: float = 0.25
    split_fraction: float = 0.2
    noise_k: float = 8.0


def parabolic_vertex(y: np.ndarray, k: int | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sub-sample offset ``p`` and height of the parabola through ``y[k-1], y[k], y[k+1]``.

    Returns ``(k + p, y_peak)`` with ``y_peak = y[k] - (y[k-1] - y[k+1]) p / 4``;
    vectorized over ``k`` (each ``1 <= k <= len(y) - 2``).
    """
    k = np.asarray(k)
    ym, y0, yp = y[k - 1], y[k], y[k + 1]
    den = ym - 2 * y0 + yp
    safe = np.where(den < 0, den, -1.0)
    p = np.where(den < 0, 0.5 * (ym - yp) / safe, 0.0)
    p = np.clip(p, -0.5, 0.5)
    return k + p, y0 - 0.25 * (ym - yp) * p


@dataclass(frozen=True)
class PeakPair:
    """Incident and reflected peaks: times (s from the first sample) and heights (N)."""

    t_incident: float
    t_reflected: float
    f_incident: float
    f_reflected: float

    @property
    def tof(self) -> float:
        """Peak-to-peak time of flight, s."""
        return self.t_reflected - self.t_incident


def pick_peaks(y: np.ndarray, rate: float, noise: float, rule: PeakRule) -> PeakPair:
    """Incident and reflected peaks of the conditioned record ``y`` (N) at ``rate`` (S/s).

    ``noise`` is the record's noise sigma (N). Raises :class:`PeakError`.
    """
    from scipy import signal

    y = np.asarray(y, dtype=np.float64)
    top = float(np.max(y))
    floor = rule.noise_k * noise
    if top <= floor:
        raise PeakError(f"no peak: maximum {top:.4g} N is within {rule.noise_k} noise sigmas "
                        f"({floor:.4g} N)")
    idx, props = signal.find_peaks(y, prominence=0.0)
    prom = props["prominences"]
    inc = idx[(y[idx] >= rule.incident_fraction * top) & (y[idx] > floor)]
    if inc.size == 0:  # the maximum sits on the record's edge
        raise PeakError("no incident peak inside the record (maximum on an end sample)")
    ki = int(inc[0])
    below = np.flatnonzero(y[ki:] < rule.gap_fraction * y[ki])
    if below.size == 0:
        raise PeakError(f"single peak: the incident pulse at sample {ki} never ends "
                        f"(stays above {rule.gap_fraction} of its height)")
    kg = ki + int(below[0])
    after = idx > kg
    win_max = float(np.max(y[kg:]))
    ok = after & (y[idx] >= rule.split_fraction * win_max) & (y[idx] > floor) & (prom > floor)
    if not np.any(ok):
        raise PeakError(
            f"single peak: no reflected peak after the incident one at sample {ki} (largest "
            f"later value {win_max:.4g} N, noise floor {floor:.4g} N)"
        )
    kr = int(idx[ok][0])
    (ti, tr), (fi, fr) = parabolic_vertex(y, np.array([ki, kr]))
    return PeakPair(float(ti / rate), float(tr / rate), float(fi), float(fr))
