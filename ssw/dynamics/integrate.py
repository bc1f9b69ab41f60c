"""The chain's batched velocity Verlet with a *stateful* last contact (research copy).

:func:`ssw.chain.integrate.simulate` knows displacement walls, ``F = wall.force(u_last)``.
A dynamic wall has internal state (the soil's motion, a footing's displacement) that
advances with time. The coupling keeps Verlet's structure (Hairer, Lubich & Wanner 2006,
sec. I.1.4): each step drifts the positions, then evaluates the forces at the new
positions, here

    F_wall(n+1), state(n+1) = wall.advance(state(n), u_last(n+1), dt),

the wall integrating its own state over the step implicitly (so that stiff internal
dynamics, e.g. a massless footing on a dashpot, cost nothing in step size) from the bead's
new position only: the force still depends on positions, not on the bead's unknown new
velocity, and the scheme stays explicit for the chain. A quasi-static wall is the special
case without state (:class:`QuasiStatic`).

Stateful wall protocol (vectorized over ``n`` scenes, SI):

* ``n``; ``dt`` (the step the wall was built for, or None for any);
* ``indentation(F)``: the static indentation carrying ``F`` (the initial state's statics);
* ``hertz_equivalent(d_ref)``: ``F(d_ref) / d_ref^1.5`` (time-step choice);
* ``start(d0) -> state``: the state at rest with the last beads at ``d0``;
* ``advance(state, d, dt) -> (F, state)``;
* ``energy(state) -> (stored, dissipated)`` (J, (n,)): what the wall holds and what it
  radiated or dissipated so far;
* ``take(idx)``, ``take_state(state, idx)``: select scenes.

The run has no early stop: it ends at ``t_end`` (a dynamic run follows the quasi-static
one, whose stop time :func:`ssw.chain.integrate.simulate` measures).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ssw.chain.params import ChainParams
from ssw.chain.statics import initial_state, kinetic_energy, static_contact_forces


class StatefulWall(Protocol):
    """What :func:`simulate` needs of a last contact with internal state (module docstring)."""

    @property
    def n(self) -> int: ...

    dt: float | None

    def indentation(self, F: np.ndarray) -> np.ndarray: ...

    def hertz_equivalent(self, d_ref: float) -> np.ndarray: ...

    def start(self, d0: np.ndarray) -> Any: ...

    def advance(self, state: Any, d: np.ndarray, dt: float) -> tuple[np.ndarray, Any]: ...

    def energy(self, state: Any) -> tuple[np.ndarray, np.ndarray]: ...

    def take(self, idx: np.ndarray) -> StatefulWall: ...

    def take_state(self, state: Any, idx: np.ndarray) -> Any: ...


@dataclass(frozen=True)
class QuasiStatic:
    """A displacement wall of :mod:`ssw.walls` as a stateful wall without state."""

    wall: Any
    dt: float | None = None

    @property
    def n(self) -> int:
        return self.wall.n

    def indentation(self, F: np.ndarray) -> np.ndarray:
        return self.wall.indentation(F)

    def hertz_equivalent(self, d_ref: float) -> np.ndarray:
        return self.wall.hertz_equivalent(d_ref)

    def start(self, d0: np.ndarray) -> np.ndarray:
        return np.asarray(d0, float).copy()

    def advance(self, state: np.ndarray, d: np.ndarray, dt: float
                ) -> tuple[np.ndarray, np.ndarray]:
        return self.wall.force(d), d

    def energy(self, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.wall.potential(state), np.zeros(self.n)

    def take(self, idx: np.ndarray) -> QuasiStatic:
        return QuasiStatic(self.wall.take(idx), self.dt)

    def take_state(self, state: np.ndarray, idx: np.ndarray) -> np.ndarray:
        return state[idx]


@dataclass(frozen=True)
class DynamicRun:
    """The record of a run. SI units.

    t : (n_t,) s.  sensor : (n_t, n) N (mean of the sensor particle's two contact forces).
    wall_force : (n_t, n) N.  wall_indentation : (n_t, n) m (the last bead's ``u``).
    energy_chain : (n_t, n) J or None: kinetic + Hertz - gravity's potential of the chain.
    energy_wall : (n_t, n) J or None: what the wall stores.  dissipated : (n_t, n) J or
    None: what the wall radiated/dissipated.  dt : s.
    """

    t: np.ndarray
    sensor: np.ndarray
    wall_force: np.ndarray
    wall_indentation: np.ndarray
    energy_chain: np.ndarray | None
    energy_wall: np.ndarray | None
    dissipated: np.ndarray | None
    dt: float


def chain_energy(params: ChainParams, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Kinetic + bead-bead Hertz energy - gravity's work (J) per scene; ``u``, ``v`` (n, N)."""
    d = np.maximum(u[:, :-1] - u[:, 1:], 0.0)
    e = kinetic_energy(params, v) + 0.4 * params.bead_coefficient * np.sum(d**2.5, axis=1)
    if params.gravity:
        e -= params.g * u @ params.masses
    return e


def simulate(
    params: ChainParams,
    wall: StatefulWall,
    *,
    t_end: float,
    dt: float,
    record_energy: bool = False,
    every: int = 1,
) -> DynamicRun:
    """Integrate ``wall.n`` chains from their static state (:mod:`ssw.chain.statics`).

    Parameters
    ----------
    params : ssw.chain.params.ChainParams
        The chain.
    wall : StatefulWall
        The stateful last contact, one per scene.
    t_end : float
        The end time, s.
    dt : float
        The time step, s (the quasi-static run's step; ``wall.dt`` must agree if set).
    record_energy : bool
        Also record the energies (the balance of the tests).
    every : int
        Record every ``every``-th step only (the peaks are picked on the record).
    """
    if wall.dt is not None and abs(wall.dt - dt) > 1e-15 * dt:
        raise ValueError(f"the wall was built for dt = {wall.dt} s, the run uses {dt} s")
    n_steps = int(np.ceil(t_end / dt - 1e-9))
    s = params.sensor_index
    A = params.bead_coefficient
    inv_m = (1.0 / params.masses)[:, None]
    g_acc = params.g if params.gravity else 0.0
    u0, v0 = initial_state(params, wall)  # the wall's static indentation under the weight
    u, v = np.ascontiguousarray(u0.T), np.ascontiguousarray(v0.T)
    state = wall.start(u[-1])
    n_rec = n_steps // every + 1
    sensor = np.empty((n_rec, wall.n))
    wall_f = np.empty((n_rec, wall.n))
    wall_d = np.empty((n_rec, wall.n))
    e_chain = np.empty((n_rec, wall.n)) if record_energy else None
    e_wall = np.empty((n_rec, wall.n)) if record_energy else None
    e_diss = np.empty((n_rec, wall.n)) if record_energy else None
    F0 = static_contact_forces(params)
    preload = float(getattr(params, "preload", 0.0))  # N on bead 1 (ChainParams)

    def forces(u: np.ndarray, f_wall: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        d = np.maximum(u[:-1] - u[1:], 0.0)
        f = np.empty_like(u)
        f[:-1] = A * d * np.sqrt(d)
        f[-1] = f_wall
        net = -f
        net[1:] += f[:-1]
        net[1] += preload
        return net * inv_m + g_acc, f

    def record(k: int, f: np.ndarray) -> None:
        sensor[k] = 0.5 * (f[s - 1] + f[s])
        wall_f[k] = f[-1]
        wall_d[k] = u[-1]
        if record_energy:
            e_chain[k] = chain_energy(params, u.T, v.T)
            e_wall[k], e_diss[k] = wall.energy(state)

    a, f = forces(u, np.broadcast_to(F0[-1], (wall.n,)).copy())
    record(0, f)
    half = 0.5 * dt
    for step in range(1, n_steps + 1):
        v += half * a
        u += dt * v
        f_wall, state = wall.advance(state, u[-1].copy(), dt)
        a, f = forces(u, f_wall)
        v += half * a
        if step % every == 0:
            record(step // every, f)
    return DynamicRun(t=dt * every * np.arange(n_rec), sensor=sensor, wall_force=wall_f,
                      wall_indentation=wall_d, energy_chain=e_chain, energy_wall=e_wall,
                      dissipated=e_diss, dt=dt * every)
