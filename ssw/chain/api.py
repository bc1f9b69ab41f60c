"""Public entry points of the chain stage (the contracts of docs/CONTRACTS.md).

* :func:`tof` (s): TOF for broadcast arrays of soil E (Pa) and nu, one batched run;
* :func:`sensor_signal` (s, N): the sensor force vs time;
* :func:`peak_wall_indentation` (m): the largest indentation of the Hertz wall;
* :func:`run_chain`: every contact force vs time (the ``ssw chain`` command).

``wall`` names a law of :data:`ssw.walls.WALLS` (``rigid``, ``hertz``, ``fit``,
``table``); ``wall_options`` are its builder's keywords (``K=``, ``power=``, ``k_table=``
for ``fit``; ``curve=`` for ``table``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.chain.integrate import Run, simulate
from ssw.chain.params import Batch, ChainParams
from ssw.chain.tof import Peaks, pick_peaks
from ssw.chain.wall import Wall
from ssw.errors import SolverError
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


#: Longest simulated time (s) a truncated scene is extended to (doubling from t_max).
T_END_CAP = 1.0


def check_complete(run: Run, params: ChainParams) -> None:
    """Raise SolverError when a scene ran to its end time without its reflected wave
    passing the sensor (``stop_time`` NaN: the record is truncated, its TOF a guess)."""
    bad = np.flatnonzero(np.isnan(run.stop_time))
    if bad.size:
        raise SolverError(
            f"{bad.size} of {run.stop_time.size} scenes (e.g. scene {bad[0]}) ran "
            f"{run.t[-1]:.4g} s (up to {T_END_CAP} s, doubling chain.t_max = {params.t_max} s) "
            "before their reflected wave had passed the sensor (record truncated): check "
            "the wall law and the striker speed"
        )


def run_peaks(params: ChainParams | Batch, wall: Wall, *, strict: bool = True,
              dt: float | None = None, on_progress: Any = None) -> tuple[Peaks, Run]:
    """Picked peaks and the run of prebuilt walls (one per scene).

    A scene whose reflected wave has not passed the sensor by ``t_max`` (a long, slow chain
    on a soft soil) is run again, alone with the others like it, for twice as long, up to
    :data:`T_END_CAP`: its TOF never comes from a truncated record. The returned run's
    ``stop_time`` and ``peak_wall_indentation`` are those of the final runs (its ``sensor``
    record is the first run's). ``strict`` raises on a scene still truncated at the cap or
    a signal without two peaks (:func:`check_complete`, :func:`ssw.chain.tof.pick_peaks`);
    otherwise those scenes get NaN (a calibration scan over wide parameter ranges). ``dt``
    (s) fixes the time step (default :func:`ssw.chain.integrate.time_step` of the batch);
    ``on_progress(k)`` is told when ``k`` scenes finish.
    """
    from dataclasses import replace

    run = simulate(params, wall, dt=dt, on_progress=on_progress)
    b = params if isinstance(params, Batch) else Batch.of(params, wall.n)
    p = b.params
    pk = pick_peaks(run.t, run.sensor, strict=False)
    cols = [pk.t_incident, pk.t_reflected, pk.f_incident, pk.f_reflected]
    stop, peak = run.stop_time.copy(), run.peak_wall_indentation.copy()
    t_end = p.t_max
    nan = np.isnan(stop)
    while nan.any() and t_end < T_END_CAP:
        t_end = min(2.0 * t_end, T_END_CAP)
        idx = np.flatnonzero(nan)
        sub = simulate(b.take(idx), wall.take(idx), dt=run.dt, t_end=t_end,
                       on_progress=on_progress)
        sp = pick_peaks(sub.t, sub.sensor, strict=False)
        for c, v in zip(cols, (sp.t_incident, sp.t_reflected, sp.f_incident, sp.f_reflected),
                        strict=True):
            c[idx] = v
        stop[idx], peak[idx] = sub.stop_time, sub.peak_wall_indentation
        nan = np.isnan(stop)
    run = replace(run, stop_time=stop, peak_wall_indentation=peak)
    if strict:
        check_complete(run, p)
        if np.any(np.isnan(cols[1])):  # stopped, but no two peaks: the strict picker says why
            bad = np.flatnonzero(np.isnan(cols[1]))
            pick_peaks(run.t, run.sensor[:, bad])
    for c in cols:
        c[np.isnan(stop)] = np.nan
    return Peaks(*cols), run


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
    soil_E : Pa, soil_nu : -, and the arrays of ``vary`` (per-scene striker speed, preload,
        masses), broadcast together; the result has their broadcast shape.
    params : the chain.  wall : last-contact law.  wall_options : its options.

    Raises
    ------
    SolverError : a scene's record is truncated (its reflected wave had not passed the
        sensor at ``params.t_max``).
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
