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
The contacts' dissipation (any law of :mod:`ssw.chain.dissipation`) acts on moving contacts
only: the chain at rest, and its derivative with respect to the dissipation coefficient
(zero), do not depend on it, nor on the time step.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.chain.params import Batch, ChainParams
from ssw.chain.sensitivity import Tangent
from ssw.chain.wall import Wall


def _batch(params: ChainParams | Batch, n: int) -> Batch:
    return params if isinstance(params, Batch) else Batch.of(params, n)


def static_contact_forces(params: ChainParams | Batch) -> np.ndarray:
    """Static forces of contacts 0..N-2 and the wall (last).

    Parameters
    ----------
    params : ChainParams or Batch
        The chain.

    Returns
    -------
    numpy.ndarray
        N, (N,) for a ChainParams, (n, N) for a Batch of ``n`` scenes.
    """
    b = _batch(params, 1)
    g = b.params.g if b.params.gravity else 0.0
    w = b.preload[:, None] + g * np.cumsum(b.masses[:, 1:], axis=1)  # contacts 1.. and wall
    F = np.concatenate([np.zeros((b.n, 1)), w], axis=1)
    return F[0] if isinstance(params, ChainParams) else F


def initial_state(params: ChainParams | Batch, wall: Wall) -> tuple[np.ndarray, np.ndarray]:
    """The chain at rest on the wall, the striker touching bead 1 at its speed.

    Parameters
    ----------
    params : ChainParams or Batch
        The chain.
    wall : Wall
        The last contact (its static ``indentation``).

    Returns
    -------
    tuple of numpy.ndarray
        Positions ``u`` (m) and velocities ``v`` (m/s), shapes (n_scenes, N).
    """
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


def initial_tangent(params: ChainParams | Batch, wall: Any, u: np.ndarray, tangent: Tangent
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Derivatives of the initial state (:func:`initial_state`) with respect to the
    parameters of ``tangent``.

    The static forces ``F_j = P + g sum_{k=1..j} m_k`` (wall: ``j = N - 1``) move with the
    preload ``P`` and the sensor's mass; each overlap ``(F_j / A)^(2/3)`` with them
    (``dd = 2/3 d dF / F``); the wall's indentation ``u_{N-1}`` solves
    ``F_wall(u_{N-1}; E) = F_{N-1}``, so ``du = (dF_{N-1} - dF_wall/dE dE) / F_wall'``
    (implicit differentiation of the statics); ``u_j = u_{N-1} + sum_{k >= j} d_k``. The
    striker's speed is ``striker_velocity``. A chain at rest without load (no gravity, no
    preload) has no finite derivative with respect to the preload at 0 N (the overlaps
    grow as ``P^(2/3)``): NaN.

    Parameters
    ----------
    params : ChainParams or Batch
        The chain (per-scene masses and preloads for a Batch).
    wall : Wall
        The last contact (its ``dforce_dd`` and, for ``E``, ``dforce_dE``).
    u : numpy.ndarray
        (n, N) m, the initial positions (:func:`initial_state`).
    tangent : Tangent
        The parameters.

    Returns
    -------
    tuple of numpy.ndarray
        ``(U, V)``: (N, n, k) m and m/s per unit of each parameter.
    """
    n = u.shape[0]
    b = _batch(params, n)
    p = b.params
    N, k = p.n_beads, tangent.k
    g = p.g if p.gravity else 0.0
    dF = np.zeros((N, n, k))  # contacts 0..N-2 and the wall (N - 1)
    if (c := tangent.col("preload")) is not None:
        dF[1:, :, c] = 1.0
    if (c := tangent.col("sensor_mass")) is not None and not p.uniform:
        dF[p.sensor_index:, :, c] = g
    F = static_contact_forces(b).T  # (N, n)
    U = np.zeros((N, n, k))
    V = np.zeros((N, n, k))
    with np.errstate(divide="ignore", invalid="ignore"):
        d = (F[1:-1] / p.bead_coefficient) ** (2.0 / 3.0)  # contacts 1..N-2
        dd = np.where(F[1:-1, :, None] > 0, 2.0 / 3.0 * (d / F[1:-1])[:, :, None], np.nan
                      ) * dF[1:-1]
        dd = np.where(dF[1:-1] == 0.0, 0.0, dd)
        stiff = wall.dforce_dd(u[:, -1])
        rhs = dF[-1].copy()
        if (c := tangent.col("E")) is not None:
            rhs[:, c] -= wall.dforce_dE(u[:, -1])
        du_last = np.where(rhs == 0.0, 0.0, rhs / stiff[:, None])
    # u_j = u_{N-1} + sum_{k=j..N-2} d_k (j = 1..N-2); u_0 = u_1
    U[1:-1] = du_last[None] + np.cumsum(dd[::-1], axis=0)[::-1]
    U[-1] = du_last
    U[0] = U[1]
    if (c := tangent.col("striker_velocity")) is not None:
        V[0, :, c] = 1.0
    return U, V


def potential_energy(params: ChainParams | Batch, wall: Wall | None, u: np.ndarray
                     ) -> np.ndarray:
    """Elastic energy (J) of the contacts and the wall minus the work potential of gravity
    and the preload, per scene (n,): Hertz ``2/5 A d^(5/2)``, the wall's ``potential``,
    ``- g sum m_i u_i - P u_1``.

    Parameters
    ----------
    params : ChainParams or Batch
        The chain.
    wall : Wall or None
        The last contact; None leaves its energy out (a stateful wall reports its own).
    u : numpy.ndarray
        (n, N) m, positions.

    Returns
    -------
    numpy.ndarray
        (n,) J.
    """
    b = _batch(params, u.shape[0])
    p = b.params
    d = np.maximum(u[:, :-1] - u[:, 1:], 0.0)
    e = 0.4 * p.bead_coefficient * np.sum(d**2.5, axis=1)
    if wall is not None:
        e = e + wall.potential(u[:, -1])
    if p.gravity:
        e -= p.g * np.sum(u * b.masses, axis=1)
    return e - b.preload * u[:, 1]


def kinetic_energy(params: ChainParams | Batch, v: np.ndarray) -> np.ndarray:
    """Kinetic energy ``sum m v^2 / 2`` per scene.

    Parameters
    ----------
    params : ChainParams or Batch
        The chain (its masses).
    v : numpy.ndarray
        (n, N) m/s.

    Returns
    -------
    numpy.ndarray
        (n,) J.
    """
    b = _batch(params, v.shape[0])
    return 0.5 * np.sum(v**2 * b.masses, axis=1)
