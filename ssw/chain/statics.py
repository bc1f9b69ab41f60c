"""Initial state of the chain: gravity precompression by static equilibrium.

Positions ``u_i`` (m) point down; ``u = 0`` is the just-touching chain, so the overlap of
contact ``j`` (beads ``j``, ``j+1``) is ``u_j - u_{j+1}`` and the wall indentation ``u_{N-1}``.

With gravity, beads 1..N-1 rest in static equilibrium: contact ``j >= 1`` carries the weight
of the beads above it except the striker, ``F_j = g sum_{k=1..j} m_k``, so its overlap is
``(F_j/A)^(2/3)``, and the wall carries ``g sum_{k=1..N-1} m_k``. The striker (bead 0)
arrives from above: it touches bead 1 with zero overlap and moves at the striker speed
(the speed after a drop from height ``h`` is ``sqrt(2 g h)``). Without gravity every
overlap is zero.
"""

from __future__ import annotations

import numpy as np

from ssw.chain.params import ChainParams
from ssw.chain.walls import Wall


def static_contact_forces(params: ChainParams) -> np.ndarray:
    """Static forces (N) of contacts 0..N-2 and the wall (last), shape (N,)."""
    m = params.masses
    if not params.gravity:
        return np.zeros(params.n_beads)
    w = params.g * np.cumsum(m[1:])  # contact j>=1 and the wall: weight of beads 1..j
    return np.concatenate([[0.0], w])


def initial_state(params: ChainParams, wall: Wall) -> tuple[np.ndarray, np.ndarray]:
    """Positions ``u`` (m) and velocities ``v`` (m/s), shapes (n_scenes, N)."""
    n, N = wall.n, params.n_beads
    F = static_contact_forces(params)
    u = np.zeros((n, N))
    v = np.zeros((n, N))
    v[:, 0] = params.striker_velocity
    if params.gravity:
        overlaps = (F[1:-1] / params.bead_coefficient) ** (2.0 / 3.0)  # contacts 1..N-2
        u_last = wall.indentation(np.full(n, F[-1]))
        # u_j = u_{N-1} + sum_{k=j..N-2} overlap_k for j = 1..N-2; u_0 = u_1
        above = np.concatenate([np.cumsum(overlaps[::-1])[::-1], [0.0]])  # beads 1..N-1
        u[:, 1:] = u_last[:, None] + above[None, :]
        u[:, 0] = u[:, 1]
    return u, v


def potential_energy(params: ChainParams, wall: Wall, u: np.ndarray) -> np.ndarray:
    """Elastic energy (J) of the contacts and the wall, minus gravity's, per scene (n,).

    Hertz: ``2/5 A d^(5/2)``; the wall: its ``potential``; gravity: ``-sum m g u``.
    """
    d = np.maximum(u[:, :-1] - u[:, 1:], 0.0)
    e = 0.4 * params.bead_coefficient * np.sum(d**2.5, axis=1) + wall.potential(u[:, -1])
    if params.gravity:
        e -= params.g * u @ params.masses
    return e


def kinetic_energy(params: ChainParams, v: np.ndarray) -> np.ndarray:
    """``sum m v^2 / 2`` (J) per scene."""
    return 0.5 * (v**2) @ params.masses
