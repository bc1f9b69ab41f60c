"""The FEM force-indentation curve itself as the last contact (``table``): one curve per
scene resampled on a uniform grid and interpolated (no fit error), :class:`TableWall`.

``g[k] = F(k h) / (k h)^1.5`` is interpolated linearly (exact for Hertz at any grid), the
curve's indentations first scaled by the bead's compliance
(:func:`ssw.chain.wall_base.compliance_scale`).

Table extension. Beyond the curve's last point ``(d_L, F_L)`` the force continues as the
power law ``F = F_L (d/d_L)^n_L`` whose exponent is the curve's log-log slope over its last
10 % of indentation (clipped to [1, 2]): C^0 and slope-continuous in the mean. The chain's
peak wall indentation (:func:`ssw.chain.run.peak_wall_indentation`) tells how far a
sweep reaches beyond the FEM range (:func:`ssw.chain.wall.beyond_exact_reach`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.chain.params import ChainParams
from ssw.chain.wall_base import compliance_scale, force_indentation, scene_arrays
from ssw.errors import ConfigError, SswError

#: Cells of the uniform indentation grid a FEM curve is resampled on.
TABLE_CELLS = 400
#: Share of the curve's indentation range used for the extension's exponent.
TABLE_TAIL = 0.1



@dataclass(frozen=True)
class TableWall:
    """Tabulated ``F(d)`` per scene on a uniform grid, with a power-law extension.

    ``g[k] = F(k h) / (k h)^1.5`` is interpolated linearly (exact for Hertz at any grid);
    beyond ``d_last = TABLE_CELLS h`` the force is ``F_last (d/d_last)^n_ext``.

    Parameters
    ----------
    h : numpy.ndarray
        Grid step per scene (m), (n,).
    g : numpy.ndarray
        ``F(k h) / (k h)^1.5`` per scene (N/m^1.5), (n, TABLE_CELLS + 1).
    f_last : numpy.ndarray
        Force at the table's last indentation (N), (n,).
    n_ext : numpy.ndarray
        Exponent of the power-law extension, (n,).
    """

    h: np.ndarray  # m, grid step per scene, (n,)
    g: np.ndarray  # N/m^1.5, (n, TABLE_CELLS + 1)
    f_last: np.ndarray  # N
    n_ext: np.ndarray  # -

    @property
    def n(self) -> int:
        """Number of scenes."""
        return self.h.shape[0]

    @property
    def exact_reach(self) -> np.ndarray:
        """(n,) m: the last indentation of each scene's curve; beyond it the law is the
        power-law extension (:func:`ssw.chain.wall.beyond_exact_reach` flags a run that goes
        there)."""
        return self.h * (self.g.shape[1] - 1)

    def force(self, d: np.ndarray) -> np.ndarray:
        """Wall force (N) at indentation ``d`` (m): the interpolated table inside it, the
        power-law extension beyond ``d_last``.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Force (N), (n,); 0 for ``d <= 0``.
        """
        dp = np.maximum(d, 0.0)
        cells = self.g.shape[1] - 1
        x = dp / self.h
        k = np.minimum(x.astype(np.int64), cells - 1)
        frac = np.minimum(x - k, 1.0)
        rows = np.arange(self.n) * (cells + 1)
        flat = self.g.ravel()
        gk = flat[rows + k]
        gval = gk + frac * (flat[rows + k + 1] - gk)
        inside = gval * dp * np.sqrt(dp)
        d_last = cells * self.h
        outside = self.f_last * (np.maximum(dp, d_last) / d_last) ** self.n_ext
        return np.where(x <= cells, inside, outside)

    def dforce_dd(self, d: np.ndarray) -> np.ndarray:
        """Tangent stiffness (N/m) of the tabulated law at ``d`` (m): ``g' d^1.5 + 1.5 g
        d^0.5`` inside the table (``g`` linear in each cell), the extension's beyond.

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Returns
        -------
        numpy.ndarray
            Tangent stiffness (N/m), (n,).
        """
        dp = np.maximum(d, 0.0)
        cells = self.g.shape[1] - 1
        x = dp / self.h
        k = np.minimum(x.astype(np.int64), cells - 1)
        frac = np.minimum(x - k, 1.0)
        r = np.arange(self.n)
        g0, g1 = self.g[r, k], self.g[r, k + 1]
        sq = np.sqrt(dp)
        inside = (g1 - g0) / self.h * dp * sq + 1.5 * (g0 + frac * (g1 - g0)) * sq
        d_last = cells * self.h
        outside = (self.n_ext * self.f_last / d_last
                   * (np.maximum(dp, d_last) / d_last) ** (self.n_ext - 1.0))
        return np.where(x <= cells, inside, outside)

    def dforce_dE(self, d: np.ndarray) -> np.ndarray:
        """Not available: a table is one FEM curve per scene, data for one modulus (the
        ``fem`` wall is the same law as a function of E).

        Parameters
        ----------
        d : numpy.ndarray
            Indentations (m), (n,).

        Raises
        ------
        ConfigError
            Always: a table holds no E-dependence.
        """
        raise ConfigError("wall", "table", "a law with its E-dependence for dF/dE: fem, fit, "
                          "hertz (a table wall's curve is data for one modulus)")

    def indentation(self, F: np.ndarray) -> np.ndarray:
        """Indentation carrying ``F`` (N): the root of the monotone law
        (:func:`ssw.chain.wall_base.force_indentation`).

        Parameters
        ----------
        F : numpy.ndarray
            Forces (N), (n,); values <= 0 give 0.

        Returns
        -------
        numpy.ndarray
            Indentation (m), (n,).
        """
        return force_indentation(self.force, F, self.h * (self.g.shape[1] - 1))

    def take(self, idx: np.ndarray) -> TableWall:
        """The scenes ``idx`` (may repeat).

        Parameters
        ----------
        idx : numpy.ndarray
            Integer indices of the scenes to keep, (k,); may repeat.

        Returns
        -------
        TableWall
            The tables of the selected scenes.
        """
        return TableWall(self.h[idx], self.g[idx], self.f_last[idx], self.n_ext[idx])

    def hertz_equivalent(self, d_ref: float) -> np.ndarray:
        """``F(d_ref) / d_ref^1.5`` (N/m^1.5).

        Parameters
        ----------
        d_ref : float
            Reference indentation (m), > 0.

        Returns
        -------
        numpy.ndarray
            Equivalent Hertz coefficient (N/m^1.5), (n,).
        """
        return self.force(np.full(self.n, d_ref)) / d_ref**1.5



def table_wall(
    params: ChainParams, soil_E: Any, soil_nu: Any, *, curve: Any = None
) -> TableWall:
    """The FEM curve(s) themselves, interpolated (module docstring).

    Parameters
    ----------
    params : ChainParams
        The chain (the bead's compliance).
    soil_E : array_like
        Pa, broadcast with ``soil_nu``: one scene each.
    soil_nu : array_like
        -.
    curve : ForceCurve or str or sequence
        One curve (:class:`ssw.curve.ForceCurve` or HDF5 path) for every scene, or a
        sequence with one per scene.

    Returns
    -------
    TableWall
        One table per scene (data for one modulus each: no E-dependence).

    Raises
    ------
    ConfigError
        No curve, or not one per scene.
    """
    E, nu = scene_arrays(soil_E, soil_nu)
    if curve is None:
        raise ConfigError("curve", None, "a contact curve (ForceCurve or results/contact/*.h5)")
    curves = list(curve) if isinstance(curve, Sequence) and not isinstance(curve, str) else [
        curve
    ] * E.size
    if len(curves) != E.size:
        raise ConfigError("curve", f"{len(curves)} curves", f"one per scene ({E.size})")
    s = compliance_scale(params, E, nu)
    rows = [_resample(_as_curve(c), si) for c, si in zip(curves, s, strict=True)]
    h, g, fl, ne = (np.array(x) for x in zip(*rows, strict=True))
    return TableWall(h, g, fl, ne)


def _as_curve(c: Any) -> Any:
    if hasattr(c, "delta") and hasattr(c, "force"):
        return c
    from ssw.curve import read_curve

    return read_curve(c, extras=False)


def _resample(curve: Any, scale: float) -> tuple[float, np.ndarray, float, float]:
    """Grid step, ``g = F/d^1.5`` on the grid, last force and extension exponent."""
    d = np.asarray(curve.delta, float) * scale
    F = np.asarray(curve.force, float)
    if d[0] > 0:  # the curve starts at contact: F(0) = 0
        d, F = np.concatenate([[0.0], d]), np.concatenate([[0.0], F])
    if np.any(np.diff(F) < 0) or not F[-1] > 0:
        raise SswError("a contact curve for the table wall must be non-decreasing and end > 0 N")
    d_last = d[-1]
    h = d_last / TABLE_CELLS
    grid = h * np.arange(TABLE_CELLS + 1)
    pos = d > 0
    g = np.interp(grid, d[pos], F[pos] / d[pos] ** 1.5)  # F/d^1.5 is what is interpolated
    tail = d >= (1.0 - TABLE_TAIL) * d_last
    sel = tail & (d > 0) & (F > 0)
    if np.count_nonzero(sel) >= 2:
        n_ext = float(np.polyfit(np.log(d[sel]), np.log(F[sel]), 1)[0])
    else:
        n_ext = 1.5
    return h, g, float(F[-1]), float(np.clip(n_ext, 1.0, 2.0))
