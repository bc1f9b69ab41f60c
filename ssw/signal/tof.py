"""Time of flight of a recording: per-hit TOF, the rejection rule, mean, std and COV.

Per hit: subtract the pretrigger baseline (median), estimate the noise (1.4826 MAD of the
pretrigger samples), low-pass with a zero-phase filter (:func:`ssw.signal.filters.lowpass`,
no delay), pick the incident and reflected peaks (:func:`ssw.signal.peaks.pick_peaks`),
``TOF = t_reflected - t_incident``. Any constant delay (NI 9234 input delay, trigger
position, cable) shifts both peaks equally and cancels.

Rejection rule for a session (thesis: "three consecutive tests"; its MATLAB rule is not
published, so this one is ours):

1. clipped hits (overrange at +-5 V) are rejected: a flattened peak has no parabolic
   vertex;
2. hits whose peaks cannot be picked (no peak, single peak, peak on the record's edge) are
   rejected with the reason;
3. with three or more remaining hits, a hit whose TOF is farther than ``OUTLIER_K``
   robust sigmas from the median is rejected; the robust sigma is ``1.4826 MAD`` floored at
   ``0.1 / f_s`` so that identical TOFs do not reject everything else.

The statistics are over the accepted hits: mean, sample standard deviation (ddof = 1,
0 for one hit) and ``COV = std / mean x 100 %``. Fewer than ``min_hits`` accepted hits is a
:class:`ssw.errors.RecordingError` listing every rejection.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ssw.errors import RecordingError
from ssw.signal.filters import MAD_TO_SIGMA, baseline, lowpass, noise_sigma
from ssw.signal.peaks import PeakError, PeakPair, PeakRule, pick_peaks

OUTLIER_K = 3.5  # robust sigmas from the median beyond which a hit's TOF is an outlier
OUTLIER_FLOOR_SAMPLES = 0.1  # robust-sigma floor, in sample periods


@dataclass(frozen=True)
class TofOptions:
    """Processing options: low-pass cutoff, peak rule, minimum accepted hits.

    ``lowpass`` (Hz) is off by default: the NI 9234 has band-limited the record to
    0.45 f_s already, and even a zero-phase filter reshapes the broader, asymmetric
    reflected pulse of a soft medium and biases the TOF (``ssw bench tof --lowpass``).
    """

    lowpass: float | None = None
    rule: PeakRule = field(default_factory=PeakRule)
    min_hits: int = 1


def hit_peaks(force: np.ndarray, rate: float, n_pre: int, opts: TofOptions) -> PeakPair:
    """Peaks of one record (force in N, ``n_pre`` pretrigger samples). Raises PeakError."""
    y = np.asarray(force, dtype=np.float64) - baseline(force, n_pre)
    sigma = noise_sigma(y, n_pre)
    return pick_peaks(lowpass(y, rate, opts.lowpass), rate, sigma, opts.rule)


@dataclass(frozen=True)
class TofResult:
    """TOF of a session: per-hit values (s; NaN if rejected), verdicts and statistics."""

    tof: np.ndarray
    accepted: np.ndarray
    reasons: tuple[str, ...]
    f_incident: np.ndarray
    f_reflected: np.ndarray
    sample_rate: float

    @property
    def n_accepted(self) -> int:
        return int(self.accepted.sum())

    @property
    def mean(self) -> float:
        """Mean TOF of the accepted hits, s."""
        return float(np.mean(self.tof[self.accepted]))

    @property
    def std(self) -> float:
        """Sample standard deviation (ddof = 1) of the accepted TOFs, s; 0 for one hit."""
        t = self.tof[self.accepted]
        return float(np.std(t, ddof=1)) if t.size > 1 else 0.0

    @property
    def cov_pct(self) -> float:
        """Coefficient of variation of the accepted TOFs, %."""
        return 100.0 * self.std / self.mean

    def to_dict(self) -> dict:
        return {
            "tof_mean": self.mean, "tof_std": self.std, "tof_cov_pct": self.cov_pct,
            "n_hits": int(self.tof.size), "n_accepted": self.n_accepted,
            "tof_per_hit": [None if not np.isfinite(v) else float(v) for v in self.tof],
            "accepted": self.accepted.tolist(), "rejections": list(self.reasons),
            "f_incident": self.f_incident.tolist(), "f_reflected": self.f_reflected.tolist(),
            "sample_rate": self.sample_rate,
        }


def outliers(tof: np.ndarray, rate: float) -> np.ndarray:
    """Mask of finite TOFs farther than ``OUTLIER_K`` robust sigmas from their median."""
    ok = np.isfinite(tof)
    out = np.zeros(tof.shape, dtype=bool)
    if ok.sum() < 3:
        return out
    med = np.median(tof[ok])
    sigma = max(MAD_TO_SIGMA * np.median(np.abs(tof[ok] - med)), OUTLIER_FLOOR_SAMPLES / rate)
    out[ok] = np.abs(tof[ok] - med) > OUTLIER_K * sigma
    return out


def session_tof(
    forces: list[np.ndarray], rate: float, n_pre: int, *, clipped: list[bool] | None = None,
    opts: TofOptions | None = None, source: str = "recording",
) -> TofResult:
    """Apply the per-hit TOF and the rejection rule to a session's records.

    Parameters
    ----------
    forces : records, N (one per hit).
    rate : sample rate, S/s.
    n_pre : pretrigger samples (baseline and noise come from them).
    clipped : per-hit clipping flags (rule 1).
    source : name used in error messages.
    """
    opts = opts or TofOptions()
    n = len(forces)
    if n == 0:
        raise RecordingError(f"{source}: empty recording: no hits")
    tof = np.full(n, np.nan)
    fi = np.full(n, np.nan)
    fr = np.full(n, np.nan)
    reasons: list[str] = []
    for i, f in enumerate(forces):
        if clipped is not None and clipped[i]:
            reasons.append(f"hit {i}: clipped")
            continue
        try:
            pp = hit_peaks(f, rate, n_pre, opts)
        except PeakError as exc:
            reasons.append(f"hit {i}: {exc}")
            continue
        tof[i], fi[i], fr[i] = pp.tof, pp.f_incident, pp.f_reflected
    out = outliers(tof, rate)
    for i in np.flatnonzero(out):
        reasons.append(f"hit {i}: TOF {tof[i] * 1e3:.4f} ms is an outlier (> {OUTLIER_K} "
                       "robust sigmas from the median)")
    accepted = np.isfinite(tof) & ~out
    if accepted.sum() < opts.min_hits:
        raise RecordingError(
            f"{source}: {int(accepted.sum())} of {n} hits accepted, at least {opts.min_hits} "
            f"needed; rejected: {'; '.join(reasons)}"
        )
    return TofResult(tof, accepted, tuple(reasons), fi, fr, float(rate))


def recording_tof(recording, opts: TofOptions | None = None) -> TofResult:
    """:func:`session_tof` of a :class:`ssw.daq.recording.Recording`."""
    hits = recording.hits
    return session_tof(
        [h.force for h in hits], recording.sample_rate,
        int(recording.meta.get("pretrigger_samples", hits[0].trigger_index)),
        clipped=[h.clipped for h in hits], opts=opts, source=recording.path,
    )
