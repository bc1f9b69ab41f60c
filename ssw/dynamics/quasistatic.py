"""Quasi-static references of a dynamic scene: static FEMs of its contact in fixed boxes.

The dynamic mesh's own static law is not a reference: its truncation boundary (dashpots in
parallel with springs) is statically approximate (its springs were measured ~1 % soft for a
punch), while the dynamic window never sees it. The references are the same contact mesh in
the quasi-static FEM's fixed 1 m box (``ssw contact``: what the study's TOFs carry) and in a
3 m box; the half-space follows by extrapolation in ``1 / L``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.dynamics.fem_wall import ContactFEM, FEMWall

#: Fixed boxes (radius = depth, m) of the quasi-static references: the quasi-static FEM's
#: soil sample (1 m, ``ssw contact``) and a larger one; the half-space's law is extrapolated
#: from the two in ``1 / L`` (a box stiffens the contact by ``O(a / L)``; measured: the TOF
#: of 1, 3 and 10 m boxes follows ``1 / L`` to 1e-6).
STATIC_BOXES = (1.0, 3.0)
#: Largest element of the static boxes (m): the quasi-static FEM's default.
STATIC_SIZE_MAX = 0.1


def static_box(contact: ContactFEM, L: float) -> ContactFEM:
    """The scene of ``contact`` as a static-only problem in a fixed box of radius = depth
    ``L`` (m), with the same contact mesh settings and candidate zone.

    Parameters
    ----------
    contact : ContactFEM
        The dynamic scene.
    L : float
        Radius = depth of the box (m).

    Returns
    -------
    ContactFEM
        The static-only scene.
    """
    from dataclasses import replace

    spec = replace(contact.spec, domain=float(L), size_max=STATIC_SIZE_MAX)
    return ContactFEM(contact.scene, spec, None, float(contact.r[-1]) * (1.0 + 1e-9),
                      "fixed", d_scale=contact.d_scale)


#: Points of the static curve a table wall is built from.
CURVE_POINTS = 400


def static_curve(contact: ContactFEM, d_max: float, points: int = CURVE_POINTS
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The scene's quasi-static law on ``points`` equal indentations up to ``d_max``:
    ``(d, F)`` (m, N), the bead's indentation (its compliance included) and the force.

    Parameters
    ----------
    contact : ContactFEM
        The scene.
    d_max : float
        Largest indentation (m).
    points : int
        Number of points.

    Returns
    -------
    d : numpy.ndarray
        Indentations (m), (points,).
    F : numpy.ndarray
        Forces (N), (points,).
    """
    d = d_max * np.arange(1, points + 1) / points
    return d, contact.static_force(d)


def static_table_wall(params: Any, wall: FEMWall, d_max: np.ndarray) -> Any:
    """A `ssw.chain.wall.TableWall` of the scenes' static laws up to ``d_max`` (m):
    the quasi-static twin of the FEM wall for the chain's own integrator and for the
    reduced wall. The table wall rescales indentations by
    :func:`ssw.chain.wall_base.compliance_scale`; the curves, which already hold the bead's
    compliance, are handed over divided by it.

    Parameters
    ----------
    params : ChainParams
        The chain.
    wall : FEMWall
        The FEM wall.
    d_max : numpy.ndarray
        Largest indentation per scene (m), (n,).

    Returns
    -------
    TableWall
        The tabulated static laws.
    """
    from types import SimpleNamespace

    from ssw.chain.wall import compliance_scale, table_wall

    curves = []
    for c, dm in zip(wall.contacts, d_max, strict=True):
        d, F = static_curve(c, float(dm))
        s = float(compliance_scale(params, c.scene.soil.E, c.scene.soil.nu))
        curves.append(SimpleNamespace(delta=d / s, force=F))
    E = np.array([c.scene.soil.E for c in wall.contacts])
    nu = np.array([c.scene.soil.nu for c in wall.contacts])
    return table_wall(params, E, nu, curve=curves)
