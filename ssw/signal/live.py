"""TOF hit by hit during an acquisition, with the running mean and (optionally) E.

:class:`LiveTof` is the per-hit hook of :func:`ssw.daq.backend.run_session`
(``on_hit=live``): each hit's TOF by :func:`ssw.signal.tof.hit_peaks` (or why it was
rejected), the session rule so far (:func:`ssw.signal.tof.outliers` once three hits are
in), the mean TOF of the accepted hits and its standard error ``s / sqrt(n)``, and, given an
``estimate`` function, the soil modulus with its interval from that mean and standard
error. It returns a :class:`HitReport`; printing is the caller's (the CLI's) business.

``estimate(tof_mean, tof_sem) -> {"E": Pa, "E_low": Pa, "E_high": Pa, ...}`` is pluggable:
signal processing knows nothing of the chain; ``ssw acquire`` plugs in
:class:`ssw.modulus.Estimator` (the device's chain, calibrated or not).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ssw.errors import SswError
from ssw.signal.peaks import PeakError
from ssw.signal.tof import TofOptions, hit_peaks, outliers

Estimate = Callable[[float, float], dict[str, float]]


@dataclass(frozen=True)
class HitReport:
    """What one hit adds: its TOF (s, or None and the reason) and the running statistics.

    Parameters
    ----------
    index : int
        The hit's index, from 0.
    tof : float or None
        Its TOF, s (None: rejected).
    reason : str or None
        Why it was rejected (None: accepted).
    n_hits : int
        Hits so far.
    n_accepted : int
        Hits accepted so far (outliers judged on every hit so far).
    tof_mean : float or None
        Mean TOF of the accepted hits, s (None: none accepted).
    tof_sem : float or None
        Standard error of that mean, s (0 for one hit).
    estimate : dict or None
        The estimate from the running mean (``E``, ``E_low``, ``E_high``, Pa).
    estimate_error : str or None
        Why the estimate failed.
    """

    index: int
    tof: float | None
    reason: str | None
    n_hits: int
    n_accepted: int
    tof_mean: float | None
    tof_sem: float | None
    estimate: dict[str, float] | None = None
    estimate_error: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """The report as a dict, one key per field.

        Returns
        -------
        dict
            Field name -> value (SI units).
        """
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


@dataclass
class LiveTof:
    """Running TOF of a session (the per-hit hook; call ``live(i, hit)`` or ``live.add(F)``).

    Parameters
    ----------
    rate : float
        Sample rate, S/s.
    n_pre : int
        Pretrigger samples.
    opts : ssw.signal.tof.TofOptions
        TOF options (peak rule, bound).
    estimate : callable or None
        ``(tof_mean, tof_sem) -> {"E", "E_low", "E_high"}`` (Pa).
    tofs : list of float
        The accepted hits' TOFs so far, s (empty at the start).
    """

    rate: float
    n_pre: int
    opts: TofOptions = field(default_factory=TofOptions)
    estimate: Estimate | None = None
    tofs: list[float] = field(default_factory=list)

    def __call__(self, i: int, hit: Any) -> HitReport:
        return self.add(hit.force, overloaded=bool(getattr(hit, "overloaded", False)))

    def add(self, force: np.ndarray, *, overloaded: bool = False) -> HitReport:
        """Process one record (N); return its report.

        Parameters
        ----------
        force : numpy.ndarray
            The record, N.
        overloaded : bool
            Whether the hardware reported an overrange (the hit is rejected).

        Returns
        -------
        HitReport
            The hit's TOF or reason, and the running statistics.
        """
        i = len(self.tofs)
        tof, reason = np.nan, None
        if overloaded:
            reason = "clipped (overrange)"
        else:
            try:
                tof = hit_peaks(force, self.rate, self.n_pre, self.opts).tof
            except PeakError as exc:
                reason = str(exc)
        self.tofs.append(float(tof))
        t = np.asarray(self.tofs)
        out = outliers(t, self.rate)
        ok = np.isfinite(t) & ~out
        if reason is None and out[i]:
            reason = "outlier (> 3.5 robust sigmas from the median so far)"
        n = int(ok.sum())
        mean = float(np.mean(t[ok])) if n else None
        sem = float(np.std(t[ok], ddof=1) / np.sqrt(n)) if n > 1 else (0.0 if n else None)
        est, err = None, None
        if self.estimate is not None and mean is not None:
            try:
                est = self.estimate(mean, sem or 0.0)
            except SswError as exc:
                err = str(exc)
        return HitReport(i, None if reason else float(tof), reason, len(self.tofs), n, mean,
                         sem, est, err)
