"""How close a measurement's contact came to yielding the sample: the Hertz peak pressure
over the sample's strength, and whether von Mises yield started below the surface.

With the peak contact force ``F`` of a hit (N), the bead's radius ``R`` (m) and the sample's
``E*`` = ``E / (1 - nu^2)`` (rigid bead), Hertz's peak pressure is
``p0 = (6 F E*^2 / (pi^3 R^2))^(1/3)`` (Johnson 1985, eq. 4.23); the yield index is
``p0 / strength`` (the strength a material's library entry states: compressive for foams,
the yield stress for metals, the unconfined compressive strength of a soil). A von Mises
half-space first yields below the surface at ``p0 = k(nu) Y`` (``k`` = 1.61 at nu 0.3,
Johnson 1985, sec. 6.1; :func:`first_yield_ratio`): the index compares pressures,
``first_yield`` applies the yield criterion.

References
----------
Johnson, K. L. (1985). *Contact Mechanics*. Cambridge, sec. 4.2 and 6.1.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def hertz_peak_pressure(force: np.ndarray, E: Any, nu: Any, radius: float) -> np.ndarray:
    """``p0 = (6 F E*^2 / (pi^3 R^2))^(1/3)`` (Pa) of forces ``F`` (N) on a half-space of
    ``E`` (Pa), ``nu`` (scalars, or arrays broadcast with ``F``) under a rigid sphere of
    ``radius`` (m).

    Parameters
    ----------
    force : numpy.ndarray
        Peak contact forces ``F`` (N).
    E : Any
        Young's modulus of the half-space (Pa).
    nu : Any
        Poisson's ratio of the half-space.
    radius : float
        Radius of the rigid sphere (m).

    Returns
    -------
    numpy.ndarray
        Peak pressure ``p0`` (Pa).

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, sec. 4.2.
    """
    Es = np.asarray(E, float) / (1.0 - np.asarray(nu, float) ** 2)
    F = np.asarray(force, float)
    return np.cbrt(6.0 * F * Es * Es / (np.pi ** 3 * float(radius) ** 2))


def first_yield_ratio(nu: float) -> float:
    """``k = p0 / Y`` at first von Mises yield under a sphere (1.61 at nu 0.3): the peak of
    ``(sigma_r - sigma_z) / p0`` on the axis (Johnson 1985, sec. 6.1), inverted.

    Parameters
    ----------
    nu : float
        Poisson's ratio of the half-space.

    Returns
    -------
    float
        ``k = p0 / Y`` at first yield.

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, sec. 6.1.
    """
    z = np.linspace(1e-4, 3.0, 30001)
    sz = -1.0 / (1.0 + z * z)
    sr = -((1.0 + nu) * (1.0 - z * np.arctan(1.0 / z)) - 0.5 / (1.0 + z * z))
    return 1.0 / float(np.max(sr - sz))


def yield_index(force: np.ndarray, E: float, nu: float, radius: float,
                strength: float) -> dict[str, np.ndarray]:
    """``{"p0": Pa, "index": p0 / strength, "first_yield": p0 > k(nu) strength}`` of peak
    forces ``F`` (N): the index and whether a von Mises sample of yield stress ``strength``
    has started to yield (the measurement then carries more than E).

    Parameters
    ----------
    force : numpy.ndarray
        Peak contact forces ``F`` (N).
    E : float
        Young's modulus of the sample (Pa).
    nu : float
        Poisson's ratio of the sample.
    radius : float
        Radius of the bead (m).
    strength : float
        The sample's strength (Pa).

    Returns
    -------
    dict
        ``p0`` (Pa), ``index`` and ``first_yield`` (bool), arrays the shape of ``force``.

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, sec. 4.2 and 6.1.
    """
    p0 = hertz_peak_pressure(force, E, nu, radius)
    return {"p0": p0, "index": p0 / float(strength),
            "first_yield": p0 > first_yield_ratio(nu) * float(strength)}
