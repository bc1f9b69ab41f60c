"""Reference implementation: the same chain solved with scipy's ``solve_ivp(DOP853)``.

This is the model as a researcher would first write it: one scene at a time, the state
``y = [u, v]`` (2N), the right-hand side in plain numpy, the adaptive Dormand-Prince 8(5,3)
method (Hairer, Norsett & Wanner 1993, sec. II.10) with tolerances ``rtol``/``atol``, the
sensor signal evaluated on a uniform output grid (``t_eval``, dense output), and the same
TOF rule (:mod:`ssw.chain.tof`). It is the yardstick of ``ssw bench chain`` and an
independent check of :mod:`ssw.chain.integrate` (different method, same equations).
Only power-law walls (``rigid``, ``hertz``, ``fit``) are supported.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssw.chain.params import ChainParams
from ssw.chain.statics import initial_state
from ssw.chain.tof import pick_peaks
from ssw.chain.walls import PowerWall
from ssw.errors import ConfigError, SolverError


@dataclass(frozen=True)
class BaselineResult:
    """TOF (s), the sampled sensor signal (s, N) and the solver's work (RHS evaluations)."""

    tof: float
    t: np.ndarray
    sensor: np.ndarray
    nfev: int


def solve_dop853(
    params: ChainParams,
    wall: PowerWall,
    *,
    t_end: float,
    rtol: float = 1e-9,
    atol: float = 1e-15,
    sample_dt: float = 1e-6,
) -> BaselineResult:
    """Solve one scene (``wall.n == 1``) to ``t_end`` (s) with DOP853; sensor sampled every
    ``sample_dt`` (s). ``atol`` is in m and m/s (displacements are ~1e-5 m)."""
    from scipy.integrate import solve_ivp

    if not isinstance(wall, PowerWall) or wall.n != 1:
        raise ConfigError("wall", type(wall).__name__, "one scene of a power-law wall")
    if params.damping:
        raise ConfigError("damping", params.damping, "0 for the DOP853 baseline")
    N, s = params.n_beads, params.sensor_index
    m = params.masses
    A = params.bead_coefficient
    c_w, n_w = float(wall.coef[0]), float(wall.exponent[0])
    g = params.g if params.gravity else 0.0
    u0, v0 = initial_state(params, wall)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        u, v = y[:N], y[N:]
        d = np.maximum(u[:-1] - u[1:], 0.0)
        f = A * d**1.5
        fw = c_w * max(u[-1], 0.0) ** n_w
        net = np.zeros(N)
        net[:-1] -= f
        net[1:] += f
        net[-1] -= fw
        return np.concatenate([v, net / m + g])

    t_eval = np.arange(0.0, t_end, sample_dt)
    sol = solve_ivp(rhs, (0.0, t_end), np.concatenate([u0[0], v0[0]]), method="DOP853",
                    rtol=rtol, atol=atol, t_eval=t_eval)
    if not sol.success:
        raise SolverError(f"DOP853 failed: {sol.message}")
    u = sol.y[:N]
    d = np.maximum(u[:-1] - u[1:], 0.0)
    sensor = 0.5 * A * (d[s - 1] ** 1.5 + d[s] ** 1.5)
    return BaselineResult(float(pick_peaks(sol.t, sensor).tof), sol.t, sensor, int(sol.nfev))
