"""Wall dynamics by name: what the chain stage's ``wall_dynamics`` option selects.

* ``quasi-static``: the wall itself (the static force-indentation law; every model so far);
* ``reduced``: :class:`ssw.dynamics.reduced.ReducedWall` around it (radiation damping and
  participating mass of the soil, the plate's inertia), needing the soil's density.

The dynamic FEM (``fem``) is not a wrapper of a wall but its own law and model: it runs
through :func:`ssw.dynamics.api.fem_tof`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ssw.errors import ConfigError

WALL_DYNAMICS = ("quasi-static", "reduced", "fem")


def _reduced(wall: Any, params: Any, soil_E: Any, soil_nu: Any, soil_density: Any) -> Any:
    from ssw.dynamics.reduced import plate_areal_density, reduced_wall

    if soil_density is None:
        raise ConfigError("soil_density", None,
                          "a density (kg/m^3) of the tested medium for the reduced wall")
    E, nu, rho = (np.ravel(x) for x in np.broadcast_arrays(
        np.asarray(soil_E, float), np.asarray(soil_nu, float),
        np.asarray(soil_density, float)))
    return reduced_wall(wall, E, nu, rho, plate_areal_density=plate_areal_density(params))


#: Registry: name -> wrapper(wall, params, soil_E, soil_nu, soil_density) -> wall.
WRAPPERS: dict[str, Callable[..., Any]] = {
    "quasi-static": lambda wall, *args: wall,
    "reduced": _reduced,
}


def with_dynamics(name: str, wall: Any, params: Any, soil_E: Any, soil_nu: Any,
                  soil_density: Any = None) -> Any:
    """The wall ``wall`` (one law per scene) with the dynamics ``name`` of :data:`WRAPPERS`
    (``fem`` is :func:`ssw.dynamics.api.fem_tof`, not a wrapper).

    Parameters
    ----------
    name : str
        The dynamics' registry name.
    wall : Wall
        The quasi-static wall.
    params : ChainParams
        The chain.
    soil_E : array_like
        Soil Young's modulus (Pa).
    soil_nu : array_like
        Soil Poisson's ratio.
    soil_density : array_like or None
        Soil density (kg/m^3).

    Returns
    -------
    Any
        The wrapped wall.

    Raises
    ------
    ConfigError
        If ``name`` is not a wrapper.
    """
    if name not in WRAPPERS:
        allowed = " | ".join(WRAPPERS) + (" (fem: ssw.dynamics.api.fem_tof)"
                                          if name == "fem" else "")
        raise ConfigError("wall_dynamics", name, allowed)
    return WRAPPERS[name](wall, params, soil_E, soil_nu, soil_density)
