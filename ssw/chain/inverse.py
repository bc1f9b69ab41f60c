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

from ssw.chain import api
from ssw.chain.params import ChainParams
from ssw.chain.sweep import Sweep
from ssw.errors import ConfigError, OutOfRangeError, SolverError

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
    tof_range: tuple[float, float]  # s, (TOF at E_max, TOF at E_min)
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


def invert(
    tof: Any,
    soil_nu: float,
    params: ChainParams,
    wall: str = "hertz",
    *,
    tof_std: Any = 0.0,
    E_range: tuple[float, float] = E_RANGE,
    sweep: Sweep | None = None,
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
    E_g, T_g = _forward_grid(float(soil_nu), params, wall, E_range, sweep, wall_options)
    if E_g.size < 2 or np.any(np.diff(T_g) >= 0):
        raise SolverError(
            f"TOF(E) at nu = {soil_nu} is not strictly decreasing on the E grid "
            f"[{E_g[0]:.4g}, {E_g[-1]:.4g}] Pa: cannot invert"
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
    targets_c = np.clip(targets, lo_T, hi_T)
    spline = PchipInterpolator(T_g[::-1], np.log(E_g[::-1]))
    logE = spline(targets_c)
    if sweep is None:
        logE = _refine(logE, targets_c, spline, soil_nu, params, wall, E_g, wall_options)
    E_all = np.exp(logE).reshape((3, *T.shape))
    return Inversion(
        E=E_all[0], E_low=E_all[1], E_high=E_all[2],
        clipped=clipped.reshape((3, *T.shape))[1:].any(axis=0),
        tof_range=(lo_T, hi_T), E_range=(float(E_g[0]), float(E_g[-1])),
    )


def _refine(
    logE: np.ndarray, targets: np.ndarray, spline: Any, soil_nu: float, params: ChainParams,
    wall: str, E_g: np.ndarray, wall_options: dict[str, Any],
) -> np.ndarray:
    """Secant steps ``ln E += (d lnE/dT) (T* - T(E))`` on the forward model (batched)."""
    slope = spline.derivative()
    lo, hi = np.log(E_g[0]), np.log(E_g[-1])
    uniq, inv = np.unique(logE, return_inverse=True)
    t_u = np.empty_like(uniq)
    t_u[inv] = targets
    for _ in range(REFINE_STEPS):
        Tm = api.tof(np.exp(uniq), soil_nu, params, wall, **wall_options)
        uniq = np.clip(uniq + slope(np.clip(Tm, spline.x[0], spline.x[-1])) * (t_u - Tm), lo, hi)
    return uniq[inv]
