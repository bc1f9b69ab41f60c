"""Every last-contact law by name, above the chain, the contact FEM, the fits and the
soil's dynamics.

The chain integrates against the :class:`ssw.chain.wall.Wall` protocol; this layer builds
the walls. The registry :data:`WALLS` maps a name to a builder
``builder(params, soil_E, soil_nu, **options) -> Wall``:

* ``rigid``, ``hertz`` (:mod:`ssw.chain.wall_power`), ``table`` (:mod:`ssw.chain.wall_table`):
  laws made of the chain's numbers and, for ``table``, FEM curves;
* ``fit`` (:mod:`ssw.chain.wall_power`'s modified Hertz or power law), with ``k_table=`` a K table
  file of the fit stage (:class:`ssw.fit.table.KTable`, read once per file version) or
  explicit ``K=`` / ``power=(C, n)`` values;
* ``fem`` (:mod:`ssw.walls.fem`): the exact FEM law, computed on demand;
* ``plastic`` (:mod:`ssw.walls.plastic`): a plastic sample's loading and unloading curves,
  history-dependent (a stateful wall; ``soil_model=`` a model of :mod:`ssw.constitutive`).

:func:`build_wall` adds the tested medium's inertia when asked (:mod:`ssw.dynamics`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ssw.chain.params import ChainParams
from ssw.chain.wall import (
    Wall,
    fit_wall,
    hertz_wall,
    rigid_wall,
    scene_arrays,
    table_wall,
)
from ssw.errors import ConfigError, SswError


def load_k_table(k_table: Any, params: ChainParams) -> Any:
    """The K table of the chain's plate. Reads are remembered per file version (path, size,
    mtime), so a calibration or an inverse that builds the wall many times reads the file
    once.

    Parameters
    ----------
    k_table : str or KTable
        A table (has ``.K``: returned as it is) or the path of an HDF5 K table file.
    params : ChainParams
        The chain (its plate's material and thickness: the table's group).

    Returns
    -------
    KTable
        The table.

    Raises
    ------
    ConfigError
        No such file.
    """
    if hasattr(k_table, "K"):
        return k_table
    p = Path(k_table)
    if not p.is_file():
        raise ConfigError("--k-table", str(p), "an existing K table (results/fit/k_table.h5)")
    st = p.stat()
    return _read_k_table(str(p.resolve()), st.st_size, st.st_mtime_ns,
                         params.plate_material, float(params.plate_thickness))


@functools.lru_cache(maxsize=8)
def _read_k_table(path: str, size: int, mtime_ns: int, plate_material: str,
                  plate_thickness: float) -> Any:
    try:
        from ssw.fit.table import KTable
    except ImportError as exc:  # the fit stage is not installed
        raise SswError(f"ssw.fit.table.KTable is not available to read {path}: {exc}") from exc
    return KTable.load(path, plate_material, plate_thickness)


def file_fit_wall(params: ChainParams, soil_E: Any, soil_nu: Any, *, k_table: Any = None,
                  **values: Any) -> Wall:
    """:func:`ssw.chain.wall_power.fit_wall` with a K table file read here.

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.
    k_table : str or KTable or None
        A K table file or object (its interpolant's derivatives give the law's
        E-dependence).
    **values
        Explicit ``K=`` or ``power=(C, n)`` instead.

    Returns
    -------
    Wall
        A :class:`ssw.chain.wall_power.PowerWall`.
    """
    table = None if k_table is None else load_k_table(k_table, params)
    return fit_wall(params, soil_E, soil_nu, k_table=table, **values)


def fem_wall(params: ChainParams, soil_E: Any, soil_nu: Any, **options: Any) -> Wall:
    """The FEM law itself, computed on demand: :func:`ssw.walls.fem.fem_wall`.

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.
    **options
        ``contact``, ``operators``, ``with_dE`` (the law's exact dF/dE).

    Returns
    -------
    Wall
        A :class:`ssw.walls.fem.PiecewiseLinearWall`.
    """
    from ssw.walls.fem import fem_wall as build

    return build(params, soil_E, soil_nu, **options)


def plastic_wall(params: ChainParams, soil_E: Any, soil_nu: Any, **options: Any) -> Wall:
    """The history-dependent wall of a plastic sample: :func:`ssw.walls.plastic.plastic_wall`.

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.
    **options
        ``soil_model`` (a model of :mod:`ssw.constitutive`, or one per scene), ``settings``.

    Returns
    -------
    Wall
        A :class:`ssw.walls.plastic.PlasticWall` (a stateful wall: its TOF's derivatives are
        central differences).
    """
    from ssw.walls.plastic import plastic_wall as build

    return build(params, soil_E, soil_nu, **options)


#: Registry: wall name -> ``builder(params, soil_E, soil_nu, **options)``.
WALLS: dict[str, Callable[..., Wall]] = {
    "rigid": rigid_wall,
    "hertz": hertz_wall,
    "fit": file_fit_wall,
    "table": table_wall,
    "fem": fem_wall,
    "plastic": plastic_wall,
}


def build_wall(name: str, params: ChainParams, soil_E: Any, soil_nu: Any, **options: Any) -> Wall:
    """The wall ``name`` of :data:`WALLS` for the scenes ``broadcast(soil_E, soil_nu)``.

    Parameters
    ----------
    name : str
        A name of :data:`WALLS`.
    params : ChainParams
        The chain.
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.
    **options
        The builder's keywords, and two of every law that add the tested medium's inertia
        (:mod:`ssw.dynamics`): ``dynamics`` (``quasi-static``, the default: the static law;
        ``reduced``: the law plus the soil's radiation damping and participating mass and
        the plate's inertia, :class:`ssw.dynamics.reduced.ReducedWall`) and
        ``soil_density`` (kg/m^3, broadcast with the scenes).

    Returns
    -------
    Wall
        One law per scene (a stateful wall for ``reduced`` dynamics and ``plastic``).

    Raises
    ------
    ConfigError
        An unknown wall, options a law does not take, dynamics for the plastic wall.
    """
    dynamics = options.pop("dynamics", "quasi-static") or "quasi-static"
    density = options.pop("soil_density", None)
    if name not in WALLS:
        raise ConfigError("wall", name, f"one of {', '.join(WALLS)}")
    if name in ("rigid", "hertz") and options:
        raise ConfigError("wall options", sorted(options), f"none for the {name} wall")
    if name == "plastic" and dynamics != "quasi-static":
        raise ConfigError("dynamics", dynamics, "quasi-static for the plastic wall")
    w = WALLS[name](params, soil_E, soil_nu, **options)
    if dynamics != "quasi-static":
        from ssw.dynamics.registry import with_dynamics

        E, nu = scene_arrays(soil_E, soil_nu)
        rho = None if density is None else np.broadcast_to(
            np.asarray(density, float).ravel() if np.ndim(density) else float(density),
            E.shape)
        w = with_dynamics(dynamics, w, params, E, nu, rho)
    return w
