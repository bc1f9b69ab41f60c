"""Time of flight from a sensor signal: peak picking with sub-sample interpolation.

TOF (thesis, "peak-to-peak"; Yang et al. 2011) is the time between the incident and the
reflected wave peaks at the sensor particle. The rule, applied to each column of a sampled
signal ``F`` (uniform step, the first sample the static baseline ``b = F[0]``, ``s = F - b``):

1. **incident peak**: the first local maximum with ``s >= INCIDENT_SHARE * max(s)``;
2. **end of the incident pulse**: the first sample after it with ``s < GAP_SHARE * s_inc``;
3. **reflected peak**: from there on, the *first* local maximum with
   ``s >= SPLIT_SHARE * max(s over that window)``.

Soft soils split the reflected wave into several pulses (Yang et al. 2011: a primary and
secondary reflected waves); rule 3 takes the primary one, the earliest pulse that is not a
ripple, even when a later one is larger, so TOF is the primary wave's (as Yang et al.'s
TOF_PSW) and does not jump from one pulse to another as E changes unless the primary pulse
falls below ``SPLIT_SHARE`` of the largest. Each peak is refined by the vertex of the
parabola through it and its two neighbours (error ``O(dt^3)`` at a smooth maximum).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.errors import RecordingError

#: A local maximum is the incident peak if it reaches this share of the signal's maximum.
INCIDENT_SHARE = 0.5
#: The incident pulse ends where the signal falls below this share of its peak.
GAP_SHARE = 0.25
#: A reflected local maximum counts if it reaches this share of the reflected maximum.
SPLIT_SHARE = 0.2


@dataclass(frozen=True)
class Peaks:
    """Picked peaks per column: times (s) and heights above baseline (N), shapes (n,)."""

    t_incident: np.ndarray
    t_reflected: np.ndarray
    f_incident: np.ndarray
    f_reflected: np.ndarray

    @property
    def tof(self) -> np.ndarray:
        """``t_reflected - t_incident`` (s)."""
        return self.t_reflected - self.t_incident


def _parabolic(y: np.ndarray, k: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertex offset (samples) and height of the parabola through ``y[k-1..k+1, col]``."""
    ym, y0, yp = y[k - 1, cols], y[k, cols], y[k + 1, cols]
    den = ym - 2.0 * y0 + yp
    safe = np.where(den < 0, den, -1.0)
    off = np.where(den < 0, 0.5 * (ym - yp) / safe, 0.0)
    return off, y0 - 0.25 * (ym - yp) * off


def pick_peaks(
    t: np.ndarray,
    F: np.ndarray,
    *,
    split_share: float = SPLIT_SHARE,
    incident_share: float = INCIDENT_SHARE,
    gap_share: float = GAP_SHARE,
    strict: bool = True,
) -> Peaks:
    """Incident and reflected peaks of ``F`` sampled at uniform times ``t``.

    Parameters
    ----------
    t : numpy.ndarray
        (n_t,) uniform sample times, s.
    F : numpy.ndarray
        (n_t,) or (n_t, n) forces, N; NaN samples (a stopped scene) count as the baseline.
    split_share : float
        The reflected peak's share of the largest (module docstring).
    incident_share : float
        The incident peak's share of the largest (module docstring).
    gap_share : float
        The gap's share of the largest (module docstring).
    strict : bool
        Raise on a column without two peaks (else its values are NaN).

    Raises
    ------
    RecordingError
        (strict) A column has no incident or no reflected peak.
    """
    t = np.asarray(t, float)
    Fa = np.asarray(F, float)
    one = Fa.ndim == 1
    y = Fa[:, None] if one else Fa
    if y.shape[0] != t.size or t.size < 5:
        raise RecordingError(f"signal of shape {Fa.shape} does not match {t.size} times (>= 5)")
    dt = (t[-1] - t[0]) / (t.size - 1)
    s = y - y[0]
    s = np.where(np.isnan(s), 0.0, s)
    idx = np.arange(s.shape[0])[:, None]
    cols = np.arange(s.shape[1])
    inner = np.zeros_like(s, dtype=bool)
    inner[1:-1] = (s[1:-1] > s[:-2]) & (s[1:-1] >= s[2:])
    smax = s.max(axis=0)
    ok_inc = inner & (s >= incident_share * smax) & (smax > 0)
    has_inc = ok_inc.any(axis=0)
    k_inc = np.argmax(ok_inc, axis=0)
    s_inc = s[k_inc, cols]
    after = (idx > k_inc) & (s < gap_share * s_inc)
    has_gap = after.any(axis=0)
    k_gap = np.argmax(after, axis=0)
    window = idx >= k_gap
    wmax = np.where(window, s, -np.inf).max(axis=0)
    ok_ref = inner & window & (s >= split_share * wmax) & (wmax > 0)
    has_ref = ok_ref.any(axis=0) & has_gap
    k_ref = np.argmax(ok_ref, axis=0)
    bad = ~(has_inc & has_ref)
    if np.any(bad) and strict:
        raise RecordingError(
            f"no {'incident' if not has_inc.all() else 'reflected'} peak in "
            f"{np.count_nonzero(bad)} of {bad.size} signals (columns {np.flatnonzero(bad)[:5]})"
        )
    o_i, h_i = _parabolic(s, k_inc, cols)
    o_r, h_r = _parabolic(s, k_ref, cols)
    nan = np.where(bad, np.nan, 0.0)
    res = Peaks(
        t_incident=t[0] + (k_inc + o_i) * dt + nan,
        t_reflected=t[0] + (k_ref + o_r) * dt + nan,
        f_incident=h_i + nan,
        f_reflected=h_r + nan,
    )
    if one:
        return Peaks(*(np.asarray(x[0]) for x in (res.t_incident, res.t_reflected,
                                                   res.f_incident, res.f_reflected)))
    return res


def tof_from_signal(t: np.ndarray, F: np.ndarray, **shares: float) -> np.ndarray:
    """TOF (s) of each column of ``F`` by the rule of :func:`pick_peaks`."""
    return pick_peaks(t, F, **shares).tof
