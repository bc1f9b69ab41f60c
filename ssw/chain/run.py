"""The chain run against prebuilt walls (the :class:`ssw.chain.wall.Wall` protocol): the
incident and reflected peaks at the sensor on the integrator's dense output (with their
derivatives when asked), a truncated record never taken for a TOF, and the peak indentation
of the Hertz wall.

The laws by name (``fem``, ``fit``, ``plastic``, ...) are built above the chain, in
:mod:`ssw.walls`; the TOF of a device on a named wall is :mod:`ssw.tof.api`.
"""

from __future__ import annotations

from dataclasses import fields, replace
from typing import Any

import numpy as np

from ssw.chain.dense import dense_peaks
from ssw.chain.integrate import Run, simulate, step_tangent, time_step
from ssw.chain.params import Batch, ChainParams
from ssw.chain.sensitivity import MOVES_STEP, STEP, Tangent, tangent_of
from ssw.chain.tof import Peaks, check_selection
from ssw.chain.wall import Wall, hertz_wall, is_stateful
from ssw.errors import SolverError
from ssw.signal.rule import select

#: Longest simulated time (s) a truncated scene is extended to (doubling from t_max).
T_END_CAP = 1.0


def check_complete(run: Run, params: ChainParams) -> None:
    """Refuse a truncated record.

    Parameters
    ----------
    run : Run
        The record.
    params : ChainParams
        The chain (its ``t_max``, for the message).

    Raises
    ------
    SolverError
        A scene ran to its end time without its reflected wave passing the sensor
        (``stop_time`` NaN: the record is truncated, its TOF a guess).
    """
    bad = np.flatnonzero(np.isnan(run.stop_time))
    if bad.size:
        raise SolverError(
            f"{bad.size} of {run.stop_time.size} scenes (e.g. scene {bad[0]}) ran "
            f"{run.t[-1]:.4g} s (up to {T_END_CAP} s, doubling chain.t_max = {params.t_max} s) "
            "before their reflected wave had passed the sensor (record truncated): check "
            "the wall law and the striker speed"
        )


def step_derivatives(params: ChainParams | Batch, wall: Any, tangent: Tangent | None
                     ) -> np.ndarray | None:
    """The step's derivatives for a run at the step its parameters give (no ``dt`` fixed),
    when the run must carry the step's own column (:data:`ssw.chain.sensitivity.STEP`) for
    the chain rule: a parameter of ``tangent`` moves the step (some derivative of
    :func:`ssw.chain.integrate.step_tangent` is not 0: the striker's speed and mass, the
    sensor's mass at bead 1, E of a wall stiffer than a rigid flat), the step's column is
    not asked itself, and the wall can differentiate it (any wall without state; a stateful
    one with ``step_tangent``). Otherwise None: the run carries no extra column.

    Parameters
    ----------
    params : ChainParams or Batch
        The chain.
    wall : Wall
        The last contact.
    tangent : Tangent or None
        The parameters.

    Returns
    -------
    numpy.ndarray or None
        (n, k) s per unit of each parameter, or None.
    """
    if tangent is None or STEP in tangent.names:  # the step's column itself is asked
        return None
    if not any(n in MOVES_STEP for n in tangent.names):
        return None
    if is_stateful(wall) and not getattr(wall, "step_tangent", False):
        return None
    b = params if isinstance(params, Batch) else Batch.of(params, wall.n)
    ddt = step_tangent(b, wall, time_step(b, wall), tangent.names)
    return ddt if np.any(ddt) else None


def chain_step(x: np.ndarray | None, ddt: np.ndarray) -> np.ndarray | None:
    """The chain rule through the step: ``x[:, :k] + x[:, k] ddt`` of derivatives ``x``
    (n, k + 1) whose last column is the step's (:data:`ssw.chain.sensitivity.STEP`), with
    ``ddt`` (n, k) the step's derivatives (:func:`ssw.chain.integrate.step_tangent`).

    Parameters
    ----------
    x : numpy.ndarray or None
        (..., n, k + 1) per unit of each parameter, then per second of step.
    ddt : numpy.ndarray
        (n, k) s per unit of each parameter.

    Returns
    -------
    numpy.ndarray or None
        (..., n, k) the total derivatives (None for None).
    """
    if x is None:
        return None
    return x[..., :-1] + x[..., -1:] * ddt


def run_peaks(params: ChainParams | Batch, wall: Wall, *, strict: bool = True,
              dt: float | None = None, on_progress: Any = None, derivatives: Any = None
              ) -> tuple[Peaks, Run]:
    """Peaks on the dense output (:func:`ssw.chain.dense.dense_peaks`) and the run of
    prebuilt walls (one per scene).

    A scene whose reflected wave has not passed the sensor by ``t_max`` (a long, slow chain
    on a soft soil) is run again, alone with the others like it, for twice as long, up to
    :data:`T_END_CAP`: its TOF never comes from a truncated record. The returned run's
    ``stop_time``, ``peak_wall_indentation`` and ``peak_contact_force`` are those of the
    final runs (its ``sensor`` and ``dsensor`` records are the first run's).

    Parameters
    ----------
    params : ChainParams or Batch
        The chain (a Batch for per-scene striker speeds, preloads, masses).
    wall : Wall
        The last contact, one per scene.
    strict : bool
        Raise on a scene still truncated at the cap or a signal without two peaks
        (:func:`check_complete`, :func:`ssw.chain.tof.check_selection`); otherwise those
        scenes get NaN (a calibration scan over wide parameter ranges).
    dt : float or None
        s, the time step (default :func:`ssw.chain.integrate.time_step` of the batch).
    on_progress : callable or None
        Told ``on_progress(k)`` when ``k`` scenes finish.
    derivatives : Tangent or str or sequence of str or None
        Parameters to differentiate the peaks with respect to
        (:mod:`ssw.chain.sensitivity`): the Peaks then carry ``dt_incident``,
        ``dt_reflected``, ... and ``dtof`` (n, k). Without ``dt`` the step is the
        parameters' own (:func:`ssw.chain.integrate.time_step`), and the derivatives
        include its dependence on them (the run carries the step's column where it moves,
        :func:`step_derivatives`, and the chain rule with
        :func:`ssw.chain.integrate.step_tangent`); with ``dt`` the step is held fixed.

    Returns
    -------
    tuple
        ``(Peaks, Run)``.

    Raises
    ------
    SolverError
        (strict) a scene is still truncated at :data:`T_END_CAP`.
    RecordingError
        (strict) a scene has no incident or no reflected peak.
    """
    tg = tangent_of(derivatives)
    ddt = step_derivatives(params, wall, tg) if dt is None else None
    carried = tg.with_step() if ddt is not None else tg
    run = simulate(params, wall, dt=dt, on_progress=on_progress, derivatives=carried)
    b = params if isinstance(params, Batch) else Batch.of(params, wall.n)
    p = b.params
    pk = dense_peaks(run, strict=False)
    names = [f.name for f in fields(Peaks) if f.name not in ("tangent",)]
    cols = {k: (None if getattr(pk, k) is None else np.array(getattr(pk, k), copy=True))
            for k in names}
    stop, peak = run.stop_time.copy(), run.peak_wall_indentation.copy()
    peak_f = run.peak_contact_force.copy()
    t_end = p.t_max
    nan = np.isnan(stop)
    while nan.any() and t_end < T_END_CAP:
        t_end = min(2.0 * t_end, T_END_CAP)
        idx = np.flatnonzero(nan)
        sub = simulate(b.take(idx), wall.take(idx), dt=run.dt, t_end=t_end,
                       on_progress=on_progress, derivatives=carried)
        sp = dense_peaks(sub, strict=False)
        for k, c in cols.items():
            if c is not None:
                c[idx] = getattr(sp, k)
        stop[idx], peak[idx] = sub.stop_time, sub.peak_wall_indentation
        peak_f[idx] = sub.peak_contact_force
        nan = np.isnan(stop)
    run = replace(run, stop_time=stop, peak_wall_indentation=peak, peak_contact_force=peak_f)
    if strict:
        check_complete(run, p)
        if np.any(np.isnan(cols["t_reflected"])):  # stopped, no two peaks: the rule says why
            bad = np.flatnonzero(np.isnan(cols["t_reflected"]))
            check_selection(select(run.sensor[:, bad] - run.sensor[0, bad]), True)
    gone = np.isnan(stop)
    for c in cols.values():
        if c is not None and c.dtype.kind == "f":
            c[gone] = np.nan
    if cols["dense"] is not None:
        cols["dense"][gone] = False
    if ddt is not None:
        for k in ("dt_incident", "dt_reflected", "df_incident", "df_reflected"):
            cols[k] = chain_step(cols[k], ddt)
    return Peaks(**cols, tangent=tg), run


def peak_wall_indentation(soil_E: Any, soil_nu: Any, params: ChainParams) -> np.ndarray:
    """Largest indentation of the last bead into the Hertz wall during the first hit.

    The fit stage uses it as the indentation range its K fits must cover.

    Parameters
    ----------
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.
    params : ChainParams
        The chain.

    Returns
    -------
    numpy.ndarray
        m, the broadcast shape of ``soil_E`` and ``soil_nu``.
    """
    w = hertz_wall(params, soil_E, soil_nu)
    run = simulate(params, w)
    return run.peak_wall_indentation.reshape(np.broadcast_shapes(np.shape(soil_E),
                                                                np.shape(soil_nu)))
