"""Interpolation of fitted parameters over the soil grid: PCHIP in log E, linear in nu.

A parameter ``p(E, nu)`` known on a grid ``E_1 < ... < E_m`` x ``nu_1 < ... < nu_k`` is
interpolated as

* along E: a monotone piecewise-cubic Hermite interpolant (PCHIP; Fritsch & Carlson 1980,
  SIAM J. Numer. Anal. 17:238) of ``g(p)`` against ``log E``, with ``g = log`` for positive
  parameters (K, C) and the identity otherwise (n). PCHIP keeps the data's monotonicity
  between nodes and passes through every node exactly;
* along nu: linear between the two neighbouring nu rows.

No extrapolation: a point outside the grid raises :class:`ssw.errors.OutOfRangeError`
naming the valid range. A grid with one E (or one nu) is valid only at that value.

Error estimate (leave-one-out): each interior node is dropped, the interpolant rebuilt from
the others and compared with the node's value. The dropped node sits in an interval twice
the grid's, so the estimate bounds the error of the full grid from above for the smooth
(``h^2`` or faster converging) parameters of contact fits.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ssw.errors import OutOfRangeError

#: Relative slack when testing whether a point lies on the grid (rounding of E and nu).
GRID_SLACK = 1e-9


def _pchip() -> type:
    """``scipy.interpolate.PchipInterpolator``, imported when a grid has two E nodes or more
    (scipy.interpolate costs a command that interpolates nothing 0.07-0.1 s to import)."""
    from scipy.interpolate import PchipInterpolator

    return PchipInterpolator


class GridInterpolant:
    """``p(E, nu)`` on a grid: PCHIP in log E of ``log p`` (or ``p``), linear in nu.

    Parameters
    ----------
    soil_E : array_like
        Moduli of the grid (Pa), (n_E,), increasing.
    soil_nu : array_like
        Poisson's ratios of the grid, (n_nu,), increasing.
    values : array_like
        Values on the grid, (n_nu, n_E).
    log_values : bool
        Whether to interpolate ``log p`` (positive values).
    """

    def __init__(
        self, soil_E: ArrayLike, soil_nu: ArrayLike, values: ArrayLike, *, log_values: bool
    ) -> None:
        self.E = np.asarray(soil_E, float)
        self.nu = np.asarray(soil_nu, float)
        self.values = np.asarray(values, float)
        if self.values.shape != (self.nu.size, self.E.size):
            raise OutOfRangeError(
                f"values of shape {self.values.shape}, expected (n_nu, n_E) = "
                f"({self.nu.size}, {self.E.size})"
            )
        if np.any(np.diff(self.E) <= 0) or np.any(np.diff(self.nu) <= 0):
            raise OutOfRangeError("the E and nu axes must be strictly increasing")
        if log_values and np.any(self.values <= 0):
            raise OutOfRangeError("a log-interpolated parameter must be > 0 at every node")
        self.log_values = log_values
        g = np.log(self.values) if log_values else self.values
        self._rows = [
            _pchip()(np.log(self.E), g[j]) if self.E.size > 1 else None
            for j in range(self.nu.size)
        ]
        self._g = g
        self._loo: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None

    def _row(self, j: int, logE: NDArray[np.float64]) -> NDArray[np.float64]:
        spline = self._rows[j]
        return np.full_like(logE, self._g[j, 0]) if spline is None else spline(logE)

    def __call__(self, soil_E: ArrayLike, soil_nu: ArrayLike) -> NDArray[np.float64]:
        """Interpolated values at the broadcast of ``soil_E`` (Pa) and ``soil_nu``."""
        E, nu = np.broadcast_arrays(np.asarray(soil_E, float), np.asarray(soil_nu, float))
        E = _snap(E, self.E, "soil_E", "Pa")
        nu = _snap(nu, self.nu, "soil_nu", "")
        logE = np.log(E)
        if self.nu.size == 1:
            g = self._row(0, logE)
        else:
            j = np.clip(np.searchsorted(self.nu, nu, side="right") - 1, 0, self.nu.size - 2)
            t = (nu - self.nu[j]) / (self.nu[j + 1] - self.nu[j])
            rows = np.stack([self._row(i, logE) for i in range(self.nu.size)])
            lo = np.take_along_axis(rows, j[None], axis=0)[0]
            hi = np.take_along_axis(rows, (j + 1)[None], axis=0)[0]
            g = (1.0 - t) * lo + t * hi
        return np.exp(g) if self.log_values else g

    def derivative_E(self, soil_E: ArrayLike, soil_nu: ArrayLike) -> NDArray[np.float64]:
        """``dp/dE`` (unit of p per Pa) of the interpolant at the broadcast of ``soil_E``
        (Pa) and ``soil_nu``: the PCHIP rows' derivative in ``log E`` (continuous: PCHIP
        is C1), ``dp/dE = p g'(log E) / E`` for log values (``g = log p``), ``g' / E``
        otherwise, mixed linearly in nu as the values are.

        Parameters
        ----------
        soil_E : array_like
            Soil Young's modulus (Pa).
        soil_nu : array_like
            Soil Poisson's ratio.

        Returns
        -------
        numpy.ndarray
            ``dp/dE`` (unit of p per Pa), the broadcast shape.
        """
        E, nu = np.broadcast_arrays(np.asarray(soil_E, float), np.asarray(soil_nu, float))
        E = _snap(E, self.E, "soil_E", "Pa")
        nu = _snap(nu, self.nu, "soil_nu", "")
        logE = np.log(E)

        def row(j: int, order: int) -> NDArray[np.float64]:
            spline = self._rows[j]
            if spline is None:
                return np.full_like(logE, self._g[j, 0] if order == 0 else 0.0)
            return spline(logE, order)

        if self.nu.size == 1:
            g, dg = row(0, 0), row(0, 1)
        else:
            j = np.clip(np.searchsorted(self.nu, nu, side="right") - 1, 0, self.nu.size - 2)
            t = (nu - self.nu[j]) / (self.nu[j + 1] - self.nu[j])

            def mix(order: int) -> NDArray[np.float64]:
                rows = np.stack([row(i, order) for i in range(self.nu.size)])
                lo = np.take_along_axis(rows, j[None], axis=0)[0]
                hi = np.take_along_axis(rows, (j + 1)[None], axis=0)[0]
                return (1.0 - t) * lo + t * hi

            g, dg = mix(0), mix(1)
        return np.exp(g) * dg / E if self.log_values else dg / E

    def loo_predictions(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Leave-one-out predictions at the nodes, shape (n_nu, n_E) each: along E (each
        interior E node from PCHIP through the others) and along nu (each interior nu row
        from its two neighbours); NaN where a node has no two-sided neighbours. Computed
        once per interpolant (a PCHIP per interior E node: 20 ms for 100 nodes; a fit set's
        outputs state the error three times) and returned read-only.

        Returns
        -------
        along_E : numpy.ndarray
            Predictions along E, (n_nu, n_E).
        along_nu : numpy.ndarray
            Predictions along nu, (n_nu, n_E).
        """
        if self._loo is None:
            self._loo = self._loo_predictions()
        return self._loo

    def _loo_predictions(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        along_E = np.full(self.values.shape, np.nan)
        x = np.log(self.E)
        for i in range(1, self.E.size - 1):
            keep = np.arange(self.E.size) != i
            along_E[:, i] = _pchip()(x[keep], self._g[:, keep], axis=1)(x[i])
        along_nu = np.full(self.values.shape, np.nan)
        for j in range(1, self.nu.size - 1):
            t = (self.nu[j] - self.nu[j - 1]) / (self.nu[j + 1] - self.nu[j - 1])
            along_nu[j] = (1.0 - t) * self._g[j - 1] + t * self._g[j + 1]
        out = (np.exp(along_E), np.exp(along_nu)) if self.log_values else (along_E, along_nu)
        for x in out:
            x.flags.writeable = False
        return out

    def loo_error(self) -> dict[str, float]:
        """Leave-one-out errors (max relative for log values, else absolute) along E and nu,
        and their sum ``bound``, the stated interpolation error.

        Returns
        -------
        dict
            Errors along ``E`` and ``nu`` and their sum ``bound``.
        """
        out = {}
        for name, pred in zip(("E", "nu"), self.loo_predictions(), strict=True):
            e = pred / self.values - 1.0 if self.log_values else pred - self.values
            out[name] = float(np.nanmax(np.abs(e))) if np.any(np.isfinite(e)) else 0.0
        out["bound"] = out["E"] + out["nu"]
        return out


def _snap(x: NDArray[np.float64], axis: NDArray[np.float64], name: str, unit: str) -> np.ndarray:
    """Clip values within GRID_SLACK of the axis ends; raise for values beyond them."""
    lo, hi = axis[0], axis[-1]
    tol = GRID_SLACK * max(abs(lo), abs(hi), 1e-300)
    if axis.size == 1:
        if np.any(np.abs(x - lo) > tol):
            raise OutOfRangeError(f"{name} must equal {lo:g} {unit}: the table has one value")
        return np.full_like(x, lo)
    if np.any(x < lo - tol) or np.any(x > hi + tol) or np.any(~np.isfinite(x)):
        bad = x[(x < lo - tol) | (x > hi + tol) | ~np.isfinite(x)].ravel()[0]
        raise OutOfRangeError(
            f"{name} = {bad:g} {unit} is outside the table's range [{lo:g}, {hi:g}] {unit}"
        )
    return np.clip(x, lo, hi)
