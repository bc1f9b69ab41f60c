"""Initial state of the chain: precompression by gravity and the preload, static equilibrium.

Positions ``u_i`` (m) point down; ``u = 0`` is the just-touching chain, so the overlap of
contact ``j`` (beads ``j``, ``j+1``) is ``u_j - u_{j+1}`` and the wall indentation ``u_{N-1}``.

Beads 1..N-1 rest in static equilibrium under their weight and the preload ``P`` (a constant
downward force on bead 1): contact ``j >= 1`` carries ``F_j = P + g sum_{k=1..j} m_k``
(without gravity, ``P``), so its overlap is ``(F_j/A)^(2/3)``, and the wall carries
``P + g sum_{k=1..N-1} m_k``. The striker (bead 0) arrives from above: it touches bead 1
with zero overlap and moves at the striker speed (the speed after a drop from height ``h``
is ``sqrt(2 g h)``).

Every function takes a :class:`ssw.chain.params.Batch` (per-scene striker speed, preload and
masses) or a plain :class:`ssw.chain.params.ChainParams` (the same values for every scene).
"""

from __future__ import annotations

import numpy as np

from ssw.chain.params import Batch, ChainParams
from ssw.chain.wall import Wall


def _batch(params: ChainParams | Batch, n: int) -> Batch:
    return params if isinstance(params, Batch) else Batch.of(params, n)


def static_contact_forces(params: ChainParams | Batch) -> np.ndarray:
    """Static forces (N) of contacts 0..N-2 and the wall (last).

    Shape (N,) for a ChainParams, (n, N) for a Batch of ``n`` scenes.
    """
    b = _batch(params, 1)
    g = b.params.g if b.params.gravity else 0.0
    w = b.preload[:, None] + g * np.cumsum(b.masses[:, 1:], axis=1)  # contacts 1.. and wall
    F = np.concatenate([np.zeros((b.n, 1)), w], axis=1)
    return F[0] if isinstance(params, ChainParams) else F


def initial_state(params: ChainParams | Batch, wall: Wall) -> tuple[np.ndarray, np.ndarray]:
    """Positions ``u`` (m) and velocities ``v`` (m/s), shapes (n_scenes, N)."""
    n = wall.n
    b = _batch(params, n)
    if b.n != n:
        raise ValueError(f"batch of {b.n} scenes for a wall of {n}")
    p = b.params
    F = static_contact_forces(b)  # (n, N)
    u = np.zeros((n, p.n_beads))
    v = np.zeros((n, p.n_beads))
    v[:, 0] = b.striker_velocity
    if np.any(F[:, -1] > 0):
        overlaps = (F[:, 1:-1] / p.bead_coefficient) ** (2.0 / 3.0)  # contacts 1..N-2
        u_last = wall.indentation(F[:, -1])
        # u_j = u_{N-1} + sum_{k=j..N-2} overlap_k for j = 1..N-2; u_0 = u_1
        above = np.concatenate([np.cumsum(overlaps[:, ::-1], axis=1)[:, ::-1],
                                np.zeros((n, 1))], axis=1)  # beads 1..N-1
        u[:, 1:] = u_last[:, None] + above
        u[:, 0] = u[:, 1]
    return u, v


def potential_energy(params: ChainParams | Batch, wall: Wall, u: np.ndarray) -> np.ndarray:
    """Elastic energy (J) of the contacts and the wall minus the work potential of gravity
    and the preload, per scene (n,): Hertz ``2/5 A d^(5/2)``, the wall's ``potential``,
    ``- g sum m_i u_i - P u_1``."""
    b = _batch(params, u.shape[0])
    p = b.params
    d = np.maximum(u[:, :-1] - u[:, 1:], 0.0)
    e = 0.4 * p.bead_coefficient * np.sum(d**2.5, axis=1) + wall.potential(u[:, -1])
    if p.gravity:
        e -= p.g * np.sum(u * b.masses, axis=1)
    return e - b.preload * u[:, 1]


def kinetic_energy(params: ChainParams | Batch, v: np.ndarray) -> np.ndarray:
    """``sum m v^2 / 2`` (J) per scene."""
    b = _batch(params, v.shape[0])
    return 0.5 * np.sum(v**2 * b.masses, axis=1)
