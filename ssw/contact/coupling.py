"""A scene's condensed contact problem: the plate's and the soil's condensed operators
(:mod:`ssw.contact.operators`, unit E) coupled at the scene's moduli and condensed onto the
contact constraints, ``LCP(W, q0 + delta q1)`` (:class:`SceneLCP`, :func:`scene_lcp`).

Per interface law, the two bodies share the interface dofs (``frictionless``, ``bonded``:
a Schur complement onto the sphere's candidates), or only the one on the axis, the others
becoming a second set of contact constraints (``unilateral``: the plate may lift off;
:func:`coupled_stiffness`). The problems are kept in memory (:data:`SCENES_KEPT`): the
sphere's radius enters only their gaps, so one scene serves the fem wall's bead and the
elastic bead's equivalent sphere of the stresses (:mod:`ssw.contact.stress`).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from ssw.contact.retained import BodyOperator, Layout, sphere_gap0
from ssw.errors import SolverError


@dataclass(frozen=True)
class SceneLCP:
    """The condensed contact problem of one scene: ``LCP(W, q0 + delta q1)``.

    ``W`` (m, m) m/N; ``q0``, ``q1`` (m,) m and -; the first ``n_sphere`` constraints are
    the sphere candidates (radius ``r``, surface weight ``weight``), the rest the plate-soil
    pairs of an unilateral interface. ``tie`` (m,) or None: the force (N, + up) the plate
    pulls on the soil's axis node per unit constraint force (unilateral only; compression
    is ``tie . lam <= 0``). ``dofs``: unknowns of the dense system. ``dW_dE`` (m, m) m/N/Pa
    or None: ``dW/dE_soil`` (no plate: ``-W / E``; a frictionless or bonded plate:
    ``-W (dH/dE) W``, ``dH/dE = E_p^2 Y^T S Y`` of the Schur complement ``H``; None for the
    unilateral interface), for the law's derivative in E (:mod:`ssw.walls.fem`).

    Parameters
    ----------
    W : numpy.ndarray
        Compliance (m/N), (m, m).
    q0 : numpy.ndarray
        Gaps at zero indentation (m), (m,).
    q1 : numpy.ndarray
        Gap change per unit indentation, (m,).
    n_sphere : int
        Number of sphere candidates (the first constraints).
    r : numpy.ndarray
        Radii of the sphere candidates (m).
    weight : numpy.ndarray
        Their surface weights (m^2).
    tie : numpy.ndarray or None
        Force the plate pulls on the soil's axis node per unit constraint force (N), (m,); None
        unless unilateral.
    dofs : int
        Unknowns of the dense system.
    dW_dE : numpy.ndarray or None
        ``dW/dE_soil`` (m/N/Pa), (m, m), or None.
    """

    W: np.ndarray
    q0: np.ndarray
    q1: np.ndarray
    n_sphere: int
    r: np.ndarray
    weight: np.ndarray
    tie: np.ndarray | None
    dofs: int
    dW_dE: np.ndarray | None = None


def coupled_stiffness(
    plate_S: np.ndarray, soil_S: np.ndarray, plate_E: float, soil_E: float, layout: Any,
    nc: int, unilateral: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The condensed plate and soil assembled on their retained dofs: ``K`` (Pa m-scaled),
    the plate's dofs ``p_map`` (candidates, then interface) and the soil's ``s_map``
    (interface) in it, and ``off`` the interface nodes whose plate and soil dofs are two
    (``unilateral``: every node off the axis; else none, the interface is shared).

    Parameters
    ----------
    plate_S : numpy.ndarray
        Plate's condensed stiffness (unit E).
    soil_S : numpy.ndarray
        Soil's condensed stiffness (unit E).
    plate_E : float
        Plate's Young's modulus (Pa).
    soil_E : float
        Soil's Young's modulus (Pa).
    layout : Layout
        The retained dofs.
    nc : int
        Number of sphere candidates.
    unilateral : bool
        Whether the interface is unilateral.

    Returns
    -------
    K : numpy.ndarray
        Coupled stiffness.
    p_map : numpy.ndarray
        Plate dofs in ``K``.
    s_map : numpy.ndarray
        Soil dofs in ``K``.
    off : numpy.ndarray
        Interface nodes with two dofs.
    """
    ni = layout.iface_r.size
    p_map = np.arange(nc + ni)
    s_map = nc + np.arange(ni)
    off = np.zeros(0, dtype=np.int64)
    if unilateral:
        axis = layout.iface_r <= 1e-9 * layout.r[-1]
        off = np.flatnonzero(~axis)
        s_map = s_map.copy()
        s_map[off] = nc + ni + np.arange(off.size)
    n = int(max(p_map.max(), s_map.max())) + 1
    K = np.zeros((n, n))
    K[: nc + ni, : nc + ni] = plate_E * plate_S  # p_map: the leading dofs, in order
    if off.size:
        K[np.ix_(s_map, s_map)] += soil_E * soil_S
    else:  # s_map: the interface block, in order (slices: no index arrays)
        K[nc:nc + ni, nc:nc + ni] += soil_E * soil_S
    return K, p_map, s_map, off


#: Scenes' condensed problems kept in memory, least recently used out (:func:`scene_lcp`).
#: A plate design's batch builds the fem walls of all its candidates before their stresses
#: ask for the same scenes again (the thesis design's scan: 6 plates x 20 soils = 120
#: scenes; at 64 every one was condensed twice, 0.2 s); about 0.16 MB a scene (98 contact
#: candidates: ``W`` and ``dW_dE``), 40 MB at most.
SCENES_KEPT = 256
_SCENES: OrderedDict[tuple[Any, ...], tuple[SceneLCP, tuple[Any, ...]]] = OrderedDict()


def scene_lcp(layout: Layout, plate: BodyOperator | None, soil: BodyOperator,
              soil_E: float, plate_E: float | None, interface: str, radius: float) -> SceneLCP:
    """The condensed contact problem of a scene (``_condensed_scene``), kept in memory:
    the sphere's radius enters only its gaps ``q0``, so the same scene under another
    sphere (the fem wall's bead, then the elastic bead's equivalent sphere of the stresses,
    :mod:`ssw.contact.stress`) reuses its compliance. Its arrays are read-only.

    Parameters
    ----------
    layout : Layout
        The retained dofs of the geometry.
    plate : BodyOperator or None
        The plate's operator (unit E); None without a plate.
    soil : BodyOperator
        The soil's operator (unit E).
    soil_E : float
        The soil's Young's modulus, Pa.
    plate_E : float or None
        The plate's Young's modulus, Pa; None without a plate.
    interface : str
        ``frictionless`` | ``bonded`` | ``unilateral``.
    radius : float
        The rigid sphere's radius, m.

    Returns
    -------
    SceneLCP
        The scene's problem.
    """
    key = (id(layout), id(plate), id(soil), float(soil_E),
           None if plate_E is None else float(plate_E), interface)
    kept = _SCENES.get(key)
    # the objects themselves are kept with the entry: their ids cannot be reused meanwhile
    if kept is not None and all(a is b for a, b in zip(kept[1], (layout, plate, soil),
                                                       strict=True)):
        _SCENES.move_to_end(key)
        lcp = kept[0]
        q0 = lcp.q0.copy()
        q0[: lcp.n_sphere] = sphere_gap0(layout.r, radius)
        q0.flags.writeable = False
        return replace(lcp, q0=q0)
    lcp = _condensed_scene(layout, plate, soil, soil_E, plate_E, interface, radius)
    for name in ("W", "q0", "q1", "tie", "dW_dE"):
        x = getattr(lcp, name)
        if isinstance(x, np.ndarray):
            x.flags.writeable = False
    _SCENES[key] = (lcp, (layout, plate, soil))
    while len(_SCENES) > SCENES_KEPT:
        _SCENES.popitem(last=False)
    return lcp


def _condensed_scene(layout: Layout, plate: BodyOperator | None, soil: BodyOperator,
                    soil_E: float, plate_E: float | None, interface: str, radius: float
                    ) -> SceneLCP:
    """Assemble ``E_plate P + E_soil S`` and condense it onto the contact constraints
    (arguments as :func:`scene_lcp`)."""
    nc = layout.r.size
    q0s = sphere_gap0(layout.r, radius)
    if plate is None:
        K = soil_E * soil.S
        try:
            cf = cho_factor(K, lower=True, check_finite=False)
        except np.linalg.LinAlgError as exc:
            raise SolverError(f"the condensed soil stiffness is not positive definite: {exc}"
                              ) from exc
        W = cho_solve(cf, np.eye(nc), check_finite=False)
        W = 0.5 * (W + W.T)
        return SceneLCP(W, q0s, -np.ones(nc), nc, layout.r, layout.weight, None, nc,
                        -W / soil_E)
    ni = layout.iface_r.size
    unilateral = interface == "unilateral"
    if not unilateral:
        # the interface dofs are shared: eliminate them (a Schur complement onto the
        # candidates), H = E_p P_cc - E_p^2 P_ci (E_p P_ii + E_s S)^-1 P_ic, and W = H^-1
        P = plate.S
        M = plate_E * P[nc:, nc:] + soil_E * soil.S
        try:
            Y = cho_solve(cho_factor(M, lower=True, check_finite=False), P[nc:, :nc],
                          check_finite=False)
            H = plate_E * P[:nc, :nc] - plate_E**2 * (P[:nc, nc:] @ Y)
            W = cho_solve(cho_factor(0.5 * (H + H.T), lower=True, check_finite=False),
                          np.eye(nc), check_finite=False)
        except np.linalg.LinAlgError as exc:
            raise SolverError(f"the condensed plate-soil stiffness is not positive definite: "
                              f"{exc}") from exc
        W = 0.5 * (W + W.T)
        # dM/dE = S: dY = -M^-1 S Y, dH = -E_p^2 P_ci dY = E_p^2 Y^T S Y (P_ci = P_ic^T)
        dH = plate_E**2 * (Y.T @ (soil.S @ Y))
        dW = -W @ (0.5 * (dH + dH.T)) @ W
        return SceneLCP(W, q0s, -np.ones(nc), nc, layout.r, layout.weight, None, nc + ni,
                        0.5 * (dW + dW.T))
    K, _, s_map, off = coupled_stiffness(plate.S, soil.S, plate_E, soil_E, layout, nc,
                                         unilateral)
    n = K.shape[0]
    G = np.zeros((nc, n))
    G[np.arange(nc), np.arange(nc)] = -1.0
    q0, q1 = q0s, -np.ones(nc)
    if unilateral:
        Gi = np.zeros((off.size, n))
        Gi[np.arange(off.size), nc + off] = 1.0
        Gi[np.arange(off.size), s_map[off]] = -1.0
        G = np.vstack([G, Gi])
        q0 = np.concatenate([q0, np.zeros(off.size)])
        q1 = np.concatenate([q1, np.zeros(off.size)])
    try:
        cf = cho_factor(K, lower=True, check_finite=False)
    except np.linalg.LinAlgError as exc:
        raise SolverError(f"the condensed plate-soil stiffness is not positive definite: {exc}"
                          ) from exc
    X = cho_solve(cf, G.T, check_finite=False)
    W = G @ X
    tie = None
    if unilateral:
        a = np.setdiff1d(np.arange(ni), off)  # the interface nodes on the axis
        tie = (soil_E * soil.S[a] @ X[s_map]).sum(axis=0) if a.size else np.zeros(len(q0))
    return SceneLCP(0.5 * (W + W.T), q0, q1, nc, layout.r, layout.weight, tie, n)
