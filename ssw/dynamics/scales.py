"""What a quasi-static run of the chain tells the dynamic model: step, window, spectrum.

The dynamic FEM wall is sized from a cheap quasi-static run of the same chain (the Hertz
wall of the soil): the chain's time step (the dynamic run uses the same, so that both TOFs
share it), the run's length (the quasi-static stop time), the window that must stay free of
boundary reflections (from the wall force's onset until the reflected peak has left the
wall: the reflected peak at the sensor minus half the TOF, with a margin), the frequency
that bounds the wall force's spectrum (for the element size) and the peak indentation (for
the candidate zone).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class ChainScales:
    """What a quasi-static run of the chain tells the dynamic model (per scene). SI units.

    dt : s, the chain's step.  t_end : s, the run's end (quasi-static stop time, with a
    margin).  window : s, from the wall's first motion until the reflected peak has left
    the wall (its reflections must stay out).  f_max : Hz, the frequency that bounds the
    wall force's spectrum.  d_peak : m, the largest indentation.  t_onset : s.

    Parameters
    ----------
    dt : float
        The chain's step (s).
    t_end : numpy.ndarray
        The run's end (s), (n,).
    window : numpy.ndarray
        Time from the wall's first motion until the reflected peak has left it (s), (n,).
    f_max : numpy.ndarray
        Frequency bounding the wall force's spectrum (Hz), (n,).
    d_peak : numpy.ndarray
        Largest indentation (m), (n,).
    t_onset : numpy.ndarray
        Time of the wall's first motion (s), (n,).
    """

    dt: float
    t_end: np.ndarray
    window: np.ndarray
    f_max: np.ndarray
    d_peak: np.ndarray
    t_onset: np.ndarray


#: The run continues this long after the quasi-static stop time (relative; 0: the same
#: record length, so that both TOFs are picked on equal windows).
END_MARGIN = 0.0
#: Window = WINDOW_MARGIN x (reflected peak at the sensor - half the TOF - wall onset).
WINDOW_MARGIN = 1.3
#: f_max = SPECTRUM_FACTOR x the frequency below which SPECTRUM_SHARE of the wall force's
#: spectral energy lies.
SPECTRUM_SHARE, SPECTRUM_FACTOR = 0.999, 2.0


def chain_scales(params: Any, wall: Any) -> ChainScales:
    """Scales of the last contact from a quasi-static run of ``params`` with ``wall``.

    The run is the device's chain without its contact dashpot and read at the sensor's
    mean: the scales size the scene's mesh, which must not change with what the sensor
    reads or with the dashpot (so that their effects are measured on one mesh).

    Parameters
    ----------
    params : ChainParams
        The chain.
    wall : Wall
        A displacement wall of :mod:`ssw.walls` (e.g. the Hertz wall of the soil).

    Returns
    -------
    ChainScales
        Per scene.
    """
    from ssw.chain.dense import dense_peaks
    from ssw.chain.integrate import simulate, time_step

    params = params.with_(sensor_reads="mean", damping=0.0)
    dt = time_step(params, wall)
    run = simulate(params, wall, dt=dt)
    pk = dense_peaks(run)
    stop = np.where(np.isnan(run.stop_time), run.t[-1], run.stop_time)
    Fr = np.nan_to_num(run.wall_force - run.wall_force[0])
    onset = run.t[np.argmax(Fr > 0.01 * Fr.max(axis=0), axis=0)]
    window = WINDOW_MARGIN * (pk.t_reflected - 0.5 * pk.tof - onset)
    spec = np.abs(np.fft.rfft(Fr, axis=0)) ** 2
    cum = np.cumsum(spec, axis=0) / spec.sum(axis=0)
    f = np.fft.rfftfreq(Fr.shape[0], dt)
    f_max = SPECTRUM_FACTOR * f[np.argmax(cum >= SPECTRUM_SHARE, axis=0)]
    return ChainScales(dt=dt, t_end=(1.0 + END_MARGIN) * stop, window=window, f_max=f_max,
                       d_peak=run.peak_wall_indentation, t_onset=onset)
