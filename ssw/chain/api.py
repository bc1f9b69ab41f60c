"""Public entry points of the chain stage (the contracts of docs/CONTRACTS.md).

* :func:`tof` (s): TOF for broadcast arrays of soil E (Pa) and nu, one batched run;
* :func:`sensor_signal` (s, N): the sensor force vs time;
* :func:`peak_wall_indentation` (m): the largest indentation of the Hertz wall;
* :func:`run_chain`: every contact force vs time (the ``ssw chain`` command).

``wall`` names a law of :data:`ssw.chain.walls.WALLS` (``rigid``, ``hertz``, ``fit``,
``table``); ``wall_options`` are its builder's keywords (``K=``, ``power=``, ``k_table=``
for ``fit``; ``curve=`` for ``table``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.chain.integrate import Run, simulate
from ssw.chain.params import ChainParams
from ssw.chain.tof import Peaks, pick_peaks
from ssw.chain.walls import build_wall


def _shape(soil_E: Any, soil_nu: Any) -> tuple[int, ...]:
    return np.broadcast_shapes(np.shape(soil_E), np.shape(soil_nu))


def peaks(
    soil_E: Any, soil_nu: Any, params: ChainParams, wall: str = "hertz", **wall_options: Any
) -> tuple[Peaks, Run]:
    """Picked peaks (flat, one per scene) and the run, for broadcast ``soil_E``, ``soil_nu``."""
    w = build_wall(wall, params, soil_E, soil_nu, **wall_options)
    run = simulate(params, w)
    return pick_peaks(run.t, run.sensor), run


def tof(
    soil_E: Any, soil_nu: Any, params: ChainParams, wall: str = "hertz", **wall_options: Any
) -> np.ndarray:
    """TOF (s) between the incident and reflected peaks at the sensor, vectorized.

    Parameters
    ----------
    soil_E : Pa, soil_nu : -, broadcast together; the result has their broadcast shape.
    params : the chain.  wall : last-contact law.  wall_options : its options.
    """
    pk, _ = peaks(soil_E, soil_nu, params, wall, **wall_options)
    return pk.tof.reshape(_shape(soil_E, soil_nu))


def sensor_signal(
    soil_E: Any,
    soil_nu: Any,
    params: ChainParams,
    wall: str = "hertz",
    *,
    t_end: float | None = None,
    **wall_options: Any,
) -> tuple[np.ndarray, np.ndarray]:
    """The sensor particle's force vs time.

    Returns ``(t, F)``: ``t`` (n_t,) s from the striker's first contact, ``F`` N, the mean of
    the sensor particle's two contact forces, static precompression included; shape (n_t,)
    for scalar ``soil_E``/``soil_nu``, else (n_t, *broadcast shape). Without ``t_end`` the run
    stops once the reflected wave has passed the sensor (the latest scene's stop time);
    with ``t_end`` (s) it runs exactly that long.
    """
    w = build_wall(wall, params, soil_E, soil_nu, **wall_options)
    if t_end is None:
        run = simulate(params, w)
        stop = run.stop_time
        n_t = run.t.size if np.any(np.isnan(stop)) else int(np.rint(stop.max() / run.dt)) + 1
        F = _hold_last(run.sensor[:n_t])
        t = run.t[:n_t]
    else:
        run = simulate(params, w, t_end=t_end, stop_early=False)
        t, F = run.t, run.sensor
    return t, F.reshape((t.size, *_shape(soil_E, soil_nu)))


def _hold_last(F: np.ndarray) -> np.ndarray:
    """Fill each column's NaN tail (stopped scene) with its last value."""
    out = F.copy()
    valid = ~np.isnan(out)
    last = np.maximum.accumulate(np.where(valid, np.arange(out.shape[0])[:, None], 0), axis=0)
    return out[last, np.arange(out.shape[1])]


def peak_wall_indentation(soil_E: Any, soil_nu: Any, params: ChainParams) -> np.ndarray:
    """Largest indentation (m) of the last bead into the Hertz wall during the first hit.

    The fit stage uses it as the indentation range its K fits must cover. Shape: the
    broadcast shape of ``soil_E`` (Pa) and ``soil_nu``.
    """
    w = build_wall("hertz", params, soil_E, soil_nu)
    run = simulate(params, w)
    return run.peak_wall_indentation.reshape(_shape(soil_E, soil_nu))


def run_chain(
    params: ChainParams,
    soil_E: float,
    soil_nu: float,
    wall: str = "hertz",
    *,
    t_end: float,
    **wall_options: Any,
) -> Run:
    """One scene run to ``t_end`` (s) recording every contact force and the energy."""
    w = build_wall(wall, params, soil_E, soil_nu, **wall_options)
    return simulate(params, w, t_end=t_end, stop_early=False, record_forces=True,
                    record_energy=True)
