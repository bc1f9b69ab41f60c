"""Conditioning of a force record before peak picking: baseline, noise level, low-pass.

Delays. A zero-phase filter (``sosfiltfilt``) shifts neither peak. A causal filter (or the
NI 9234's own decimation FIR, or any fixed trigger/dead time) delays every sample by the
same group delay only if the filter is linear-phase or the pulses share a spectrum; the
delay then cancels in the peak-to-peak TOF ``t_r - t_i``. The reflected pulse off a soft
medium is broader than the incident one, so with a non-linear-phase (e.g. causal
Butterworth) filter its peak moves by a different amount and a bias remains: that is why
:func:`lowpass` is zero-phase, and why TOFs must be compared only between records
processed identically.
"""

from __future__ import annotations

import numpy as np

from ssw.errors import ConfigError

MAD_TO_SIGMA = 1.4826  # sigma = 1.4826 MAD for Gaussian noise


def baseline(force: np.ndarray, n_pre: int) -> float:
    """Median of the first ``n_pre`` samples (the pretrigger part), N.

    Parameters
    ----------
    force : numpy.ndarray
        The record, N.
    n_pre : int
        Pretrigger samples (at least 1 is used).

    Returns
    -------
    float
        The baseline, N.
    """
    n = max(int(n_pre), 1)
    return float(np.median(force[:n]))


def noise_sigma(force: np.ndarray, n_pre: int) -> float:
    """Robust noise level of the pretrigger samples, ``1.4826 MAD``, N.

    Parameters
    ----------
    force : numpy.ndarray
        The record, N.
    n_pre : int
        Pretrigger samples (at least 2 are used).

    Returns
    -------
    float
        The noise's standard deviation estimate, N.
    """
    pre = force[: max(int(n_pre), 2)]
    return float(MAD_TO_SIGMA * np.median(np.abs(pre - np.median(pre))))


def lowpass(force: np.ndarray, rate: float, cutoff: float | None, order: int = 4) -> np.ndarray:
    """Zero-phase Butterworth low-pass (forward-backward, ``scipy.signal.sosfiltfilt``).

    Parameters
    ----------
    force : numpy.ndarray
        (n,) record, N.
    rate : float
        Sample rate, S/s.
    cutoff : float or None
        -3 dB frequency of each pass, Hz (the forward-backward response is -6 dB there);
        ``None`` returns the record unchanged.
    order : int
        Butterworth order of each pass.

    Returns
    -------
    numpy.ndarray
        The filtered record, N (float64).

    Raises
    ------
    ssw.errors.ConfigError
        When ``cutoff`` is not in (0, rate / 2) Hz.
    """
    if cutoff is None:
        return np.asarray(force, dtype=np.float64)
    if not 0 < cutoff < rate / 2:
        raise ConfigError("signal.lowpass", cutoff, f"a frequency in (0, {rate / 2}) Hz or null")
    from scipy import signal

    sos = signal.butter(order, cutoff, btype="lowpass", fs=rate, output="sos")
    return signal.sosfiltfilt(sos, np.asarray(force, dtype=np.float64))
