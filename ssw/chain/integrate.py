"""Batched velocity-Verlet integration of many chains (scenes) at once.

Equations of motion (REFERENCE.md "The chain"; Nesterenko 2001, Daraio et al. 2006), beads
``i = 0..N-1`` from the striker, positions ``u`` down (m)::

    m_i u_i'' = F_{i-1} - F_i + m_i g + P delta_{i1},   F_j = A [u_j - u_{j+1}]_+^(3/2)
    (j = 0..N-2),   F_{N-1} = wall law at [u_{N-1}]_+,   F_{-1} = 0,

with ``P`` the device's preload on bead 1, plus, when ``damping > 0``, a dashpot
``c (v_j - v_{j+1})`` in every closed contact (evaluated at the new time's velocity,
predicted as ``v_{n+1/2} + dt/2 a_n``, which keeps the scheme second order). The striker
speed, the preload and the masses may differ from scene to scene
(:class:`ssw.chain.params.Batch`: a calibration scan advances many parameter sets in one
run).

Method: velocity Verlet (Stormer-Verlet; Hairer, Lubich & Wanner 2006, *Geometric Numerical
Integration*, sec. I.1.4): explicit, symplectic, second order, one force evaluation per step.
Its energy error stays bounded (no drift) and the TOF converges as ``dt^2``. The step is a
fixed fraction of the shortest Hertz contact time at the striker speed (Johnson 1985,
eq. 11.24) of two beads and of the last bead on a rigid flat (:func:`time_step`), so that
it depends on the chain alone. Every scene shares the step (the shortest of the batch's
scenes when their striker speeds or masses differ), so a whole sweep advances as
(N, n_scenes) arrays; at the default 80 steps per contact time the TOF is within 8e-5 of
an independent DOP853 solution over the thesis sweep (10 MPa; within 3.4e-5 above it;
``tests/test_chain_order.py``, ``ssw bench chain``).

The sensor signal is what the device's sensor reads (``ChainParams.sensor_reads``): the mean
of the sensor particle's two contact forces, or its upper or lower one.

Early stop. Every ``check_every`` steps each scene's record is inspected; a scene stops when
(1) its incident pulse has passed the sensor (the sensor signal fell below 30 % of its peak),
(2) the wall force has peaked and fallen below 35 % of its peak above the static force
(the first wall contact is over: every reflected pulse has left the wall), and (3) the
time since then exceeds 1.5 x the measured sensor-to-wall travel time (incident peak at
the sensor to the wall force's onset, plus one contact time) plus four contact times (the
slower, weaker reflected pulses have passed the sensor). Stopped scenes are removed from
the arrays.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.chain.params import Batch, ChainParams
from ssw.chain.statics import (
    initial_state,
    kinetic_energy,
    potential_energy,
    static_contact_forces,
)
from ssw.chain.wall import Wall

#: Fall of the sensor signal (share of its peak) that ends the incident pulse.
INCIDENT_END = 0.3
#: Fall of the wall force (share of its peak above the static force) that ends the first
#: wall contact. Soft soils keep the bottom bead pressed after the hit (the chain's weight
#: plus its rebound), so the force does not return to its static value: 0.35 of the peak.
WALL_RELEASE = 0.35
#: Travel-time factor and contact times waited after the wall release.
TRAVEL_FACTOR, TAIL_CONTACTS = 1.5, 4.0
#: Share of the two-bead impact force below which a signal counts as noise for stopping.
NOISE_SHARE = 0.01


@dataclass(frozen=True)
class Run:
    """The record of a batched run. SI units.

    t : (n_t,) s.  sensor : (n_t, n) N, the sensor signal (mean of the sensor particle's two
    contact forces, static precompression included), NaN after a scene stopped.
    wall_force : (n_t, n) N.  forces : (n_t, n, N) N or None: contacts 0..N-2 and the wall.
    energy : (n_t, n) J or None: kinetic + elastic - gravity potential (with a stateful
    wall, its ``energy(state)``: stored plus dissipated).
    peak_wall_indentation : (n,) m, the largest ``u_{N-1}``.  stop_time : (n,) s (NaN: ran
    to the end).  dt : s.
    """

    t: np.ndarray
    sensor: np.ndarray
    wall_force: np.ndarray
    forces: np.ndarray | None
    energy: np.ndarray | None
    peak_wall_indentation: np.ndarray
    stop_time: np.ndarray
    dt: float


def impact_scales(params: ChainParams | Batch) -> tuple[np.ndarray, np.ndarray]:
    """Peak overlap (m) and force (N) of the striker meeting bead 1 (Hertz); floats for a
    ChainParams, (n,) arrays for a Batch."""
    b = params if isinstance(params, Batch) else Batch.of(params, 1)
    m0, m1 = b.masses[:, 0], b.masses[:, 1]
    m_eff = m0 * m1 / (m0 + m1)
    A = b.params.bead_coefficient
    d_max = (5.0 * m_eff * b.striker_velocity**2 / (4.0 * A)) ** 0.4
    f = A * d_max**1.5
    if isinstance(params, Batch):
        return d_max, f
    return float(d_max[0]), float(f[0])


def sensor_reading(params: ChainParams, f_upper: np.ndarray, f_lower: np.ndarray
                   ) -> np.ndarray:
    """The sensor's signal (N) from the forces of its upper and lower contacts
    (``params.sensor_reads``: mean, upper or lower)."""
    if params.sensor_reads == "upper":
        return np.asarray(f_upper, float)
    if params.sensor_reads == "lower":
        return np.asarray(f_lower, float)
    return 0.5 * (np.asarray(f_upper, float) + np.asarray(f_lower, float))


def time_step(params: ChainParams | Batch, wall: Wall) -> float:
    """``min(t_c bead-bead, t_c bead on a rigid flat, t_c bead on the wall) / steps_per_contact``.

    The rigid flat is the stiffest physical wall, so for every physical wall the step
    depends on the chain alone: a scene's TOF does not depend on the batch (chunk, MPI
    rank) it is computed in, as long as the batch's scenes share the striker speed and the
    masses (a Batch takes its shortest scene's step). Only a wall stiffer than rigid at the
    impact's overlap (``hertz_equivalent``) shortens the step further.
    """
    from ssw.hertz import contact_time as hertz_time

    b = params if isinstance(params, Batch) else Batch.of(params, 1)
    p = b.params
    d_ref = float(np.min(impact_scales(b)[0]))
    a_rigid = 4.0 / 3.0 * np.sqrt(p.bead_radius) / p.bead_compliance
    a_wall = max(float(np.max(wall.hertz_equivalent(d_ref))), a_rigid)
    t_wall = float(np.min(hertz_time(b.masses[:, -1], a_wall, b.striker_velocity)))
    return min(float(np.min(b.contact_time())), t_wall) / p.steps_per_contact


class _StopRule:
    """Per-scene state of the early-stop rule (module docstring); arrays over all scenes."""

    def __init__(self, n: int, sensor0: np.ndarray, wall0: np.ndarray, f_noise: np.ndarray,
                 t_c: np.ndarray):
        self.sensor0, self.wall0, self.f_noise, self.t_c = sensor0, wall0, f_noise, t_c
        self.inc_max = np.zeros(n)
        self.t_inc = np.zeros(n)
        self.inc_done = np.zeros(n, bool)
        self.t_onset = np.full(n, np.nan)
        self.w_max = np.zeros(n)
        self.released = np.zeros(n, bool)
        self.t_rel = np.zeros(n)

    def update(self, active: np.ndarray, times: np.ndarray, S: np.ndarray, W: np.ndarray
               ) -> np.ndarray:
        """Digest a block (k, n_active) of sensor and wall forces; the scenes that may stop."""
        Sr, Wr = S - self.sensor0[active], W - self.wall0[active]
        f_noise, t_c = self.f_noise[active], self.t_c[active]
        bm = Sr.max(axis=0)
        upd = ~self.inc_done[active] & (bm > self.inc_max[active])
        self.inc_max[active[upd]] = bm[upd]
        self.t_inc[active[upd]] = times[np.argmax(Sr, axis=0)[upd]]
        self.inc_done[active] |= (self.inc_max[active] > f_noise) & (
            Sr[-1] < INCIDENT_END * self.inc_max[active]
        )
        above = Wr > f_noise
        first = np.isnan(self.t_onset[active]) & above.any(axis=0)
        self.t_onset[active[first]] = times[np.argmax(above, axis=0)[first]]
        wm = Wr.max(axis=0)
        upw = ~self.released[active] & (wm > self.w_max[active])
        self.w_max[active[upw]] = wm[upw]
        newly = (
            ~self.released[active]
            & self.inc_done[active]
            & (self.w_max[active] > f_noise)
            & (Wr[-1] < WALL_RELEASE * self.w_max[active])
        )
        self.released[active[newly]] = True
        self.t_rel[active[newly]] = times[-1]
        travel = np.nan_to_num(self.t_onset[active] - self.t_inc[active]) + t_c
        return self.released[active] & (
            times[-1] > self.t_rel[active] + TRAVEL_FACTOR * travel + TAIL_CONTACTS * t_c
        )


def simulate(
    params: ChainParams | Batch,
    wall: Wall,
    *,
    t_end: float | None = None,
    dt: float | None = None,
    stop_early: bool = True,
    record_forces: bool = False,
    record_energy: bool = False,
    check_every: int = 32,
    initial: tuple[np.ndarray, np.ndarray] | None = None,
    on_progress: Any = None,
) -> Run:
    """Integrate ``wall.n`` chains from the initial state of :mod:`ssw.chain.statics`.

    Parameters
    ----------
    params : ssw.chain.params.ChainParams or Batch
        The chain; a ``Batch`` of ``wall.n`` scenes for per-scene striker speeds,
        preloads or masses.
    wall : ssw.chain.wall.Wall
        The last-contact law, one per scene.
    t_end : float or None
        The end time, s (default ``params.t_max``).
    dt : float or None
        The time step, s (default :func:`time_step`).
    stop_early : bool
        Stop each scene once its reflected pulses have passed the sensor.
    record_forces : bool
        Also keep every contact force.
    record_energy : bool
        Also keep the total energy.
    check_every : int
        Steps between stop checks.
    initial : tuple of numpy.ndarray or None
        ``(u, v)`` (m, m/s), shapes (n, N), instead of the static initial state.
    on_progress : callable or None
        Called as ``on_progress(k)`` when ``k`` more scenes have finished (a progress
        bar's update; ``ssw.progress``).
    """
    n = wall.n
    b = params if isinstance(params, Batch) else Batch.of(params, n)
    if b.n != n:
        raise ValueError(f"batch of {b.n} scenes for a wall of {n}")
    p = b.params
    dt = float(dt if dt is not None else time_step(b, wall))
    t_end = float(t_end if t_end is not None else p.t_max)
    n_steps = int(np.ceil(t_end / dt - 1e-9))
    N, s = p.n_beads, p.sensor_index
    A, damping = p.bead_coefficient, p.damping
    inv_m_all = np.ascontiguousarray((1.0 / b.masses).T)  # (N, n)
    g_acc = p.g if p.gravity else 0.0
    F0 = static_contact_forces(b)  # (n, N)
    _, f_impact = impact_scales(b)
    rule = _StopRule(n, sensor_reading(p, F0[:, s - 1], F0[:, s]), F0[:, -1].copy(),
                     NOISE_SHARE * f_impact, b.contact_time())
    preload_all = b.preload.copy()
    has_preload = bool(np.any(preload_all > 0))
    reads = p.sensor_reads

    # internal layout (N, n_scenes): every bead's row is contiguous
    u0, v0 = initial if initial is not None else initial_state(b, wall)
    u, v = np.ascontiguousarray(u0.T), np.ascontiguousarray(v0.T)
    forces = np.full((n_steps + 1, n, N), np.nan) if record_forces else None
    energy = np.full((n_steps + 1, n), np.nan) if record_energy else None
    peak_ind = u[-1].copy()  # per active scene
    peak_all = np.empty(n)
    inv_m, preload = inv_m_all, preload_all
    # a wall with internal state (ssw.dynamics: the reduced dynamic wall) advances it every
    # step from the last bead's new position; its force is then f_wall, not force(u_last)
    stateful = hasattr(wall, "advance")
    wstate = wall.start(u[-1].copy()) if stateful else None
    f_wall = wall.force(u[-1]) if stateful else None

    def accel(u: np.ndarray, v: np.ndarray, w: Wall) -> tuple[np.ndarray, np.ndarray]:
        d = u[:-1] - u[1:]
        np.maximum(d, 0.0, out=d)
        f = np.empty_like(u)
        np.multiply(d, np.sqrt(d), out=f[:-1])
        f[:-1] *= A
        f[-1] = w.force(u[-1]) if f_wall is None else f_wall
        if damping > 0.0:
            dv = np.empty_like(u)
            dv[:-1] = v[:-1] - v[1:]
            dv[-1] = v[-1]
            closed = np.concatenate([d > 0, u[-1:] > 0], axis=0)
            f += damping * dv * closed
        net = -f
        net[1:] += f[:-1]
        if has_preload:
            net[1] += preload
        net *= inv_m
        net += g_acc
        return net, f

    def record_state(step: int, active: np.ndarray, f: np.ndarray, w: Wall) -> None:
        if forces is not None:
            forces[step, active] = f.T
        if energy is not None:
            sub = b.take(active)
            e = kinetic_energy(sub, v.T) + potential_energy(sub, w, u.T)
            if stateful and hasattr(w, "energy"):
                # a stateful wall's energy is its state's: stored plus dissipated
                stored, lost = w.energy(wstate)
                e += stored + lost - w.potential(u[-1])
            energy[step, active] = e

    def read(f: np.ndarray, out: np.ndarray) -> None:
        if reads == "upper":
            out[:] = f[s - 1]
        elif reads == "lower":
            out[:] = f[s]
        else:
            np.add(f[s - 1], f[s], out=out)
            out *= 0.5

    a, f = accel(u, v, wall)
    active = np.arange(n)
    w = wall
    record_state(0, active, f, w)
    first = np.empty(n)
    read(f, first)
    blocks: list[tuple[int, np.ndarray, np.ndarray, np.ndarray]] = [
        (0, active, first[None, :], f[-1][None, :])
    ]
    stop_time = np.full(n, np.nan)
    blk_s = np.empty((check_every, n))
    blk_w = np.empty((check_every, n))
    half = 0.5 * dt
    step, j0 = 0, 1
    for step in range(1, n_steps + 1):
        v += half * a
        u += dt * v
        if stateful:
            f_wall, wstate = w.advance(wstate, u[-1].copy(), dt)
        # the dashpot needs the velocity at the new time: v_half + dt/2 a_old estimates it
        # to O(dt^2) (a half-step velocity would make the damped scheme first order)
        a, f = accel(u, v + half * a if damping > 0.0 else v, w)
        v += half * a
        k = step - j0
        na = active.size
        read(f, blk_s[k, :na])
        blk_w[k, :na] = f[-1]
        np.maximum(peak_ind, u[-1], out=peak_ind)
        record_state(step, active, f, w)
        if k + 1 < check_every and step < n_steps:
            continue
        S = blk_s[: k + 1, :na].copy()
        W = blk_w[: k + 1, :na].copy()
        blocks.append((j0, active, S, W))
        times = dt * np.arange(j0, step + 1)
        j0 = step + 1
        if not stop_early:
            continue
        done = rule.update(active, times, S, W)
        if np.any(done):
            if on_progress is not None:
                on_progress(int(np.count_nonzero(done)))
            stop_time[active[done]] = times[-1]
            keep = ~done
            peak_all[active[done]] = peak_ind[done]
            active, peak_ind = active[keep], peak_ind[keep]
            if active.size == 0:
                break
            u, v, a = u[:, keep], v[:, keep], a[:, keep]
            inv_m, preload = inv_m_all[:, active], preload_all[active]
            if stateful:
                wstate = w.take_state(wstate, np.flatnonzero(keep))
                f_wall = f_wall[keep]
            w = w.take(np.flatnonzero(keep))
    peak_all[active] = peak_ind
    n_t = step + 1
    sensor = np.full((n_t, n), np.nan)
    wall_f = np.full((n_t, n), np.nan)
    for j, act, S, W in blocks:
        sensor[j : j + S.shape[0], act] = S
        wall_f[j : j + W.shape[0], act] = W
    return Run(
        t=dt * np.arange(n_t),
        sensor=sensor,
        wall_force=wall_f,
        forces=None if forces is None else forces[:n_t],
        energy=None if energy is None else energy[:n_t],
        peak_wall_indentation=peak_all,
        stop_time=stop_time,
        dt=dt,
    )
