"""The ``plastic`` wall: a history-dependent last contact on an elasto-plastic sample.

The law of a rigid sphere of the bead's radius on the sample (:mod:`ssw.contact.plastic`,
any model of :mod:`ssw.constitutive`; through the chain's elastic plate when it has one) is
tabulated on demand, once per scene and kept in memory:

* the virgin loading curve ``F_L(d)`` to the reach ``d_top`` (one loading path);
* unloading curves from ``K`` maximum indentations ``d_m`` spread evenly between the first
  yield indentation ``d_e`` and ``d_top`` (one loading-unloading path each), each with its
  residual indentation ``d_res(d_m)``.

State: per scene the largest indentation reached, ``d_max``. Force at an indentation ``d``::

    d >= d_max:            F = F_L(d)                                  (virgin loading)
    d_res < d < d_max:     F = F_L(d_max) f(xi; d_max),  xi = (d - d_res) / (d_max - d_res)
    d <= d_res:            F = 0

with ``f(0) = 0`` and ``f(1) = 1``, so the force is continuous at ``d_max`` and vanishes at
``d_res``. Below ``d_e`` the sample is elastic: ``F = F_L(d)`` both ways. Reloading below
``d_max`` follows the unloading curve of ``d_max`` (elastic reloading): the material
that yielded on loading unloads and reloads elastically as long as the load stays below the
largest one it carried (Melan's shakedown; for the sphere, Johnson 1985 sec. 6.2 and
Stronge 2000 ch. 4); the contact models of the discrete element method take the same
branch (Thornton 1997; Li, Wu & Thornton 2002). Reverse yielding on unloading, which the
FEM includes in its unloading curves, does not change the reloading path in that model.

Interpolation between levels. Thornton's unloading law, ``F = 4/3 E* sqrt(R_p)
(d - d_res)^{3/2}`` with a flattened radius ``R_p`` fixed by continuity at ``d_max``, is
``F_L(d_max) xi^{3/2}`` in the normalized variable ``xi``: the same shape at every level. The
FEM's shapes ``f_k(xi)`` are close to that (PCF 08: within 0.04 of ``xi^{3/2}`` as von
Mises, 0.06 as the crushable foam, while ``d_res / d_m`` grows from 0.1 to 0.45 and from 0.4
to 0.73 over the levels), so ``f`` and ``d_res`` are interpolated linearly
in ``d_max`` between the two neighbouring levels (exact for a self-similar family); the
lowest level is ``d_e`` itself (``d_res = 0``, ``f`` the loading curve's own shape).
Above the last level its shape and ``d_res / d_m`` are kept (beyond ``exact_reach``).

Energy. The work the chain does on the wall is a state function: ``stored(d, d_max) =
F_L(d_max) (d_max - d_res) int_0^xi f`` (released on unloading) and ``dissipated(d_max) =
W_L(d_max) - stored(d_max, d_max)``, ``W_L = int_0^d F_L`` (the loop's area: plastic work
plus the elastic energy locked in the residual stresses, both lost to the chain). Both
integrals are exact for the piecewise linear tables, so the chain's energy balance closes
to the integrator's error.

Bead compliance: as for the other FEM walls, ``F(d) = F_R(d / s)`` with
:func:`ssw.chain.wall_base.compliance_scale` (exact for Hertz; for the plastic branches a
first-order correction, ``s - 1 < 1e-3`` on soils and foams below 200 MPa).

Cost: a loading path and ``K`` loading-unloading paths on a mesh scaled to the contact
radius at ``d_top`` (element ``a / fine`` under the sphere, growth ``growth``): 6-7 s for
PCF 08's 11 paths at the default 10 levels x 12 increments, one core. An unloading curve
interpolated between two levels matches a fresh FEM path (tests/test_plastic_wall.py).

References
----------
Johnson, K. L. (1985). *Contact Mechanics*. Cambridge, ch. 6.
Li, L.-Y., Wu, C.-Y. & Thornton, C. (2002). A theoretical model for the contact of
elastoplastic bodies. *Proc. IMechE C* 216, 421-431.
Stronge, W. J. (2000). *Impact Mechanics*. Cambridge, ch. 4-5.
Thornton, C. (1997). Coefficient of restitution for collinear collisions of elastic-perfectly
plastic spheres. *J. Appl. Mech.* 64, 383-386.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ssw.chain.params import ChainParams
from ssw.chain.wall import compliance_scale, force_indentation, scene_arrays
from ssw.contact.plastic import ContactZoneError
from ssw.errors import ConfigError

#: Cells of the virgin curve's uniform table and of the normalized unloading shapes.
VIRGIN_CELLS, SHAPE_CELLS = 512, 64
#: Energy the virgin curve must hold up to ``d_top``, as a multiple of the energy of one
#: hit (striker kinetic energy plus the chain's weight and preload over ``d_top``).
ENERGY_MARGIN = 3.0


@dataclass(frozen=True)
class Settings:
    """FEM settings of the tables: ``levels`` unloading curves, ``increments`` per path
    (loading: ``2 x``), mesh: element ``a / fine`` under the sphere, ``growth``, domain
    ``domain x a`` (``a`` the contact radius at the reach).

    Parameters
    ----------
    levels : int
        Number of unloading curves.
    increments : int
        Increments per path (loading: twice).
    fine : float
        Element size under the sphere is ``a / fine``.
    growth : float
        Element size growth rate.
    domain : float
        Domain size in units of ``a`` (the contact radius at the reach).
    """

    levels: int = 10
    increments: int = 12
    fine: float = 8.0
    growth: float = 0.3
    domain: float = 40.0


@dataclass(frozen=True)
class Tables:
    """One scene's tables, rigid sphere (SI): virgin ``F`` on ``d = h k``, its cumulative
    work ``W``; levels ``d_m`` (level 0 = ``d_e``), ``d_res``, shapes ``f`` and their
    cumulative integrals ``S`` on ``xi = k / SHAPE_CELLS``; ``elastic``: never yielded;
    ``d_res_interface`` the plate-sample interface's residual depth on the axis per level
    (``d_res`` less the plate's permanent thinning; without a plate ``d_res``).

    Parameters
    ----------
    h : float
        Virgin table step (m).
    F : numpy.ndarray
        Virgin force on ``d = h k`` (N).
    W : numpy.ndarray
        Its cumulative work (J).
    d_m : numpy.ndarray
        Level indentations (m); level 0 is ``d_e``.
    d_res : numpy.ndarray
        Residual indentations per level (m).
    f : numpy.ndarray
        Unloading shapes on ``xi = k / SHAPE_CELLS``.
    S : numpy.ndarray
        Their cumulative integrals.
    elastic : bool
        Whether the sample never yielded.
    stats : dict
        Solver statistics.
    d_res_interface : numpy.ndarray or None
        The plate-sample interface's residual depth per level (m); None: ``d_res``.
    """

    h: float
    F: np.ndarray
    W: np.ndarray
    d_m: np.ndarray
    d_res: np.ndarray
    f: np.ndarray
    S: np.ndarray
    elastic: bool
    stats: dict
    d_res_interface: np.ndarray | None = None


def _cumulative(y: np.ndarray, step: float) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * step)])


def _shape_of(delta: np.ndarray, force: np.ndarray, d_m: float, f_m: float, d_res: float
              ) -> np.ndarray:
    """The unloading branch ``(delta, force)`` from ``(d_m, f_m)`` to ``d_res``, normalized
    and resampled on the ``xi`` grid: nondecreasing, ``f(0) = 0``, ``f(1) = 1``."""
    xi = (np.concatenate([[d_m], delta, [d_res]]) - d_res) / (d_m - d_res)
    fn = np.concatenate([[1.0], force / f_m, [0.0]])
    order = np.argsort(xi, kind="stable")
    xi, fn = np.clip(xi[order], 0.0, 1.0), np.clip(fn[order], 0.0, 1.0)
    grid = np.linspace(0.0, 1.0, SHAPE_CELLS + 1)
    f = np.maximum.accumulate(np.interp(grid, xi, fn))
    f[0], f[-1] = 0.0, 1.0
    return f


@functools.lru_cache(maxsize=32)
def tables(E: float, nu: float, model: Any, radius: float, d_top: float,
           settings: Settings = Settings(), plate: tuple | None = None) -> Tables:
    """The tables of one scene (module docstring), computed once per argument set.

    ``model``: the sample's (None: elastic). ``plate``: None (the sphere on the sample), or
    ``(E Pa, nu, thickness m, radius m, interface, model)`` of a plate between them (its
    model None: elastic; :func:`ssw.contact.plastic.contact_mesh` meshes it).

    Parameters
    ----------
    E : float
        Sample's Young's modulus (Pa).
    nu : float
        Sample's Poisson's ratio.
    model : Any
        The sample's constitutive model; None: elastic.
    radius : float
        Radius of the rigid sphere (m).
    d_top : float
        Deepest indentation of the tables (m).
    settings : Settings
        The contact FEM's settings.
    plate : tuple or None
        The plate ``(E, nu, thickness, radius, interface, model)`` (Pa, -, m, m); None:
        none.

    Returns
    -------
    Tables
        The scene's loading and unloading tables (SI).
    """
    import time

    from ssw.contact.plastic import contact_mesh, plate_contact_radius, solve_path

    t0 = time.perf_counter()
    Ep, nup, t, rp, interface, plate_model = plate if plate is not None else (
        0, 0, 0.0, 0.0, "frictionless", None)
    a_c = None  # a yielding plate: its own contact resolved (plate_contact_radius)
    if plate_model is not None:
        a_c = plate_contact_radius(radius, d_top, (E, nu), (Ep, nup))
    mesh = contact_mesh(radius, d_top, fine=settings.fine, growth=settings.growth,
                        domain=settings.domain, plate_thickness=t, plate_radius=rp,
                        contact_radius=a_c)
    elastic_plate = None if plate is None else (float(Ep), float(nup))
    n_load = 2 * settings.increments
    # uniform steps, and below the first one 6 halvings (the law of a plate on the sample
    # is not Hertz's at small indentations: the table must not extrapolate F / d^1.5 there)
    first = d_top / n_load
    steps = np.concatenate([first * 0.5 ** np.arange(6, 0, -1),
                            d_top * np.arange(1, n_load + 1) / n_load])
    load = solve_path(mesh, E, nu, model, radius, steps, plate=elastic_plate,
                      interface=interface, plate_model=plate_model)
    h = d_top / VIRGIN_CELLS
    grid = h * np.arange(VIRGIN_CELLS + 1)
    d, F = load.delta, load.force
    g = np.interp(grid[1:], d, F / d**1.5)  # F / d^1.5 interpolated: Hertz-exact near 0
    Fv = np.concatenate([[0.0], g * grid[1:] ** 1.5])
    Fv = np.maximum.accumulate(Fv)
    W = _cumulative(Fv, h)
    elastic = load.dissipated_work <= 0.0
    # the near zone that held the loading path's plastic zone holds the shallower paths'
    near = load.stats["near_radius"]
    xi = np.linspace(0.0, 1.0, SHAPE_CELLS + 1)
    paths = 1
    if elastic:
        d_m, d_res = np.array([np.inf]), np.zeros(1)
        d_res_interface = np.zeros(1)
        f = np.zeros((1, SHAPE_CELLS + 1))
    else:
        d_e = load.first_yield_delta or float(d[0])
        d_e = min(d_e, 0.5 * d_top)
        d_m = np.concatenate([[d_e], np.linspace(d_e, d_top, settings.levels + 1)[1:]])
        d_res = np.zeros(d_m.size)
        d_res_interface = np.zeros(d_m.size)
        f = np.zeros((d_m.size, SHAPE_CELLS + 1))
        f[0] = np.interp(xi * d_e, grid, Fv) / np.interp(d_e, grid, Fv)
        for k in range(1, d_m.size):
            n = settings.increments
            c = solve_path(mesh, E, nu, model, radius, d_m[k] * np.arange(1, n + 1) / n,
                           unload=True, plate=elastic_plate, interface=interface,
                           plate_model=plate_model, near=near)
            paths += 1
            up, down = c.branch == 0, c.branch == 1
            d_res[k] = c.residual_indentation if c.residual_indentation is not None else 0.0
            d_res[k] = min(max(d_res[k], 0.0), 0.99 * d_m[k])
            d_res_interface[k] = min(max(c.interface_residual or 0.0, 0.0), d_res[k])
            f[k] = _shape_of(c.delta[down], c.force[down], d_m[k], float(c.force[up][-1]),
                             d_res[k])
    S = np.stack([_cumulative(row, 1.0 / SHAPE_CELLS) for row in f])
    stats = {"paths": paths, "seconds": time.perf_counter() - t0, "nodes": len(mesh.nodes),
             "first_yield_delta": load.first_yield_delta}
    return Tables(h, Fv, W, d_m, d_res, f, S, bool(elastic), stats, d_res_interface)


@dataclass(frozen=True)
class PlasticState:
    """Per scene: the indentation ``d`` and the largest one reached ``d_max`` (m).

    Parameters
    ----------
    d : numpy.ndarray
        Indentations (m), (n,).
    d_max : numpy.ndarray
        Largest indentations reached (m), (n,).
    """

    d: np.ndarray
    d_max: np.ndarray


@dataclass(frozen=True)
class PlasticWall:
    """History-dependent wall (module docstring), ``n`` scenes; arrays over the scenes.

    ``h`` (n,) m and ``F``, ``W`` (n, VIRGIN_CELLS + 1) the virgin table (N, J); ``d_m``,
    ``d_res`` (n, L) m the levels; ``f``, ``S`` (n, L, SHAPE_CELLS + 1) the shapes;
    ``d_max0`` (n,) m the history the wall starts with (the sample's largest indentation
    so far); ``d_res_interface`` (n, L) m the plate-sample interface's residual depth per
    level (None: ``d_res``). A :class:`ssw.chain.wall.Wall` (the law at the carried
    history) and a stateful wall (``start``, ``advance``, ``take_state``, ``energy``;
    docs/CONTRACTS.md).

    Parameters
    ----------
    h : numpy.ndarray
        Virgin table step (m), (n,).
    F : numpy.ndarray
        Virgin force (N), (n, VIRGIN_CELLS + 1).
    W : numpy.ndarray
        Virgin cumulative work (J), (n, VIRGIN_CELLS + 1).
    d_m : numpy.ndarray
        Level indentations (m), (n, L).
    d_res : numpy.ndarray
        Residual indentations per level (m), (n, L).
    f : numpy.ndarray
        Unloading shapes, (n, L, SHAPE_CELLS + 1).
    S : numpy.ndarray
        Their cumulative integrals, (n, L, SHAPE_CELLS + 1).
    d_max0 : numpy.ndarray
        The history the wall starts with (m), (n,).
    d_res_interface : numpy.ndarray or None
        The plate-sample interface's residual depth per level (m), (n, L); None: ``d_res``.
    """

    h: np.ndarray
    F: np.ndarray
    W: np.ndarray
    d_m: np.ndarray
    d_res: np.ndarray
    f: np.ndarray
    S: np.ndarray
    d_max0: np.ndarray
    d_res_interface: np.ndarray | None = None

    @property
    def n(self) -> int:
        """Number of scenes."""
        return self.h.shape[0]

    @property
    def exact_reach(self) -> np.ndarray:
        """(n,) m: the end of the tabulated virgin curve."""
        return self.h * VIRGIN_CELLS

    # --- the tables
    def _virgin(self, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``F_L(d)`` (N) and ``W_L(d)`` (J), piecewise linear force (linear beyond the
        table), exact integral."""
        x = np.maximum(d, 0.0) / self.h
        k = np.minimum(x.astype(np.int64), VIRGIN_CELLS - 1)
        r = np.arange(self.n)
        t = (x - k) * self.h
        F0, F1 = self.F[r, k], self.F[r, k + 1]
        slope = (F1 - F0) / self.h
        return F0 + slope * t, self.W[r, k] + F0 * t + 0.5 * slope * t * t

    def _level(self, d_max: np.ndarray, table: np.ndarray | None = None
               ) -> tuple[np.ndarray, ...]:
        """Residual indentation (of ``table``, per level; default ``d_res``), and the two
        neighbouring levels with their weight."""
        table = self.d_res if table is None else table
        L = self.d_m.shape[1]
        r = np.arange(self.n)
        k = np.clip(np.sum(d_max[:, None] >= self.d_m, axis=1) - 1, 0, L - 1)
        k1 = np.minimum(k + 1, L - 1)
        lo, hi = self.d_m[r, k], self.d_m[r, k1]
        span = np.where(np.isfinite(lo), hi - np.where(np.isfinite(lo), lo, 0.0), 0.0)
        w = np.where(span > 0, (d_max - lo) / np.where(span > 0, span, 1.0), 0.0)
        w = np.clip(w, 0.0, 1.0)
        last = k == k1  # beyond the last level: its ratio d_res / d_m
        ratio = table[r, k] / np.where(np.isfinite(self.d_m[r, k]), self.d_m[r, k], 1.0)
        d_res = np.where(last, ratio * d_max, (1 - w) * table[r, k] + w * table[r, k1])
        return d_res, k, k1, w

    def _shape(self, tab: np.ndarray, k: np.ndarray, k1: np.ndarray, w: np.ndarray,
               xi: np.ndarray) -> np.ndarray:
        r = np.arange(self.n)
        x = np.clip(xi, 0.0, 1.0) * SHAPE_CELLS
        j = np.minimum(x.astype(np.int64), SHAPE_CELLS - 1)
        t = x - j

        def at(kk: np.ndarray) -> np.ndarray:
            a, b = tab[r, kk, j], tab[r, kk, j + 1]
            return a + t * (b - a)

        return (1 - w) * at(k) + w * at(k1)

    def _shape_integral(self, k: np.ndarray, k1: np.ndarray, w: np.ndarray, xi: np.ndarray
                        ) -> np.ndarray:
        """``int_0^xi f`` exact for the piecewise linear shapes."""
        r = np.arange(self.n)
        x = np.clip(xi, 0.0, 1.0) * SHAPE_CELLS
        j = np.minimum(x.astype(np.int64), SHAPE_CELLS - 1)
        t = x - j
        hx = 1.0 / SHAPE_CELLS

        def at(kk: np.ndarray) -> np.ndarray:
            a, b = self.f[r, kk, j], self.f[r, kk, j + 1]
            return self.S[r, kk, j] + hx * (a * t + 0.5 * (b - a) * t * t)

        return (1 - w) * at(k) + w * at(k1)

    # --- the law at a state
    def force_at(self, d: np.ndarray, d_max: np.ndarray) -> np.ndarray:
        """Force (N) at indentation ``d`` for the largest indentation ``d_max`` (m).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).
        d_max : numpy.ndarray
            Largest indentations of the history (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,).
        """
        d = np.maximum(np.asarray(d, float), 0.0)
        d_max = np.maximum(np.asarray(d_max, float), d)
        FL, _ = self._virgin(d)
        FLm, _ = self._virgin(d_max)
        d_res, k, k1, w = self._level(d_max)
        xi = (d - d_res) / np.maximum(d_max - d_res, 1e-300)
        below = FLm * self._shape(self.f, k, k1, w, xi) * (xi > 0)
        elastic = (d >= d_max) | (d_max <= self.d_m[:, 0])
        return np.where(elastic, FL, below)

    def energies(self, d: np.ndarray, d_max: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Stored and dissipated energy (J) at ``d`` for the history ``d_max`` (m).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).
        d_max : numpy.ndarray
            Largest indentations of the history (m), (n,).

        Returns
        -------
        stored : numpy.ndarray
            Stored energy (J), (n,).
        dissipated : numpy.ndarray
            Dissipated energy (J), (n,).
        """
        d = np.maximum(np.asarray(d, float), 0.0)
        d_max = np.maximum(np.asarray(d_max, float), d)
        _, WL = self._virgin(d)
        FLm, WLm = self._virgin(d_max)
        d_res, k, k1, w = self._level(d_max)
        span = np.maximum(d_max - d_res, 1e-300)
        xi = (d - d_res) / span
        stored = FLm * span * self._shape_integral(k, k1, w, xi) * (xi > 0)
        r = np.arange(self.n)
        full = FLm * span * ((1 - w) * self.S[r, k, -1] + w * self.S[r, k1, -1])
        elastic = d_max <= self.d_m[:, 0]
        return np.where(elastic, WL, stored), np.where(elastic, 0.0, WLm - full)

    def residual_indentation(self, d_max: np.ndarray | None = None) -> np.ndarray:
        """(n,) m: the permanent set after unloading from ``d_max`` (default the history).

        Parameters
        ----------
        d_max : numpy.ndarray or None
            Largest indentations (m), (n,); None: the wall's history.

        Returns
        -------
        numpy.ndarray
            Permanent set (m), (n,).
        """
        dm = self.d_max0 if d_max is None else np.asarray(d_max, float)
        return np.where(dm <= self.d_m[:, 0], 0.0, self._level(dm)[0])

    def interface_residual_indentation(self, d_max: np.ndarray | None = None) -> np.ndarray:
        """(n,) m: the plate-sample interface's permanent depth on the axis after unloading
        from ``d_max`` (default the history): :meth:`residual_indentation` less the plate's
        permanent thinning (without a plate, the residual indentation).

        Parameters
        ----------
        d_max : numpy.ndarray or None
            Largest indentations (m), (n,); None: the wall's history.

        Returns
        -------
        numpy.ndarray
            Permanent interface depth (m), (n,).
        """
        if self.d_res_interface is None:
            return self.residual_indentation(d_max)
        dm = self.d_max0 if d_max is None else np.asarray(d_max, float)
        return np.where(dm <= self.d_m[:, 0], 0.0, self._level(dm, self.d_res_interface)[0])

    def with_history(self, d_max: np.ndarray) -> PlasticWall:
        """The same sample after it reached ``d_max`` (m) (the larger of it and the past).

        Parameters
        ----------
        d_max : numpy.ndarray
            Largest indentations reached (m), (n,).

        Returns
        -------
        PlasticWall
            The wall with the new history.
        """
        return replace(self, d_max0=np.maximum(self.d_max0, np.asarray(d_max, float)))

    # --- the Wall protocol (at the carried history)
    def force(self, d: np.ndarray) -> np.ndarray:
        """Force (N) at indentation ``d`` (m) on the wall's history ``d_max0``.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,).
        """
        return self.force_at(d, self.d_max0)

    def potential(self, d: np.ndarray) -> np.ndarray:
        """Work of the wall force from the unloaded sample to ``d`` on the current history
        (J): the stored energy plus what a new yield would dissipate.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Work (J), (n,).
        """
        s, diss = self.energies(d, self.d_max0)
        return s + diss - self._lost0

    @functools.cached_property
    def _lost0(self) -> np.ndarray:
        """(n,) J: the energy dissipated by the carried history."""
        return self.energies(np.zeros(self.n), self.d_max0)[1]

    def indentation(self, F: np.ndarray) -> np.ndarray:
        """Indentation (m) carrying ``F`` (N) on the current history (the root of the
        monotone law, :func:`ssw.chain.wall_base.force_indentation`).

        Parameters
        ----------
        F : numpy.ndarray
            Forces (N), (n,).

        Returns
        -------
        numpy.ndarray
            Indentation (m), (n,).
        """
        return force_indentation(self.force, F, np.maximum(self.exact_reach, self.d_max0))

    def take(self, idx: np.ndarray) -> PlasticWall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        PlasticWall
            The wall of the selected scenes.
        """
        return PlasticWall(self.h[idx], self.F[idx], self.W[idx], self.d_m[idx],
                           self.d_res[idx], self.f[idx], self.S[idx], self.d_max0[idx],
                           None if self.d_res_interface is None else self.d_res_interface[idx])

    def hertz_equivalent(self, d_ref: float) -> np.ndarray:
        """``F_L(d) / d^1.5`` (N/m^1.5) at ``max(d_ref, one table cell)``.

        Parameters
        ----------
        d_ref : float
            Reference indentation (m), > 0.

        Returns
        -------
        numpy.ndarray
            Equivalent Hertz coefficient (N/m^1.5), (n,).
        """
        d = np.maximum(np.full(self.n, d_ref), self.h)
        return self._virgin(d)[0] / d**1.5

    # --- stateful wall
    def start(self, d0: np.ndarray) -> PlasticState:
        """The state with the last beads at ``d0`` (m), on the wall's history.

        Parameters
        ----------
        d0 : numpy.ndarray
            Initial indentations (m), (n,).

        Returns
        -------
        PlasticState
            The state.
        """
        d0 = np.array(d0, float)
        return PlasticState(d0, np.maximum(self.d_max0, d0))

    def advance(self, st: PlasticState, d: np.ndarray, dt: float
                ) -> tuple[np.ndarray, PlasticState]:
        """Force (N) at the new indentation ``d`` (m) and the new state.

        Parameters
        ----------
        st : PlasticState
            The state (indentations and history, m).
        d : numpy.ndarray
            Indentations at the step's end (m), (n,).
        dt : float
            Time step (s); unused (the law is rate-independent).

        Returns
        -------
        F : numpy.ndarray
            Force (N), (n,).
        state : PlasticState
            The new state.
        """
        d = np.array(d, float)
        d_max = np.maximum(st.d_max, d)
        return self.force_at(d, d_max), PlasticState(d, d_max)

    def take_state(self, st: PlasticState, idx: np.ndarray) -> PlasticState:
        """The state of the scenes ``idx``.

        Parameters
        ----------
        st : PlasticState
            The state (indentations and history, m).
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        PlasticState
            The selected scenes' state.
        """
        return PlasticState(st.d[idx], st.d_max[idx])

    def energy(self, st: PlasticState) -> tuple[np.ndarray, np.ndarray]:
        """Stored and dissipated (since the unloaded virgin sample) energy, J.

        Parameters
        ----------
        st : PlasticState
            The state (indentations and history, m).

        Returns
        -------
        stored : numpy.ndarray
            Stored energy (J), (n,).
        dissipated : numpy.ndarray
            Dissipated energy (J), (n,).
        """
        return self.energies(st.d, st.d_max)


def reach(params: ChainParams, E: float, nu: float, margin: float = ENERGY_MARGIN) -> float:
    """A first ``d_top`` (m): where a Hertz wall stores ``margin`` hits' energy, doubled
    (a plastic sample is softer). :func:`plastic_wall` extends it when the virgin curve
    holds less.

    Parameters
    ----------
    params : ChainParams
        The chain.
    E : float
        Sample's Young's modulus (Pa).
    nu : float
        Sample's Poisson's ratio.
    margin : float
        Number of hits' energy to hold.

    Returns
    -------
    float
        Indentation (m).

    References
    ----------
    Johnson, K. L. (1985). *Contact Mechanics*, ch. 11.
    """
    from ssw.hertz import energy_indentation

    A = float(params.wall_coefficient(np.array([E]), np.array([nu]))[0])
    e_hit = 0.5 * params.masses[0] * params.striker_velocity**2
    return 2.0 * float(energy_indentation(A, margin * e_hit))


def plastic_wall(params: ChainParams, soil_E: Any, soil_nu: Any, *, soil_model: Any = None,
                 plate_model: Any = None, settings: Settings = Settings(),
                 margin: float = ENERGY_MARGIN, **_: Any) -> PlasticWall:
    """The plastic wall of virgin samples (``d_max0 = 0``) under the chain's plate.

    Parameters
    ----------
    params : ChainParams
        The chain; its plate (if any) tied to the sample by its interface,
        ``frictionless`` or ``bonded``.
    soil_E : array_like
        The samples' Young's moduli, Pa (broadcast with ``soil_nu``: the scenes).
    soil_nu : array_like
        The samples' Poisson's ratios.
    soil_model : model of :mod:`ssw.constitutive`, sequence of models, or None
        The sample's law, or one per scene; None: an elastic sample (with a
        ``plate_model``).
    plate_model : model of :mod:`ssw.constitutive` or None
        The plate's law (None: elastic).
    settings : Settings
        The tables' FEM settings.
    margin : float
        The virgin curve holds ``margin`` hits' energy (:data:`ENERGY_MARGIN`).
    **_ : Any
        Options of the other walls (the wall registry passes every wall the same ones),
        ignored.

    Returns
    -------
    PlasticWall
        The wall of the scenes.

    Raises
    ------
    ConfigError
        Without a plastic model of the sample or the plate, with a plate model and no plate,
        or with a plate interface the plastic contact does not model.
    """
    models = list(soil_model) if isinstance(soil_model, list | tuple) else [soil_model]
    if plate_model is None and (not models or any(m is None for m in models)):
        raise ConfigError("soil_model", soil_model, "a plastic model of ssw.constitutive "
                          "(von-mises, tresca, drucker-prager, crushable-foam), or one per "
                          "scene (or a plate_model)")
    if any(m is not None and not hasattr(m, "update") for m in models):
        raise ConfigError("soil_model", soil_model, "models of ssw.constitutive")
    if plate_model is not None and not hasattr(plate_model, "update"):
        raise ConfigError("plate_model", plate_model, "a model of ssw.constitutive")
    if plate_model is not None and not params.plate_thickness > 0:
        raise ConfigError("plate_model", plate_model.key, "a plate (thickness > 0)")
    plate = None
    if params.plate_thickness > 0:
        if params.plate_interface not in ("frictionless", "bonded"):
            raise ConfigError("plate.interface", params.plate_interface,
                              "frictionless | bonded with the plastic wall (the plate stays "
                              "on the sample)")
        plate = (float(params.plate_E), float(params.plate_nu),
                 float(params.plate_thickness), 0.5 * float(params.plate_diameter),
                 params.plate_interface, plate_model)
    E, nu = scene_arrays(soil_E, soil_nu)
    if len(models) not in (1, E.size):
        raise ConfigError("soil_model", f"{len(models)} models",
                          f"one model, or one per scene ({E.size})")
    models = models * E.size if len(models) == 1 else models
    s = compliance_scale(params, E, nu)
    weight = params.g * float(np.sum(params.masses[1:])) if params.gravity else 0.0
    e_hit = 0.5 * float(params.masses[0]) * params.striker_velocity**2
    rows = []
    for Ei, nui, si, model in zip(E, nu, s, models, strict=True):
        d_top = reach(params, float(Ei), float(nui), margin)
        t_prev = None
        for _ in range(4):
            try:
                t = tables(float(Ei), float(nui), model, float(params.bead_radius), d_top,
                           settings, plate)
            except ContactZoneError:
                if t_prev is None:
                    raise
                # deeper than the small-strain contact reaches: the last tables, whose
                # exact_reach a hit may pass (run_hits says so)
                t = t_prev
                break
            if t.W[-1] >= margin * (e_hit + (weight + params.preload) * d_top):
                break
            t_prev = t
            d_top *= 1.5
        rows.append((t, float(si)))
    L = max(t.d_m.size for t, _ in rows)

    def pad(x: np.ndarray) -> np.ndarray:  # repeat the last level up to L
        return np.concatenate([x, np.repeat(x[-1:], L - x.shape[0], axis=0)], axis=0)

    return PlasticWall(
        np.array([t.h * si for t, si in rows]), np.stack([t.F for t, _ in rows]),
        np.stack([t.W * si for t, si in rows]),
        np.stack([pad(t.d_m * si) for t, si in rows]),
        np.stack([pad(t.d_res * si) for t, si in rows]),
        np.stack([pad(t.f) for t, _ in rows]), np.stack([pad(t.S) for t, _ in rows]),
        np.zeros(len(rows)), np.stack([pad(t.d_res_interface * si) for t, si in rows]))
