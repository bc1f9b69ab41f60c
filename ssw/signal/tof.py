"""Time of flight of a recording: per-hit TOF, the rejection rule, mean, std and COV.

Per hit: subtract the pretrigger baseline (median), estimate the noise (1.4826 MAD of the
pretrigger samples), low-pass with a zero-phase filter (:func:`ssw.signal.filters.lowpass`,
no delay), pick the incident and reflected peaks (:func:`ssw.signal.peaks.pick_peaks`,
band-limited upsampling then a parabolic vertex), ``TOF = t_reflected - t_incident``. Any
constant delay (NI 9234 input delay, trigger position, cable) shifts both peaks equally and
cancels.

The physical bound. The reflected wave cannot return sooner than the shortest round trip
sensor -> wall -> sensor (:func:`shortest_round_trip`): the path ``L = (2 n_below + 1) R``
from the sensor's centre through the ``n_below`` beads under it to the wall, twice, at the
fastest speed a solitary wave in the chain can have (Daraio et al. 2006, with the chain's
static load), the speed at the largest contact force on the path, bounded by
:data:`WALL_AMPLIFICATION` times the largest force the record shows. The reflected peak is
searched only after it; a TOF below it is a :class:`ssw.signal.peaks.PeakError`, never a
number.

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
from typing import Any

import numpy as np

from ssw.errors import ConfigError, RecordingError
from ssw.signal.filters import MAD_TO_SIGMA, baseline, lowpass, noise_sigma
from ssw.signal.peaks import UPSAMPLE, PeakError, PeakPair, PeakRule, pick_peaks

OUTLIER_K = 3.5  # robust sigmas from the median beyond which a hit's TOF is an outlier
OUTLIER_FLOOR_SAMPLES = 0.1  # robust-sigma floor, in sample periods
#: Daraio et al. (2006): solitary wave speed coefficient without precompression, and the
#: precompressed chain's coefficient (its long-wave sound speed as f_r -> 1).
SPEED_COEFFICIENT = 0.6802
SOUND_COEFFICIENT = 0.9314
#: Largest contact force between the sensor and the wall over the largest force at the
#: sensor: at a stiff wall the incident and reflected waves overlap on a contact 2 sqrt(2)
#: times stiffer than a bead pair. Measured with ssw.chain on rigid and steel walls
#: (20-, 12-, 30- and 5-bead chains, 0.01-3 m/s, gravity on/off, preload 0-50 N): 2.1-3.2.
WALL_AMPLIFICATION = 3.2


def solitary_wave_speed(force: float, bead_radius: float, bead_E: float, bead_nu: float,
                        bead_density: float, static_force: float = 0.0) -> float:
    """Speed (m/s) of a solitary wave whose largest contact force is ``force`` (N).

    Without precompression (``static_force = 0``)
    ``V_s = 0.6802 X F_m^(1/6)``, ``X = [2 E / (a rho^(3/2) (1 - nu^2))]^(1/3)``, ``a = 2 R``
    the bead diameter (m), ``E`` (Pa), ``nu``, ``rho`` (kg/m^3) the beads'. With a static
    contact force ``F_0`` (N) and ``F_m = F_0 + force``, ``f_r = F_m / F_0``:
    ``V_s = 0.9314 X F_0^(1/6) / (f_r^(2/3) - 1) [4/15 (3 + 2 f_r^(5/3) - 5 f_r^(2/3))]^(1/2)``,
    which tends to the first law as ``f_r -> inf`` and to the long-wave sound speed
    ``c_0 = 0.9314 X F_0^(1/6)`` as ``f_r -> 1``. Long-wave approximations: a discrete chain
    runs faster by a share that is the same at every amplitude, under 2 %
    (tests/test_chain_physics.py).

    Parameters
    ----------
    force : float
        The wave's largest dynamic contact force, N (> 0).
    bead_radius : float
        The beads' radius ``R``, m.
    bead_E : float
        The beads' Young's modulus ``E``, Pa.
    bead_nu : float
        The beads' Poisson's ratio ``nu``, in (-1, 0.5].
    bead_density : float
        The beads' density ``rho``, kg/m^3.
    static_force : float
        The static contact force ``F_0``, N (>= 0).

    Returns
    -------
    float
        The wave speed ``V_s``, m/s.

    Raises
    ------
    ssw.errors.ConfigError
        When a value is out of its range.

    References
    ----------
    Daraio, C., Nesterenko, V. F., Herbold, E. B. and Jin, S. (2006). Tunability of solitary
    wave properties in one-dimensional strongly nonlinear phononic crystals. Phys. Rev. E
    73, 026610, eqs. (2)-(3). Nesterenko, V. F. (2001). Dynamics of Heterogeneous
    Materials, ch. 1.
    """
    for name, val in (("force", force), ("bead_radius", bead_radius), ("bead_E", bead_E),
                      ("bead_density", bead_density)):
        if not (np.isfinite(val) and val > 0):
            raise ConfigError(name, val, "a positive finite number (SI)")
    if not (np.isfinite(static_force) and static_force >= 0):
        raise ConfigError("static_force", static_force, "a finite force >= 0 N")
    if not -1.0 < bead_nu <= 0.5:
        raise ConfigError("bead_nu", bead_nu, "a Poisson's ratio in (-1, 0.5]")
    x = (2.0 * bead_E / (2.0 * bead_radius * bead_density**1.5 * (1.0 - bead_nu**2))) ** (1 / 3)
    if static_force == 0:
        return float(SPEED_COEFFICIENT * x * force ** (1 / 6))
    fr = (static_force + force) / static_force
    c0 = SOUND_COEFFICIENT * x * static_force ** (1 / 6)
    if fr - 1.0 < 1e-6:  # the weak-wave limit (0/0 in the formula)
        return float(c0)
    shape = np.sqrt(4.0 / 15.0 * (3.0 + 2.0 * fr ** (5 / 3) - 5.0 * fr ** (2 / 3)))
    return float(c0 * shape / (fr ** (2 / 3) - 1.0))


def shortest_round_trip(beads_below: int, bead_radius: float, bead_E: float, bead_nu: float,
                        bead_density: float, force: float, static_force: float = 0.0,
                        amplification: float = WALL_AMPLIFICATION) -> float:
    """The shortest physical TOF (s): sensor -> wall -> sensor at the fastest wave speed.

    ``t_min = 2 L / V_s`` with ``L = (2 n + 1) R`` the path (m) from the sensor's centre
    through the ``n = beads_below`` beads under it to the wall, and ``V_s`` the solitary
    wave speed (:func:`solitary_wave_speed`) at the largest contact force on that path:
    ``amplification x force`` over the static load ``static_force`` (N), ``force`` (N) the
    largest force the record shows. No reflected peak can come back sooner.

    ``amplification = 1`` is the bound at the recorded force itself; it is not a bound on a
    stiff wall: there the peak-to-peak TOF of ssw.chain falls to 0.85-0.93 of it, because
    the waves overlapping at the wall run faster (:data:`WALL_AMPLIFICATION`).

    Parameters
    ----------
    beads_below : int
        Beads between the sensor and the wall, ``n``.
    bead_radius : float
        The beads' radius ``R``, m.
    bead_E : float
        The beads' Young's modulus, Pa.
    bead_nu : float
        The beads' Poisson's ratio.
    bead_density : float
        The beads' density, kg/m^3.
    force : float
        The record's largest force, N.
    static_force : float
        The static contact force, N.
    amplification : float
        The wall's force amplification, >= 1.

    Returns
    -------
    float
        ``t_min``, s.

    Raises
    ------
    ssw.errors.ConfigError
        When ``beads_below`` is not a whole number >= 0, ``amplification`` < 1, or a value of
        :func:`solitary_wave_speed` is out of its range.

    References
    ----------
    Daraio, C., Nesterenko, V. F., Herbold, E. B. and Jin, S. (2006). Phys. Rev. E 73,
    026610, eqs. (2)-(3) (the wave speed).
    """
    n = int(beads_below)
    if n != beads_below or n < 0:
        raise ConfigError("beads_below", beads_below, "a whole number of beads >= 0")
    if not amplification >= 1:
        raise ConfigError("amplification", amplification, "a factor >= 1")
    path = (2 * n + 1) * bead_radius
    v = solitary_wave_speed(amplification * force, bead_radius, bead_E, bead_nu, bead_density,
                            static_force)
    return 2.0 * path / v


#: Fewest accepted hits whose sample standard deviation estimates the TOF's scatter (two
#: hits give one degree of freedom: an estimate that can be off by a factor of ten): the
#: default of ``TofOptions.min_hits``.
MIN_HITS_FOR_SCATTER = 3

@dataclass(frozen=True)
class ChainPath:
    """The chain between the sensor and the wall, for the bound of :func:`shortest_round_trip`.

    Parameters
    ----------
    beads_below : int
        Beads between the sensor and the wall.
    bead_radius : float
        The beads' radius, m.
    bead_E : float
        The beads' Young's modulus, Pa.
    bead_nu : float
        The beads' Poisson's ratio.
    bead_density : float
        The beads' density, kg/m^3.
    static_force : float
        The largest static contact force on the path, N (the chain's weight on the wall
        plus any preload); an AC-coupled IEPE sensor records from zero.
    """

    beads_below: int
    bead_radius: float
    bead_E: float
    bead_nu: float
    bead_density: float
    static_force: float = 0.0

    def min_tof(self, force: float) -> float:
        """Shortest round trip (s) when the record's largest force is ``force`` (N).

        Parameters
        ----------
        force : float
            The record's largest force, N.

        Returns
        -------
        float
            :func:`shortest_round_trip` along this path, with its default amplification.
        """
        return shortest_round_trip(self.beads_below, self.bead_radius, self.bead_E,
                                   self.bead_nu, self.bead_density, force, self.static_force)

    @classmethod
    def from_params(cls, params: Any) -> ChainPath:
        """From a :class:`ssw.chain.params.ChainParams` (its gravity load and preload).

        Parameters
        ----------
        params : ssw.chain.params.ChainParams
            The chain's parameters.

        Returns
        -------
        ChainPath
            The path from the sensor bead to the wall; static force: the beads' weight (with
            gravity) plus the preload, N.
        """
        weight = float(np.sum(params.masses)) * params.g if params.gravity else 0.0
        return cls(beads_below=params.n_beads - 1 - params.sensor_index,
                   bead_radius=params.bead_radius, bead_E=params.bead_E,
                   bead_nu=params.bead_nu, bead_density=params.bead_density,
                   static_force=weight + params.preload)


@dataclass(frozen=True)
class TofOptions:
    """Processing options: low-pass cutoff, peak rule, interpolation, bound, minimum hits.

    ``lowpass`` (Hz) is off by default: the NI 9234 has band-limited the record to
    0.45 f_s already, and even a zero-phase filter reshapes the broader, asymmetric
    reflected pulse of a soft medium and biases the TOF (``ssw bench tof --lowpass``).
    ``upsample``: band-limited interpolation factor before the parabolic vertex (1: the
    parabola on the samples). The physical bound of the reflected peak: ``min_tof`` (s),
    fixed, or ``chain`` (:class:`ChainPath`), evaluated per hit at its largest force; the
    larger applies. Neither: no bound (a record of unknown origin).

    Parameters
    ----------
    lowpass : float or None
        The low-pass cutoff, Hz (None: off).
    rule : ssw.signal.rule.PeakRule
        The peak rule.
    min_hits : int
        Hits that must be accepted.
    upsample : int
        The interpolation factor (1: the parabola on the samples).
    min_tof : float or None
        A fixed bound on the TOF, s.
    chain : ChainPath or None
        The chain path whose round trip bounds the TOF.
    """

    lowpass: float | None = None
    rule: PeakRule = field(default_factory=PeakRule)
    min_hits: int = MIN_HITS_FOR_SCATTER
    upsample: int = UPSAMPLE
    min_tof: float | None = None
    chain: ChainPath | None = None

    def bound(self, force_max: float) -> float | None:
        """The shortest physical TOF (s) of a record whose largest force is ``force_max``.

        Parameters
        ----------
        force_max : float
            The record's largest force, N.

        Returns
        -------
        float or None
            The larger of ``min_tof`` and the chain's bound, s; None when neither is set.
        """
        b = [self.min_tof] if self.min_tof is not None else []
        if self.chain is not None and force_max > 0:
            b.append(self.chain.min_tof(force_max))
        return max(b) if b else None


def hit_peaks(force: np.ndarray, rate: float, n_pre: int, opts: TofOptions) -> PeakPair:
    """Peaks of one record (force in N, ``n_pre`` pretrigger samples). Raises PeakError.

    Parameters
    ----------
    force : numpy.ndarray
        The record, N.
    rate : float
        The sample rate, S/s.
    n_pre : int
        Pretrigger samples (baseline and noise).
    opts : TofOptions
        The low-pass cutoff, peak rule, interpolation and bound.

    Returns
    -------
    ssw.signal.peaks.PeakPair
        The incident and reflected peaks and their TOF (s).

    Raises
    ------
    ssw.signal.peaks.PeakError
        When the rule finds no valid pair of peaks.
    """
    y = np.asarray(force, dtype=np.float64) - baseline(force, n_pre)
    sigma = noise_sigma(y, n_pre)
    y = lowpass(y, rate, opts.lowpass)
    return pick_peaks(y, rate, sigma, opts.rule, min_tof=opts.bound(float(np.max(y))),
                      upsample=opts.upsample)


@dataclass(frozen=True)
class TofResult:
    """TOF of a session: per-hit values (s; NaN if rejected), verdicts and statistics.

    Parameters
    ----------
    tof : numpy.ndarray
        Per-hit TOF, s (NaN: no pair of peaks, or clipped).
    accepted : numpy.ndarray
        Per-hit verdict, bool (finite and not an outlier).
    reasons : tuple of str
        One reason per rejected hit, naming the hit.
    f_incident : numpy.ndarray
        Per-hit incident peak force, N (NaN: no peaks).
    f_reflected : numpy.ndarray
        Per-hit reflected peak force, N (NaN: no peaks).
    sample_rate : float
        The sample rate, S/s.
    labels : tuple of str
        Each hit's name, as its file labels it (empty: ``hit k``).
    """

    tof: np.ndarray
    accepted: np.ndarray
    reasons: tuple[str, ...]
    f_incident: np.ndarray
    f_reflected: np.ndarray
    sample_rate: float
    labels: tuple[str, ...] = ()  # each hit's name, as its file labels it

    @property
    def n_accepted(self) -> int:
        """The number of accepted hits."""
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
        """The result as a JSON-able dict.

        Returns
        -------
        dict
            ``tof_mean``, ``tof_std`` (s), ``tof_cov_pct`` (%), ``n_hits``, ``n_accepted``,
            ``tof_per_hit`` (s, None when rejected), ``accepted``, ``rejections``, ``hits``,
            ``f_incident``, ``f_reflected`` (N) and ``sample_rate`` (S/s).
        """
        return {
            "tof_mean": self.mean, "tof_std": self.std, "tof_cov_pct": self.cov_pct,
            "n_hits": int(self.tof.size), "n_accepted": self.n_accepted,
            "tof_per_hit": [None if not np.isfinite(v) else float(v) for v in self.tof],
            "accepted": self.accepted.tolist(), "rejections": list(self.reasons),
            "hits": list(self.labels) or [f"hit {i + 1}" for i in range(self.tof.size)],
            "f_incident": self.f_incident.tolist(), "f_reflected": self.f_reflected.tolist(),
            "sample_rate": self.sample_rate,
        }


def outliers(tof: np.ndarray, rate: float) -> np.ndarray:
    """Mask of finite TOFs farther than ``OUTLIER_K`` robust sigmas from their median.

    Parameters
    ----------
    tof : numpy.ndarray
        Per-hit TOF, s (NaN: none).
    rate : float
        The sample rate, S/s (the robust sigma is at least ``OUTLIER_FLOOR_SAMPLES / rate``).

    Returns
    -------
    numpy.ndarray
        The mask, bool; all False with fewer than 3 finite TOFs.
    """
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
    labels: list[str] | None = None,
) -> TofResult:
    """Apply the per-hit TOF and the rejection rule to a session's records.

    Parameters
    ----------
    forces : list of numpy.ndarray
        Records, N (one per hit).
    rate : float
        Sample rate, S/s.
    n_pre : int
        Pretrigger samples (baseline and noise come from them).
    clipped : list of bool or None
        Per-hit clipping flags (rule 1).
    opts : TofOptions or None
        The peak rule, bound and rejection rule (default ``TofOptions()``).
    source : str
        Name used in error messages.
    labels : list of str or None
        Each hit's name as its file labels it (a CSV column's header, a channel's name),
        used in every reason; default ``hit k`` counted from 1.

    Returns
    -------
    TofResult
        Per-hit TOFs, verdicts and statistics.

    Raises
    ------
    ssw.errors.RecordingError
        When there are no records, or fewer than ``opts.min_hits`` are accepted.
    ssw.errors.ConfigError
        When ``labels`` does not name every hit once.
    """
    opts = opts or TofOptions()
    n = len(forces)
    if n == 0:
        raise RecordingError(f"{source}: empty recording: no hits")
    names = list(labels) if labels is not None else [f"hit {i + 1}" for i in range(n)]
    if len(names) != n:
        raise ConfigError("labels", len(names), f"one name per hit ({n})")
    tof = np.full(n, np.nan)
    fi = np.full(n, np.nan)
    fr = np.full(n, np.nan)
    reasons: list[str] = []
    for i, f in enumerate(forces):
        if clipped is not None and clipped[i]:
            reasons.append(f"{names[i]}: clipped")
            continue
        try:
            pp = hit_peaks(f, rate, n_pre, opts)
        except PeakError as exc:
            reasons.append(f"{names[i]}: {exc}")
            continue
        tof[i], fi[i], fr[i] = pp.tof, pp.f_incident, pp.f_reflected
    out = outliers(tof, rate)
    for i in np.flatnonzero(out):
        reasons.append(f"{names[i]}: TOF {tof[i] * 1e3:.4f} ms is an outlier (> {OUTLIER_K} "
                       "robust sigmas from the median)")
    accepted = np.isfinite(tof) & ~out
    k = int(accepted.sum())
    if k < opts.min_hits:
        how = ""
        if k:  # what accepts the hits there are (none: nothing would)
            what = "its TOF, without a scatter" if k == 1 else "their TOFs"
            how = f" (--min-hits {k}, or a config's validation.min_hits: {k}, accepts {what})"
        why = f"; rejected: {'; '.join(reasons)}" if reasons else ""
        raise RecordingError(f"{source}: {k} of {n} hits accepted, at least {opts.min_hits} "
                             f"needed{how}{why}")
    return TofResult(tof, accepted, tuple(reasons), fi, fr, float(rate), tuple(names))


def recording_tof(recording, opts: TofOptions | None = None) -> TofResult:
    """:func:`session_tof` of a :class:`ssw.daq.recording.Recording`.

    Parameters
    ----------
    recording : ssw.daq.recording.Recording
        The recording (force in N).
    opts : TofOptions or None
        The options (default ``TofOptions()``).

    Returns
    -------
    TofResult
        Per-hit TOFs, verdicts and statistics.

    Raises
    ------
    ssw.errors.RecordingError
        When fewer than ``opts.min_hits`` hits are accepted.
    """
    hits = recording.hits
    return session_tof(
        [h.force for h in hits], recording.sample_rate,
        int(recording.meta.get("pretrigger_samples", hits[0].trigger_index)),
        clipped=[h.clipped for h in hits], opts=opts, source=recording.path,
        labels=[h.name for h in hits],
    )
