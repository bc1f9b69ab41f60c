"""Inverse problem: the soil modulus E from a measured TOF and an assumed Poisson's ratio.

TOF(E) at fixed nu decreases strictly with E (a stiffer wall returns the wave sooner). The
inverse evaluates the forward model on a log-spaced E grid in one batched run, checks
monotonicity, interpolates ``ln E`` against TOF with a monotone cubic (PCHIP, Fritsch &
Carlson 1980), then refines each estimate by secant steps on the forward model itself, so
that ``inverse(forward(E)) = E`` to the forward model's own precision rather than the
grid's. With a stored sweep (``sweep=``) only the interpolation is used.

One inversion serves every path: :func:`invert_batch` on a :class:`ForwardGrid` (computed
for the targets, or given: a stored sweep's, :class:`ssw.modulus.Estimator`'s) is what
``ssw invert``, ``ssw measure`` (:func:`ssw.modulus.estimate_moduli`), acquisition's live E
(:class:`ssw.modulus.Estimator`), the validation and the calibration's leave-one-out call.
Its guards (:func:`grid_fault`): a forward grid with a missing (NaN) or non-finite TOF, or
one that does not decrease strictly, is not inverted.

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
    """E (Pa) and its interval for each TOF (s); arrays of the TOF's shape.

    Parameters
    ----------
    E : numpy.ndarray
        Young's modulus (Pa).
    E_low : numpy.ndarray
        Lower end of its interval (Pa), from TOF + std.
    E_high : numpy.ndarray
        Upper end of its interval (Pa), from TOF - std.
    clipped : numpy.ndarray
        Whether an interval end hit the range's end.
    tof_range : tuple
        TOF at the largest and at the smallest modulus (s).
    E_range : tuple
        Modulus range of the forward model (Pa).
    """

    E: np.ndarray
    E_low: np.ndarray  # from TOF + std
    E_high: np.ndarray  # from TOF - std
    clipped: np.ndarray  # bool: an interval end hit the range's end
    tof_range: tuple[float, float]  # s, (TOF at E_max, TOF at E_min): common to every TOF
    E_range: tuple[float, float]  # Pa


@dataclass(frozen=True)
class ForwardGrid:
    """The forward model's TOF(E) on one E grid, for each group of targets that share a
    Poisson's ratio and chain values: what the inversion interpolates.

    ``E`` (m,) Pa, increasing; ``T`` (G, m) s; ``nu`` (G,); ``vary``: the per-scene chain
    values (:data:`ssw.chain.params.VARYING` name -> (G,) array) of each group.

    Parameters
    ----------
    E : numpy.ndarray
        Moduli (Pa), (m,), increasing.
    T : numpy.ndarray
        TOFs (s), (G, m).
    nu : numpy.ndarray
        Poisson's ratio of each group, (G,).
    vary : dict
        Per-scene chain values of each group, name -> (G,) array.
    """

    E: np.ndarray
    T: np.ndarray
    nu: np.ndarray
    vary: dict[str, np.ndarray]

    def group_of(self, nu: np.ndarray, vary: dict[str, np.ndarray]) -> np.ndarray:
        """The group of each target (its nu and chain values).

        Parameters
        ----------
        nu : ndarray
            (k,) Poisson's ratios of the targets.
        vary : dict
            The targets' chain values, name -> (k,) array.

        Returns
        -------
        ndarray
            (k,) int: the row of each target's group, -1 where the grid has none.
        """
        if set(vary) != set(self.vary):
            return np.full(nu.size, -1)
        rows = {tuple(r): g for g, r in enumerate(
            np.column_stack([self.nu, *(self.vary[n] for n in sorted(self.vary))]).tolist())}
        keys = np.column_stack([nu, *(vary[n] for n in sorted(vary))]).tolist()
        return np.array([rows.get(tuple(k), -1) for k in keys], dtype=np.int64)

    def interpolant(self, g: int) -> Any:
        """``ln E`` against TOF of group ``g``: the monotone cubic the inversion reads (PCHIP,
        Fritsch & Carlson 1980); its derivative is ``d ln E / d TOF`` (1/s), the slope of
        the secant steps and of a TOF's term in ``ln E`` (:class:`ssw.modulus.Estimator`).

        Parameters
        ----------
        g : int
            The group's row; its TOFs must pass :func:`grid_fault`.

        Returns
        -------
        scipy.interpolate.PchipInterpolator
            ``ln E`` (E in Pa) of a TOF (s), on the group's TOFs in increasing order.

        References
        ----------
        Fritsch, F. N. and Carlson, R. E. (1980). Monotone piecewise cubic interpolation.
        SIAM J. Numer. Anal. 17, 238-246.
        """
        from scipy.interpolate import PchipInterpolator

        return PchipInterpolator(self.T[g, ::-1], np.log(self.E[::-1]))


def forward_grid(
    soil_nu: Any, params: ChainParams, wall: str, *, vary: dict[str, Any] | None = None,
    E_range: tuple[float, float] = E_RANGE, grid_points: int = GRID_POINTS,
    **wall_options: Any,
) -> ForwardGrid:
    """TOF(E) on ``grid_points`` log-spaced moduli over ``E_range`` for each distinct
    (``soil_nu``, ``vary``) of the targets, in ONE batched forward run.

    Parameters
    ----------
    soil_nu : array_like
        The targets' Poisson's ratios, (k,) or one.
    params : ChainParams
        The device's chain.
    wall : str
        The wall law's name (:mod:`ssw.walls`).
    vary : dict, optional
        Per-target chain values (:data:`ssw.chain.params.VARYING` name -> (k,) array).
    E_range : tuple of float
        ``(E_min, E_max)``, Pa.
    grid_points : int
        Moduli of the grid.
    **wall_options
        The wall law's options.

    Returns
    -------
    ForwardGrid
        One row of TOFs per group.
    """
    nu = np.atleast_1d(np.asarray(soil_nu, float)).ravel()
    vk = {n: np.broadcast_to(np.asarray(v, float), nu.shape).ravel()
          for n, v in (vary or {}).items() if v is not None}
    names = sorted(vk)
    keys = np.column_stack([nu, *(vk[n] for n in names)])
    groups = np.unique(keys, axis=0)
    G = groups.shape[0]
    E_g = np.geomspace(E_range[0], E_range[1], int(grid_points))
    gvary = {n: np.repeat(groups[:, 1 + j], E_g.size) for j, n in enumerate(names)}
    T_g = api.tof(np.tile(E_g, G), np.repeat(groups[:, 0], E_g.size), params, wall,
                  vary=gvary or None, **wall_options).reshape(G, E_g.size)
    return ForwardGrid(E_g, np.asarray(T_g, float), groups[:, 0].copy(),
                       {n: groups[:, 1 + j].copy() for j, n in enumerate(names)})


def sweep_grid(sweep: Sweep, soil_nu: float, E_range: tuple[float, float]) -> ForwardGrid:
    """The :class:`ForwardGrid` of a stored sweep.

    Parameters
    ----------
    sweep : Sweep
        A stored forward sweep.
    soil_nu : float
        The Poisson's ratio (one of the sweep's).
    E_range : tuple of float
        ``(E_min, E_max)``, Pa: the sweep's moduli kept.

    Returns
    -------
    ForwardGrid
        One group: the sweep's TOFs at ``soil_nu`` within ``E_range``.
    """
    E, T = sweep.curve(soil_nu)
    sel = (E >= E_range[0] * (1 - 1e-12)) & (E <= E_range[1] * (1 + 1e-12))
    return ForwardGrid(np.asarray(E[sel], float), np.asarray(T[sel], float)[None],
                       np.array([float(soil_nu)]), {})


def grid_fault(E: np.ndarray, T: np.ndarray, nu: float) -> str:
    """Why a forward grid cannot be inverted (the inversion's guards), or "" if it can.

    Fewer than two points, a missing (NaN) or infinite TOF (NaN compares false: a bare
    difference test would pass it), or TOF(E) not strictly decreasing.

    Parameters
    ----------
    E : ndarray
        (m,) moduli of the grid, Pa, increasing.
    T : ndarray
        (m,) their TOFs, s.
    nu : float
        The Poisson's ratio (for the message).

    Returns
    -------
    str
        The reason, "" when the grid is invertible.
    """
    if E.size < 2 or not np.all(np.isfinite(T)) or not np.all(np.diff(T) < 0):
        return (f"TOF(E) at nu = {nu:g} is not strictly decreasing on the E grid "
                f"[{E[0]:.4g}, {E[-1]:.4g}] Pa, or has a missing value: cannot invert")
    return ""


@dataclass(frozen=True)
class BatchInversion:
    """E (Pa) of many targets, each with its own nu and per-scene chain values; (k,) arrays.

    ``E`` is NaN where ``reason`` (a text per target, "" when inverted) says why not;
    ``tof_lo``/``tof_hi`` (s) the forward model's TOF range of each target's group.

    Parameters
    ----------
    E : numpy.ndarray
        Young's modulus (Pa), (k,); NaN where not inverted.
    tof_lo : numpy.ndarray
        Smallest TOF of each target's group (s), (k,).
    tof_hi : numpy.ndarray
        Largest TOF of each target's group (s), (k,).
    reason : tuple
        Why a target was not inverted, per target; empty when it was.
    E_range : tuple
        Modulus range of the forward model (Pa).
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
    grid: ForwardGrid | None = None, **wall_options: Any,
) -> BatchInversion:
    """E (Pa) from TOFs (s) of ``k`` targets with their own ``soil_nu`` and per-scene chain
    values ``vary`` (:data:`ssw.chain.params.VARYING` -> (k,) arrays), in few batched runs.

    Targets sharing nu and chain values share one forward grid (``grid_points`` log-spaced
    E, default :data:`GRID_POINTS`; fewer over a narrow ``E_range`` where every forward
    law is costly, as a plastic sample's), computed in ONE run (:func:`forward_grid`) or
    given (``grid``: a stored sweep's, or one kept between calls); PCHIP in ``ln E``
    against TOF, then ``refine`` secant steps on the forward model (one run each, all
    targets together).

    Parameters
    ----------
    tof : array_like
        (k,) TOFs, s.
    soil_nu : array_like
        Poisson's ratio of each target, (k,) or one.
    params : ChainParams
        The device's chain.
    wall : str
        The wall law's name.
    vary : dict, optional
        Per-target chain values.
    E_range : tuple of float
        ``(E_min, E_max)`` of the grid, Pa (ignored with ``grid``).
    strict : bool
        Raise on a target that cannot be inverted; otherwise its E is NaN and ``reason``
        says why.
    refine : int
        Secant steps on the forward model (0: the interpolation alone).
    grid_points : int
        Moduli of a computed grid.
    grid : ForwardGrid, optional
        The forward grid to use; it must hold every target's group.
    **wall_options
        The wall law's options.

    Returns
    -------
    BatchInversion
        E per target, the TOF range of its group and the reasons.

    Raises
    ------
    OutOfRangeError
        (``strict``) A TOF outside its forward model's range over ``E_range``.
    SolverError
        (``strict``) A forward TOF(E) that is not strictly decreasing or has a missing
        value (:func:`grid_fault`): not invertible.
    ConfigError
        A TOF <= 0, a bad ``E_range``, or a ``grid`` without a target's group.
    """
    T = np.atleast_1d(np.asarray(tof, float)).ravel()
    k = T.size
    nu = np.broadcast_to(np.asarray(soil_nu, float), (k,)).ravel()
    vk = {n: np.broadcast_to(np.asarray(v, float), (k,)).ravel()
          for n, v in (vary or {}).items() if v is not None}
    if np.any(~(T > 0)):
        raise ConfigError("tof", T.tolist(), "TOF > 0 s")
    if not 0 < E_range[0] < E_range[1]:
        raise ConfigError("E_range", E_range, "0 < E_min < E_max (Pa)")
    if grid is None:
        grid = forward_grid(nu, params, wall, vary=vk, E_range=E_range,
                            grid_points=grid_points, **wall_options)
    gidx = grid.group_of(nu, vk)
    if np.any(gidx < 0):
        raise ConfigError("grid", f"{grid.nu.size} group(s)",
                          "a forward grid computed for every target's nu and chain values")
    E_g, T_g = grid.E, grid.T
    reason = [""] * k
    lo_T, hi_T = T_g[:, -1].copy(), T_g[:, 0].copy()
    logE, splines = _interpolated(T, grid, gidx, strict, reason)
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


def _interpolated(T: np.ndarray, grid: ForwardGrid, gidx: np.ndarray, strict: bool,
                  reason: list[str]) -> tuple[np.ndarray, list[Any]]:
    """``ln E`` of each target from its group's forward grid: its interpolant in ``ln E``
    against TOF (:meth:`ForwardGrid.interpolant`, for :func:`invert_batch`). ``T`` (k,) the
    TOFs (s), ``gidx`` (k,) each target's group in ``grid``; a group whose TOF(E) is not
    invertible (:func:`grid_fault`) or a TOF outside its range raises (``strict``) or leaves
    NaN and its reason in ``reason`` (in place). Returns ``ln E`` (k,) and each group's
    interpolant (None where not invertible)."""
    E_g, T_g = grid.E, grid.T
    logE = np.full(T.size, np.nan)
    lo_T, hi_T = T_g[:, -1], T_g[:, 0]
    splines: list[Any] = []
    for g in range(T_g.shape[0]):
        members = np.flatnonzero(gidx == g)
        msg = grid_fault(E_g, T_g[g], float(grid.nu[g]))
        if msg:
            if strict and members.size:
                raise SolverError(msg)
            for i in members:
                reason[i] = msg
            splines.append(None)
            continue
        sp = grid.interpolant(g)
        splines.append(sp)
        for i in members:
            if not lo_T[g] <= T[i] <= hi_T[g]:
                msg = (f"TOF {T[i]:.6g} s is outside the valid range [{lo_T[g]:.6g}, "
                       f"{hi_T[g]:.6g}] s (E {E_g[-1] / 1e6:g}..{E_g[0] / 1e6:g} MPa at nu = "
                       f"{grid.nu[g]:g})")
                if strict:
                    raise OutOfRangeError(msg)
                reason[i] = msg
            else:
                logE[i] = float(sp(T[i]))
    return logE, splines


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

    One batched :func:`invert_batch` of ``T``, ``T + std`` and ``T - std`` on the forward
    model (refined on it), or on a stored ``sweep`` (its interpolation alone); the central
    TOFs must lie inside the model's range (an error otherwise), an interval end beyond it
    is the range's end (``clipped``).

    Parameters
    ----------
    tof : array_like
        TOFs, s.
    soil_nu : float
        Poisson's ratio.
    params : ChainParams
        The device's chain.
    wall : str
        The wall law's name.
    tof_std : array_like
        Standard deviation of each TOF, s (broadcast to ``tof``).
    E_range : tuple of float
        ``(E_min, E_max)``, Pa.
    sweep : Sweep, optional
        A stored forward sweep to interpolate instead of running the model.
    vary : dict, optional
        Per-target chain values, broadcast to ``tof``.
    **wall_options
        The wall law's options.

    Returns
    -------
    Inversion
        E, its interval ends and their clipping, the TOF and E ranges.

    Raises
    ------
    OutOfRangeError
        A TOF outside the forward model's range over ``E_range``.
    SolverError
        The forward TOF(E) is not strictly decreasing or has a missing value.
    """
    T = np.asarray(tof, float)
    S = np.broadcast_to(np.asarray(tof_std, float), T.shape)
    if np.any(~(T > 0)):
        raise ConfigError("tof", T.tolist(), "TOF > 0 s")
    if np.any(~(S >= 0)):
        raise ConfigError("tof_std", S.tolist(), "standard deviations >= 0 s")
    if not 0 < E_range[0] < E_range[1]:
        raise ConfigError("E_range", E_range, "0 < E_min < E_max (Pa)")
    targets = np.stack([T, T + S, T - S]).ravel()
    # per-target chain values follow their target into each of the three stacks
    vary3 = None if not vary else {k: np.tile(np.broadcast_to(np.asarray(v, float),
                                                              T.shape).ravel(), 3)
                                   for k, v in vary.items() if v is not None}
    grid = None if sweep is None else sweep_grid(sweep, float(soil_nu), E_range)
    res = invert_batch(targets, soil_nu, params, wall, vary=vary3, E_range=E_range,
                       strict=False, grid=grid, refine=REFINE_STEPS if sweep is None else 0,
                       **wall_options)
    n = T.size
    bad = [r for r in res.reason[:n] if r]
    if bad:
        if "not strictly decreasing" in bad[0]:
            raise SolverError(bad[0])
        raise OutOfRangeError(bad[0])
    # each target's own range (its nu and chain values: ``vary``), not the first one's
    lo_T, hi_T = res.tof_lo, res.tof_hi
    E = np.where(targets > hi_T, res.E_range[0], res.E)
    E = np.where(targets < lo_T, res.E_range[1], E)
    clipped = (targets < lo_T) | (targets > hi_T)
    E_all = E.reshape((3, *T.shape))
    return Inversion(
        E=E_all[0], E_low=E_all[1], E_high=E_all[2],
        clipped=clipped.reshape((3, *T.shape))[1:].any(axis=0),
        tof_range=(float(np.max(lo_T[:n])), float(np.min(hi_T[:n]))),
        E_range=res.E_range,
    )
