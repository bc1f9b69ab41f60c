"""Time of flight of a sampled sensor signal: the peak rule, refined by a parabola.

The rule that chooses the incident and reflected peaks is :mod:`ssw.signal.rule` (stated
once for simulated and measured signals). Here it is applied to the columns of a signal
sampled on a uniform grid (the first sample the static baseline ``b = F[0]``,
``s = F - b``), and each chosen sample is refined by the vertex of the parabola through it
and its two neighbours (error ``O(dt^3)`` at a smooth maximum). A simulated run's own TOF
is located on the integrator's dense output instead (:mod:`ssw.chain.dense`), which is
smooth in the run's parameters; this sampled picker serves signals without one (a
resampled or filtered force, a sweep of saved records).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.errors import RecordingError
from ssw.signal.peaks import parabolic_vertex
from ssw.signal.rule import RULE, PeakRule, Selection, select


@dataclass(frozen=True)
class Peaks:
    """Picked peaks per column, shapes (n,).

    Parameters
    ----------
    t_incident : numpy.ndarray
        Incident peak times (s).
    t_reflected : numpy.ndarray
        Reflected peak times (s).
    f_incident : numpy.ndarray
        Incident peak heights above the baseline (N).
    f_reflected : numpy.ndarray
        Reflected peak heights above the baseline (N).
    dt_incident : numpy.ndarray or None
        (n, k) s per unit of each parameter of ``tangent``: the incident time's derivatives
        (peaks on a run's dense output with sensitivities, :mod:`ssw.chain.dense`).
    dt_reflected : numpy.ndarray or None
        (n, k), the reflected time's.
    df_incident : numpy.ndarray or None
        (n, k) N per unit, the incident height's.
    df_reflected : numpy.ndarray or None
        (n, k), the reflected height's.
    dense : numpy.ndarray or None
        (n,) bool: both peaks located on the dense output (False: a parabolic vertex);
        None for peaks of a sampled signal.
    tangent : Tangent or None
        The parameters of the derivatives.
    """

    t_incident: np.ndarray
    t_reflected: np.ndarray
    f_incident: np.ndarray
    f_reflected: np.ndarray
    dt_incident: np.ndarray | None = None
    dt_reflected: np.ndarray | None = None
    df_incident: np.ndarray | None = None
    df_reflected: np.ndarray | None = None
    dense: np.ndarray | None = None
    tangent: Any = None

    @property
    def tof(self) -> np.ndarray:
        """``t_reflected - t_incident`` (s)."""
        return self.t_reflected - self.t_incident

    @property
    def dtof(self) -> np.ndarray | None:
        """(n, k) s per unit of each parameter: the TOF's derivatives (None without)."""
        if self.dt_reflected is None or self.dt_incident is None:
            return None
        return self.dt_reflected - self.dt_incident


def parabolic(y: np.ndarray, k: np.ndarray, cols: np.ndarray, *, near: bool = False
              ) -> tuple[np.ndarray, np.ndarray]:
    """Vertex offset (samples) and height of the parabola through ``y[k-1..k+1, col]``
    (``y`` (n_t, n), ``k`` and ``cols`` (m,) with ``1 <= k <= n_t - 2``; with ``near``,
    ``y`` (3, m) holds only those samples): :func:`ssw.signal.peaks.parabolic_vertex`.

    Parameters
    ----------
    y : numpy.ndarray
        Samples, (n_t, n), or with ``near`` (3, m).
    k : numpy.ndarray
        Sample index of each peak, (m,).
    cols : numpy.ndarray
        Column of each peak, (m,).
    near : bool
        Whether ``y`` holds only the three samples around each peak.

    Returns
    -------
    offset : numpy.ndarray
        Vertex offset from ``k`` (samples), (m,).
    height : numpy.ndarray
        Vertex height (the unit of ``y``), (m,).
    """
    pos, height = parabolic_vertex(y, k, cols, near=near)
    return pos - k, height


def check_selection(sel: Selection, strict: bool) -> np.ndarray:
    """The columns without two peaks.

    Parameters
    ----------
    sel : Selection
        The rule's choice (:func:`ssw.signal.rule.select`).
    strict : bool
        Raise for any.

    Returns
    -------
    numpy.ndarray
        (n,) bool.

    Raises
    ------
    RecordingError
        (strict) a column has no incident or no reflected peak.
    """
    bad = ~sel.ok
    if np.any(bad) and strict:
        raise RecordingError(
            f"no {'incident' if not sel.has_incident.all() else 'reflected'} peak in "
            f"{np.count_nonzero(bad)} of {bad.size} signals (columns {np.flatnonzero(bad)[:5]})"
        )
    return bad


def pick_peaks(t: np.ndarray, F: np.ndarray, *, rule: PeakRule = RULE,
               strict: bool = True) -> Peaks:
    """Incident and reflected peaks of ``F`` sampled at uniform times ``t``.

    Parameters
    ----------
    t : numpy.ndarray
        (n_t,) s, uniform.
    F : numpy.ndarray
        (n_t,) or (n_t, n) N; NaN samples (a stopped scene) count as the baseline.
    rule : PeakRule
        The peak rule (:data:`ssw.signal.rule.RULE`).
    strict : bool
        Raise on a column without two peaks (else its values are NaN).

    Returns
    -------
    Peaks
        Per column; 0-d arrays for a 1-d ``F``.

    Raises
    ------
    RecordingError
        (strict) a column has no incident or no reflected peak.
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
    sel = select(s, rule)
    bad = check_selection(sel, strict)
    cols = np.arange(s.shape[1])
    k_inc = np.clip(sel.k_incident, 1, s.shape[0] - 2)
    k_ref = np.clip(sel.k_reflected, 1, s.shape[0] - 2)
    o_i, h_i = parabolic(s, k_inc, cols)
    o_r, h_r = parabolic(s, k_ref, cols)
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


def tof_from_signal(t: np.ndarray, F: np.ndarray, *, rule: PeakRule = RULE) -> np.ndarray:
    """TOF (s) of each column of ``F`` by :func:`pick_peaks`.

    Parameters
    ----------
    t : numpy.ndarray
        (n_t,) s, uniform.
    F : numpy.ndarray
        (n_t,) or (n_t, n) N.
    rule : PeakRule
        The peak rule.

    Returns
    -------
    numpy.ndarray
        (n,) s (0-d for a 1-d ``F``).
    """
    return pick_peaks(t, F, rule=rule).tof
