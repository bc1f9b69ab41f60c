"""Inverse problem: the soil modulus E from a measured TOF and an assumed Poisson's ratio.

TOF(E) at fixed nu decreases strictly with E (a stiffer wall returns the wave sooner). The
inverse evaluates the forward model on a log-spaced E grid in one batched run, checks
monotonicity, interpolates ``ln E`` against TOF with a monotone cubic (PCHIP, Fritsch &
Carlson 1980), then refines each estimate by secant steps on the forward model itself, so
that ``inverse(forward(E)) = E`` to the forward model's own precision rather than the
grid's. With a stored sweep (``sweep=``) only the interpolation is used.

The interval: ``E(TOF + std)`` and ``E(TOF - std)`` (a longer TOF means a softer soil).
A TOF outside ``[TOF(E_max), TOF(E_min)]`` raises :class:`ssw.errors.OutOfRangeError`
naming the valid range; an interval end outside it is clipped to the range's end and
flagged.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.chain.params import ChainParams
from ssw.errors import ConfigError, OutOfRangeError, SolverError
from ssw.tof import api
from ssw.tof.sweep import Sweep

#: Default E range (Pa) of the inverse: the thesis's sweep.
E_RANGE = (10.0e6, 1000.0e6)
#: Points of the log-spaced forward grid.
GRID_POINTS = 48
#: Secant refinements on the forward model.
REFINE_STEPS = 2


@dataclass(frozen=True)
class Inversion:
    """E (Pa) and its interval for each TOF (s); arrays of the TOF's shape."""

    E: np.ndarray
    E_low: np.ndarray  # from TOF + std
    E_high: np.ndarray  # from TOF - std
    clipped: np.ndarray  # bool: an interval end hit the range's end
    tof_range: tuple[float, float]  # s, (TOF at E_max, TOF at E_min): common to every TOF
    E_range: tuple[float, float]  # Pa


def _forward_grid(
    soil_nu: float, params: ChainParams, wall: str, E_range: tuple[float, float],
    sweep: Sweep | None, wall_options: dict[str, Any],
) -> tuple[np.ndarray, np.ndarray]:
    if sweep is not None:
        E, T = sweep.curve(soil_nu)
        sel = (E >= E_range[0] * (1 - 1e-12)) & (E <= E_range[1] * (1 + 1e-12))
        return E[sel], T[sel]
    E = np.geomspace(E_range[0], E_range[1], GRID_POINTS)
    return E, api.tof(E, soil_nu, params, wall, **wall_options)


@dataclass(frozen=True)
class BatchInversion:
    """E (Pa) of many targets, each with its own nu and per-scene chain values; (k,) arrays.

    ``E`` is NaN where ``reason`` (a text per target, "" when inverted) says why not;
    ``tof_lo``/``tof_hi`` (s) the forward model's TOF range of each target's group.
    """

    E: np.ndarray
    tof_lo: np.ndarray
    tof_hi: np.ndarray
    reason: tuple[str, ...]
    E_range: tuple[float, float]


def invert_batch(
    tof: Any, soil_nu: Any, params: ChainParams, wall: str = "hertz", *,
    vary: dict[str, Any] | None = None, E_range: tuple[float, float] = E_RANGE,
    strict: bool = True, refine: int = REFINE_STEPS, grid_points: int = GRID_POINTS,
    **wall_options: Any,
) -> BatchInversion:
    """E (Pa) from TOFs (s) of ``k`` targets with their own ``soil_nu`` and per-scene chain
    values ``vary`` (:data:`ssw.chain.params.VARYING` -> (k,) arrays), in few batched runs.

    Targets sharing nu and chain values share one forward grid (``grid_points`` log-spaced
    E, default :data:`GRID_POINTS`; fewer over a narrow ``E_range`` where every forward
    law is costly, as a plastic sample's); every grid advances in ONE run; PCHIP in
    ``ln E`` against TOF, then ``refine`` secant steps on the forward model (one run each,
    all targets together).

    Raises
    ------
    OutOfRangeError
        (``strict``; otherwise E is NaN and ``reason`` says why) A TOF outside its forward
        model's range over ``E_range``.
    SolverError
        (``strict``) A forward TOF(E) that is not strictly decreasing (not invertible).
    """
    from scipy.interpolate import PchipInterpolator

    T = np.atleast_1d(np.asarray(tof, float)).ravel()
    k = T.size
    nu = np.broadcast_to(np.asarray(soil_nu, float), (k,)).ravel()
    vk = {n: np.broadcast_to(np.asarray(v, float), (k,)).ravel()
          for n, v in (vary or {}).items() if v is not None}
    if np.any(~(T > 0)):
        raise ConfigError("tof", T.tolist(), "TOF > 0 s")
    if not 0 < E_range[0] < E_range[1]:
        raise ConfigError("E_range", E_range, "0 < E_min < E_max (Pa)")
    keys = np.column_stack([nu, *vk.values()]) if vk else nu[:, None]
    groups, gidx = np.unique(keys, axis=0, return_inverse=True)
    gidx = np.asarray(gidx).ravel()
    G = groups.shape[0]
    E_g = np.geomspace(E_range[0], E_range[1], int(grid_points))
    gvary = {n: np.repeat(groups[:, 1 + j], E_g.size) for j, n in enumerate(vk)}
    T_g = api.tof(np.tile(E_g, G), np.repeat(groups[:, 0], E_g.size), params, wall,
                  vary=gvary or None, **wall_options).reshape(G, E_g.size)
    reason = [""] * k
    logE = np.full(k, np.nan)
    lo_T, hi_T = T_g[:, -1].copy(), T_g[:, 0].copy()
    splines = []
    for g in range(G):
        members = np.flatnonzero(gidx == g)
        if np.any(np.diff(T_g[g]) >= 0) or not np.all(np.isfinite(T_g[g])):
            msg = (f"TOF(E) at nu = {groups[g, 0]:g} is not strictly decreasing on the E grid "
                   f"[{E_g[0]:.4g}, {E_g[-1]:.4g}] Pa: cannot invert")
            if strict:
                raise SolverError(msg)
            for i in members:
                reason[i] = msg
            splines.append(None)
            continue
        sp = PchipInterpolator(T_g[g, ::-1], np.log(E_g[::-1]))
        splines.append(sp)
        for i in members:
            if not lo_T[g] <= T[i] <= hi_T[g]:
                msg = (f"TOF {T[i]:.6g} s is outside the valid range [{lo_T[g]:.6g}, "
                       f"{hi_T[g]:.6g}] s (E {E_g[-1] / 1e6:g}..{E_g[0] / 1e6:g} MPa at nu = "
                       f"{groups[g, 0]:g})")
                if strict:
                    raise OutOfRangeError(msg)
                reason[i] = msg
            else:
                logE[i] = float(sp(T[i]))
    ok = np.isfinite(logE)
    lo, hi = np.log(E_g[0]), np.log(E_g[-1])
    for _ in range(refine if ok.any() else 0):
        sel = np.flatnonzero(ok)
        Tm = api.tof(np.exp(logE[sel]), nu[sel], params, wall,
                     vary={n: v[sel] for n, v in vk.items()} or None, **wall_options)
        for j, i in enumerate(sel):
            sp = splines[gidx[i]]
            slope = float(sp.derivative()(np.clip(Tm[j], sp.x[0], sp.x[-1])))
            logE[i] = float(np.clip(logE[i] + slope * (T[i] - Tm[j]), lo, hi))
    return BatchInversion(np.exp(logE), lo_T[gidx], hi_T[gidx], tuple(reason),
                          (float(E_g[0]), float(E_g[-1])))


def invert(
    tof: Any,
    soil_nu: float,
    params: ChainParams,
    wall: str = "hertz",
    *,
    tof_std: Any = 0.0,
    E_range: tuple[float, float] = E_RANGE,
    sweep: Sweep | None = None,
    vary: dict[str, Any] | None = None,
    **wall_options: Any,
) -> Inversion:
    """E (Pa) from TOF (s) at Poisson's ratio ``soil_nu``, with the interval from ``tof_std``.

    Raises
    ------
    OutOfRangeError : a TOF outside the forward model's range over ``E_range``.
    SolverError : the forward TOF(E) is not strictly decreasing (not invertible).
    """
    from scipy.interpolate import PchipInterpolator

    T = np.asarray(tof, float)
    S = np.broadcast_to(np.asarray(tof_std, float), T.shape)
    if np.any(~(T > 0)):
        raise ConfigError("tof", T.tolist(), "TOF > 0 s")
    if np.any(~(S >= 0)):
        raise ConfigError("tof_std", S.tolist(), "standard deviations >= 0 s")
    if not 0 < E_range[0] < E_range[1]:
        raise ConfigError("E_range", E_range, "0 < E_min < E_max (Pa)")
    if sweep is None:
        # one batched inversion of T, T + std, T - std; the central TOFs must lie inside the
        # model's range (an error otherwise); an interval end beyond it is the range's end
        targets = np.stack([T, T + S, T - S]).ravel()
        # per-target chain values follow their target into each of the three stacks
        vary3 = None if not vary else {k: np.tile(np.broadcast_to(np.asarray(v, float),
                                                                  T.shape).ravel(), 3)
                                       for k, v in vary.items() if v is not None}
        res = invert_batch(targets, soil_nu, params, wall, vary=vary3, E_range=E_range,
                           strict=False, **wall_options)
        n = T.size
        bad = [r for r in res.reason[:n] if r]
        if bad:
            if "not strictly decreasing" in bad[0]:
                raise SolverError(bad[0])
            raise OutOfRangeError(bad[0])
        # each target's own range (its nu and chain values: ``vary``), not the first one's
        lo_T, hi_T = res.tof_lo, res.tof_hi
        E = res.E.copy()
        E = np.where(targets > hi_T, res.E_range[0], E)
        E = np.where(targets < lo_T, res.E_range[1], E)
        clipped = (targets < lo_T) | (targets > hi_T)
        E_all = E.reshape((3, *T.shape))
        return Inversion(
            E=E_all[0], E_low=E_all[1], E_high=E_all[2],
            clipped=clipped.reshape((3, *T.shape))[1:].any(axis=0),
            tof_range=(float(np.max(lo_T[:n])), float(np.min(hi_T[:n]))),
            E_range=res.E_range,
        )
    E_g, T_g = _forward_grid(float(soil_nu), params, wall, E_range, sweep, wall_options)
    # NaN compares false: a table with a missing TOF would pass a bare diff test
    if E_g.size < 2 or not np.all(np.isfinite(T_g)) or not np.all(np.diff(T_g) < 0):
        raise SolverError(
            f"TOF(E) at nu = {soil_nu} is not strictly decreasing on the E grid "
            f"[{E_g[0]:.4g}, {E_g[-1]:.4g}] Pa, or has a missing value: cannot invert"
        )
    lo_T, hi_T = float(T_g[-1]), float(T_g[0])
    out = (T < lo_T) | (T > hi_T)
    if np.any(out):
        raise OutOfRangeError(
            f"TOF {T[out].tolist()} s is outside the valid range [{lo_T:.6g}, {hi_T:.6g}] s "
            f"(E {E_g[-1] / 1e6:g}..{E_g[0] / 1e6:g} MPa at nu = {soil_nu})"
        )
    targets = np.stack([T, T + S, T - S]).ravel()
    clipped = (targets < lo_T) | (targets > hi_T)
    spline = PchipInterpolator(T_g[::-1], np.log(E_g[::-1]))
    E_all = np.exp(spline(np.clip(targets, lo_T, hi_T))).reshape((3, *T.shape))
    return Inversion(
        E=E_all[0], E_low=E_all[1], E_high=E_all[2],
        clipped=clipped.reshape((3, *T.shape))[1:].any(axis=0),
        tof_range=(lo_T, hi_T), E_range=(float(E_g[0]), float(E_g[-1])),
    )
