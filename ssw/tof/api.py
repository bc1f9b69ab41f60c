"""The TOF of a device on a sample: the chain run against a last-contact law named in
:data:`ssw.walls.WALLS` (the public entry points of docs/CONTRACTS.md).

* :func:`tof` (s): TOF for broadcast arrays of soil E (Pa) and nu, one batched run;
* :func:`peaks`: the picked peaks and the run behind them;
* :func:`sensor_signal` (s, N): the sensor force vs time;
* :func:`run_chain`: every contact force vs time (the ``ssw chain`` command).

``wall`` names a law of :data:`ssw.walls.WALLS` (``rigid``, ``hertz``, ``fit``, ``table``,
``fem``, ``plastic``); ``wall_options`` are its builder's keywords (``K=``, ``power=``,
``k_table=`` for ``fit``; ``curve=`` for ``table``; ``contact=`` for ``fem``). The chain
itself (:mod:`ssw.chain`) knows only the wall protocol: :func:`ssw.chain.run.run_peaks` runs
walls already built.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.chain.integrate import Run, simulate
from ssw.chain.params import Batch, ChainParams
from ssw.chain.run import run_peaks
from ssw.chain.tof import Peaks
from ssw.walls import build_wall


def _shape(soil_E: Any, soil_nu: Any, vary: dict[str, Any] | None = None) -> tuple[int, ...]:
    extra = [np.shape(v) for v in (vary or {}).values() if v is not None]
    return np.broadcast_shapes(np.shape(soil_E), np.shape(soil_nu), *extra)


def _broadcast(soil_E: Any, soil_nu: Any, vary: dict[str, Any] | None
               ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray] | None]:
    """E, nu and the varied fields broadcast to one shape, flattened."""
    shape = _shape(soil_E, soil_nu, vary)
    E = np.broadcast_to(np.asarray(soil_E, float), shape).ravel()
    nu = np.broadcast_to(np.asarray(soil_nu, float), shape).ravel()
    flat = None if not vary else {
        k: np.broadcast_to(np.asarray(v, float), shape).ravel()
        for k, v in vary.items() if v is not None}
    return E, nu, flat


def peaks(
    soil_E: Any, soil_nu: Any, params: ChainParams, wall: str = "hertz", *,
    vary: dict[str, Any] | None = None, strict: bool = True, on_progress: Any = None,
    **wall_options: Any,
) -> tuple[Peaks, Run]:
    """Picked peaks (flat, one per scene) and the run, for broadcast ``soil_E``, ``soil_nu``
    and the per-scene fields ``vary`` (:data:`ssw.chain.params.VARYING` -> values)."""
    E, nu, flat = _broadcast(soil_E, soil_nu, vary)
    w = build_wall(wall, params, E, nu, **wall_options)
    b = Batch.of(params, w.n, flat) if flat else params
    return run_peaks(b, w, strict=strict, on_progress=on_progress)


def tof(
    soil_E: Any, soil_nu: Any, params: ChainParams, wall: str = "hertz", *,
    vary: dict[str, Any] | None = None, **wall_options: Any,
) -> np.ndarray:
    """TOF (s) between the incident and reflected peaks at the sensor, vectorized.

    Parameters
    ----------
    soil_E : array_like
        The soil's Young's modulus, Pa; broadcast with ``soil_nu`` and the arrays of
        ``vary``: the result has their broadcast shape.
    soil_nu : array_like
        The soil's Poisson's ratio.
    params : ssw.chain.params.ChainParams
        The chain.
    wall : str
        The last-contact law's name (:data:`ssw.walls.WALLS`).
    vary : dict or None
        Per-scene arrays of chain parameters (striker speed, preload, masses:
        :data:`ssw.chain.params.VARYING`).
    **wall_options : dict
        The wall builder's options.

    Raises
    ------
    SolverError
        A scene's record is truncated (its reflected wave had not passed the sensor at
        ``params.t_max``).
    """
    pk, _ = peaks(soil_E, soil_nu, params, wall, vary=vary, **wall_options)
    return pk.tof.reshape(_shape(soil_E, soil_nu, vary))


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
    for scalar ``soil_E``/``soil_nu``, else ``(n_t, *broadcast_shape)``. Without ``t_end`` the run
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
