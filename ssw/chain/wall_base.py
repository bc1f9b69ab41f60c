"""What every last-contact law made of the chain's numbers shares: the scenes' soil arrays,
the bead's compliance added to a rigid-sphere law, and the inverse of a monotone law.

Bead compliance. The thesis's K and the FEM curves come from a *rigid* sphere, law
``F_R(d)``. The chain's bead is steel, so we add its compliance the way Hertz does
(``1/E* = c_w + c_b``, ``c = (1-nu^2)/E``): ``F(d) = F_R(d / s)`` with
``s = (1 + c_b/c_w)^(2/3)`` (:func:`compliance_scale`). This is exact for a Hertz-shaped
``F_R`` and turns the rigid-sphere law ``K 4/3 E_w/(1-nu_w^2) sqrt(R) d^1.5`` into exactly
the thesis's ``K A_w d^1.5``; for the plate's non-Hertzian curves it is an approximation of
relative size ``c_b/c_w`` (2e-4 at 38 MPa, 5e-3 at 1000 MPa).

The laws themselves: :mod:`ssw.chain.wall_power` (rigid, Hertz, the fitted laws) and
:mod:`ssw.chain.wall_table` (a FEM curve interpolated); the protocol the chain integrates
against: :mod:`ssw.chain.wall`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.chain.params import ChainParams
from ssw.errors import ConfigError
from ssw.roots import find_root


def force_indentation(force: Any, F: Any, start: np.ndarray) -> np.ndarray:
    """Indentations (m) at which the non-decreasing laws ``force(d)`` carry ``F``.

    The bracket ``[0, start]`` is grown until it holds ``F``, then the roots are found by
    :func:`ssw.roots.find_root` to its default relative tolerance (a few ulp), vectorized
    over the scenes.

    Parameters
    ----------
    force : callable
        ``force(d) -> F``: the laws' forces (N) at the indentations ``d`` (m), one per
        scene.
    F : array_like
        Forces to carry (N), one per scene; a negative one is read as 0.
    start : array_like
        First upper end of each bracket (m, > 0).

    Returns
    -------
    ndarray
        Indentations (m), the broadcast shape of ``start`` and ``F``.
    """
    hi, target = np.broadcast_arrays(np.asarray(start, float), np.asarray(F, float))
    target = np.maximum(target, 0.0)
    return find_root(lambda d: force(d) - target, np.zeros(hi.shape), hi, grow=True).x



def compliance_scale(params: ChainParams, soil_E: np.ndarray, soil_nu: np.ndarray) -> np.ndarray:
    """``s = (1 + c_b/c_w)^(2/3)``: rigid-sphere law ``F_R(d)`` -> steel bead ``F_R(d/s)``.

    Parameters
    ----------
    params : ChainParams
        The chain (its bead's compliance ``c_b``).
    soil_E : numpy.ndarray
        Pa.
    soil_nu : numpy.ndarray
        -.

    Returns
    -------
    numpy.ndarray
        -, broadcast.
    """
    c_w = (1.0 - np.asarray(soil_nu, float) ** 2) / np.asarray(soil_E, float)
    return (1.0 + params.bead_compliance / c_w) ** (2.0 / 3.0)


def compliance_scale_dE(params: ChainParams, soil_E: np.ndarray, soil_nu: np.ndarray
                        ) -> np.ndarray:
    """``ds/dE`` of :func:`compliance_scale`: with ``x = c_b E / (1 - nu^2)``,
    ``s = (1 + x)^(2/3)`` and ``ds/dE = 2/3 (1 + x)^(-1/3) c_b / (1 - nu^2)``.

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : numpy.ndarray
        Pa.
    soil_nu : numpy.ndarray
        -.

    Returns
    -------
    numpy.ndarray
        1/Pa, broadcast.
    """
    k = params.bead_compliance / (1.0 - np.asarray(soil_nu, float) ** 2)
    return 2.0 / 3.0 * (1.0 + k * np.asarray(soil_E, float)) ** (-1.0 / 3.0) * k


def scene_arrays(soil_E: Any, soil_nu: Any) -> tuple[np.ndarray, np.ndarray]:
    """Soil moduli and Poisson's ratios broadcast together and flattened, one per scene.

    Parameters
    ----------
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.

    Returns
    -------
    tuple of numpy.ndarray
        (n,) Pa and (n,) -.

    Raises
    ------
    ConfigError
        E <= 0 or nu outside (-1, 0.5].
    """
    E, nu = np.broadcast_arrays(np.asarray(soil_E, float), np.asarray(soil_nu, float))
    E, nu = E.ravel(), nu.ravel()
    if np.any(~(E > 0)):
        raise ConfigError("soil_E", E[~(E > 0)].tolist(), "moduli > 0 Pa")
    if np.any((nu <= -1) | (nu > 0.5)):
        raise ConfigError("soil_nu", nu.tolist(), "Poisson's ratios in (-1, 0.5]")
    return E, nu
