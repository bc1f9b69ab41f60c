"""The chain run against prebuilt walls (the :class:`ssw.chain.wall.Wall` protocol): the
incident and reflected peaks at the sensor, a truncated record never taken for a TOF, and the
peak indentation of the Hertz wall.

The laws by name (``fem``, ``fit``, ``plastic``, ...) are built above the chain, in
:mod:`ssw.walls`; the TOF of a device on a named wall is :mod:`ssw.tof.api`.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ssw.chain.integrate import Run, simulate
from ssw.chain.params import Batch, ChainParams
from ssw.chain.tof import Peaks, pick_peaks
from ssw.chain.wall import Wall, hertz_wall
from ssw.errors import SolverError

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


def peak_wall_indentation(soil_E: Any, soil_nu: Any, params: ChainParams) -> np.ndarray:
    """Largest indentation (m) of the last bead into the Hertz wall during the first hit.

    The fit stage uses it as the indentation range its K fits must cover. Shape: the
    broadcast shape of ``soil_E`` (Pa) and ``soil_nu``.
    """
    w = hertz_wall(params, soil_E, soil_nu)
    run = simulate(params, w)
    return run.peak_wall_indentation.reshape(np.broadcast_shapes(np.shape(soil_E),
                                                                np.shape(soil_nu)))
