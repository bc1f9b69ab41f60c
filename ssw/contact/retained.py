"""What the condensation of a geometry keeps: its retained dofs (:class:`Layout`), a body's
condensed operator at unit E (:class:`BodyOperator`), and the rigid sphere's gap at the
contact candidates (:func:`sphere_gap0`).

The operators are built and cached by :mod:`ssw.contact.operators`; a scene's contact
problem is assembled from them by :mod:`ssw.contact.coupling`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ssw.errors import SolverError


def sphere_gap0(r: np.ndarray, radius: float) -> np.ndarray:
    """Gap (m) at zero indentation between a sphere of ``radius`` and the flat at radius
    ``r``: ``R - sqrt(R^2 - r^2)`` written as ``r^2 / (R + sqrt(R^2 - r^2))`` (no
    cancellation at small ``r``: relative accuracy of a few ulp).

    Parameters
    ----------
    r : numpy.ndarray
        Radii (m), < ``radius``.
    radius : float
        Sphere radius (m).

    Returns
    -------
    numpy.ndarray
        Gaps (m).

    Raises
    ------
    SolverError
        If a radius is not below the sphere's.
    """
    r = np.asarray(r, float)
    if np.any(r >= radius):
        raise SolverError("contact candidate beyond the sphere's radius: shrink the zone")
    return r * r / (radius + np.sqrt((radius - r) * (radius + r)))


@dataclass(frozen=True)
class Layout:
    """The retained dofs of a geometry (what a scene's assembly needs of the mesh).

    ``r``, ``weight`` (n_c,): radius (m) and ``int N_j 2 pi r ds`` (m^2) of the contact
    candidates, sorted by radius; ``iface_r``, ``iface_comp`` (n_i,): node radius (m) and
    component (0 = u_r, 1 = u_z) of the retained interface dofs (empty without a plate);
    ``nodes``, ``elements``: the mesh's counts.

    Parameters
    ----------
    r : numpy.ndarray
        Radii of the contact candidates (m), (n_c,), sorted.
    weight : numpy.ndarray
        Their surface weights ``int N_j 2 pi r ds`` (m^2), (n_c,).
    iface_r : numpy.ndarray
        Radii of the retained interface dofs' nodes (m), (n_i,).
    iface_comp : numpy.ndarray
        Their components (0 = u_r, 1 = u_z), (n_i,).
    nodes : int
        Number of mesh nodes.
    elements : int
        Number of mesh elements.
    """

    r: np.ndarray
    weight: np.ndarray
    iface_r: np.ndarray
    iface_comp: np.ndarray
    nodes: int
    elements: int


@dataclass(frozen=True)
class BodyOperator:
    """A body's condensed stiffness ``S`` at unit E (m = N/m per Pa) and how it was made.

    Parameters
    ----------
    S : numpy.ndarray
        Condensed stiffness at unit E (m), (nb, nb).
    stats : dict
        How it was made (sizes, times in s).
    """

    S: np.ndarray
    stats: dict[str, Any] = field(default_factory=dict)
