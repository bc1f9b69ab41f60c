"""K(E, nu) tables: per (plate material, thickness), the fits over the soil grid.

A :class:`KTable` holds, for one plate (material, thickness), every law's parameters on the
grid ``soil_nu x soil_E`` with the residuals of each fit, and interpolates them
(:mod:`ssw.fit.interp`: PCHIP in log E, linear in nu):

* ``K(E, nu)``: the ``k_hertz`` factor against the rigid-sphere Hertz law of the FEM,
  ``F_H = 4/3 E/(1 - nu^2) sqrt(R) delta^1.5`` (see :mod:`ssw.fit.fitting` for E*);
* ``power(E, nu) -> (C, n)``: ``F = C delta^n`` (N, m) for the FEM's rigid sphere of
  radius ``radius``.

Stated interpolation errors (``interp_error``; leave-one-out, :mod:`ssw.fit.interp`):
``K`` relative; ``power`` as the relative error of the force ``C delta^n`` at the fit
ranges' ends. Files: HDF5 (``ssw_kind = "k_table"``; one group per plate) and CSV (one row
per scene).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ssw import hertz
from ssw.errors import ConfigError, OutOfRangeError, SswError
from ssw.fit.fitting import FitResult
from ssw.fit.interp import GridInterpolant
from ssw.fit.laws import LAWS
from ssw.h5io import atomic_h5, check_kind, read_inputs, write_dataset, write_rows_csv

KIND = "k_table"
RESIDUALS = ("rms_rel_residual", "max_rel_residual")


def group_name(plate_material: str, plate_thickness: float) -> str:
    """HDF5 group of a plate, e.g. ``pla-t400um`` (``noplate`` for thickness 0).

    Parameters
    ----------
    plate_material : str
        The plate's material key.
    plate_thickness : float
        The plate's thickness (m).

    Returns
    -------
    str
        The group's name.
    """
    return "noplate" if plate_thickness == 0 else f"{plate_material}-t{plate_thickness * 1e6:g}um"


@dataclass
class KTable:
    """Fits of one plate over a soil grid; arrays have shape (n_nu, n_E). SI units.

    Parameters
    ----------
    plate_material : str
        The plate's material key.
    plate_thickness : float
        Plate thickness (m).
    radius : float
        Indenter radius of the fits (m).
    soil_E : numpy.ndarray
        Soil moduli (Pa), increasing.
    soil_nu : numpy.ndarray
        Soil Poisson's ratios, increasing.
    params : dict
        law -> parameter -> values, (n_nu, n_E).
    residuals : dict
        law -> ``rms``/``max`` -> relative residuals, (n_nu, n_E).
    delta_lo : numpy.ndarray
        Lower end of each scene's fit range (m).
    delta_hi : numpy.ndarray
        Upper end of each scene's fit range (m).
    weighting : str
        The fits' residual weighting.

    Other Parameters
    ----------------
    _interp : dict
        Interpolants by quantity, built on first use (a cache).
    """

    plate_material: str
    plate_thickness: float  # m
    radius: float  # m, indenter radius of the fits
    soil_E: NDArray[np.float64]  # Pa, increasing
    soil_nu: NDArray[np.float64]  # -, increasing
    params: dict[str, dict[str, NDArray[np.float64]]]  # law -> parameter -> (n_nu, n_E)
    residuals: dict[str, dict[str, NDArray[np.float64]]]  # law -> rms/max -> (n_nu, n_E)
    delta_lo: NDArray[np.float64]  # m, fit range per scene
    delta_hi: NDArray[np.float64]  # m
    weighting: str = "absolute"
    _interp: dict[str, GridInterpolant] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        self.soil_E = np.asarray(self.soil_E, float)
        self.soil_nu = np.asarray(self.soil_nu, float)
        if "k_hertz" in self.params:
            self._interp["K"] = GridInterpolant(
                self.soil_E, self.soil_nu, self.params["k_hertz"]["K"], log_values=True
            )
        if "power" in self.params:
            # F = C d^n is interpolated as F(d_ref) relative to Hertz, Kp = C d_ref^n / (A_H
            # d_ref^1.5), and n: Kp carries little of the E and nu dependence (A_H does) and,
            # at an indentation inside every fit range, is nearly uncorrelated with n. C
            # itself (N m^-n) swings with n by orders of magnitude; interpolated alone it
            # costs several times the error (leave-one-out, Set 3).
            p = self.params["power"]
            Kp = p["C"] * self.power_ref ** p["n"] / (self._hertz_A() * self.power_ref**1.5)
            self._interp["Kp"] = GridInterpolant(self.soil_E, self.soil_nu, Kp, log_values=True)
            self._interp["n"] = GridInterpolant(self.soil_E, self.soil_nu, p["n"], log_values=False)

    @classmethod
    def load(
        cls,
        path: str | Path,
        plate_material: str | None = None,
        plate_thickness: float | None = None,
    ) -> KTable:
        """The table of one plate (m) from an HDF5 file (the only one when it holds one).

        Parameters
        ----------
        path : str or pathlib.Path
            The HDF5 file.
        plate_material : str or None
            The plate's material key; None: any.
        plate_thickness : float or None
            The plate's thickness (m); None: any.

        Returns
        -------
        KTable
            The matching table.
        """
        tables, _ = load_tables(path)
        pick = [
            tb
            for tb in tables
            if (plate_material is None or tb.plate_material == plate_material)
            and (plate_thickness is None or abs(tb.plate_thickness - plate_thickness) <= 1e-12)
        ]
        if len(pick) != 1:
            have = ", ".join(tb.name for tb in tables)
            raise OutOfRangeError(
                f"{path}: plate {plate_material!r}, thickness {plate_thickness!r} m selects "
                f"{len(pick)} of the tables ({have}); name one plate"
            )
        return pick[0]

    @property
    def name(self) -> str:
        """The table's HDF5 group name (:func:`group_name`)."""
        return group_name(self.plate_material, self.plate_thickness)

    @property
    def power_ref(self) -> float:
        """m, the reference indentation of the power law's interpolation: the geometric
        mean of the fit ranges' upper ends."""
        return float(np.exp(np.mean(np.log(np.asarray(self.delta_hi, float)))))

    def _hertz_A(self, soil_E: ArrayLike | None = None, soil_nu: ArrayLike | None = None
                 ) -> NDArray[np.float64]:
        """``A_H = 4/3 E/(1 - nu^2) sqrt(R)`` (rigid indenter), on the grid by default."""
        if soil_E is None:
            soil_E, soil_nu = np.meshgrid(self.soil_E, self.soil_nu)
        return hertz.hertz_coefficient(hertz.effective_modulus(soil_E, soil_nu), self.radius)

    def _need(self, key: str, law: str) -> GridInterpolant:
        if key not in self._interp:
            raise ConfigError("fit.compare_laws", sorted(self.params), f"must include {law}")
        return self._interp[key]

    def K(self, soil_E: ArrayLike, soil_nu: ArrayLike) -> NDArray[np.float64]:
        """Interpolated K (-) at soil modulus ``soil_E`` (Pa) and Poisson's ratio ``soil_nu``.

        Parameters
        ----------
        soil_E : array_like
            Soil Young's modulus (Pa).
        soil_nu : array_like
            Soil Poisson's ratio.

        Returns
        -------
        numpy.ndarray
            K (dimensionless), the broadcast shape.
        """
        return self._need("K", "k_hertz")(soil_E, soil_nu)

    def power(
        self, soil_E: ArrayLike, soil_nu: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Interpolated ``(C, n)`` of ``F = C delta^n`` (C in N m^-n); exact at grid nodes.

        Parameters
        ----------
        soil_E : array_like
            Soil Young's modulus (Pa).
        soil_nu : array_like
            Soil Poisson's ratio.

        Returns
        -------
        C : numpy.ndarray
            Coefficient (N m^-n).
        n : numpy.ndarray
            Exponent (dimensionless).
        """
        Kp = self._need("Kp", "power")(soil_E, soil_nu)
        n = self._need("n", "power")(soil_E, soil_nu)
        E, nu = np.broadcast_arrays(np.asarray(soil_E, float), np.asarray(soil_nu, float))
        d = self.power_ref
        return Kp * self._hertz_A(E, nu) * d**1.5 / d**n, n

    def dK_dE(self, soil_E: ArrayLike, soil_nu: ArrayLike) -> NDArray[np.float64]:
        """``dK/dE`` (1/Pa) of the interpolated K at fixed ``soil_nu``.

        Parameters
        ----------
        soil_E : array_like
            Soil Young's modulus (Pa).
        soil_nu : array_like
            Soil Poisson's ratio.

        Returns
        -------
        numpy.ndarray
            ``dK/dE`` (1/Pa), the broadcast shape.
        """
        return self._need("K", "k_hertz").derivative_E(soil_E, soil_nu)

    def dpower_dE(
        self, soil_E: ArrayLike, soil_nu: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(dC/dE, dn/dE)`` of :meth:`power` at fixed ``soil_nu`` (N m^-n / Pa, 1/Pa):
        ``C = Kp A_H d^(1.5 - n)`` with ``A_H`` proportional to E, so
        ``dC/dE = C (Kp'/Kp + 1/E - ln(d) n')``.

        Parameters
        ----------
        soil_E : array_like
            Soil Young's modulus (Pa).
        soil_nu : array_like
            Soil Poisson's ratio.

        Returns
        -------
        dC_dE : numpy.ndarray
            ``dC/dE`` (N m^-n / Pa).
        dn_dE : numpy.ndarray
            ``dn/dE`` (1/Pa).
        """
        C, _ = self.power(soil_E, soil_nu)
        Kp = self._need("Kp", "power")(soil_E, soil_nu)
        dKp = self._interp["Kp"].derivative_E(soil_E, soil_nu)
        dn = self._need("n", "power").derivative_E(soil_E, soil_nu)
        E = np.broadcast_to(np.asarray(soil_E, float), np.shape(C))
        return C * (dKp / Kp + 1.0 / E - np.log(self.power_ref) * dn), dn

    def interp_error(self) -> dict[str, float]:
        """Stated maximum interpolation errors (relative), leave-one-out estimates.

        Returns
        -------
        dict
            Relative error per interpolated quantity.
        """
        out: dict[str, float] = {}
        if "K" in self._interp:
            e = self._interp["K"].loo_error()
            out.update(K_E=e["E"], K_nu=e["nu"], K=e["bound"])
        if "Kp" in self._interp:
            (kE, knu), (nE, nnu) = (self._interp[k].loo_predictions() for k in ("Kp", "n"))
            Kp, n0 = self._interp["Kp"].values, self.params["power"]["n"]
            errs = []
            # the force at 10 %, 30 % and 100 % of each fit range's upper end: the wall's
            # force during the compression that sets the TOF (below 0.1 d_hi the force is
            # under ~3 % of its peak and the TOF insensitive to it)
            for d in (0.1 * self.delta_hi, 0.3 * self.delta_hi, self.delta_hi):
                x = d / self.power_ref  # F ~ Kp (d / d_ref)^n
                errs.append([np.abs(k / Kp * x ** (n - n0) - 1.0)
                             for k, n in ((kE, nE), (knu, nnu))])
            e_E = _nanmax([e[0] for e in errs])
            e_nu = _nanmax([e[1] for e in errs])
            out.update(power_E=e_E, power_nu=e_nu, power=e_E + e_nu)
        return out

    def rows(self) -> list[dict[str, Any]]:
        """One dict per scene: plate, soil, every law's parameters and residuals.

        Returns
        -------
        list of dict
            One row per scene (SI).
        """
        out = []
        for j, nu in enumerate(self.soil_nu):
            for i, E in enumerate(self.soil_E):
                row: dict[str, Any] = {
                    "plate_material": self.plate_material,
                    "plate_thickness": self.plate_thickness,
                    "soil_E": float(E),
                    "soil_nu": float(nu),
                    "delta_lo": float(self.delta_lo[j, i]),
                    "delta_hi": float(self.delta_hi[j, i]),
                }
                for law, ps in self.params.items():
                    for k, v in ps.items():
                        row[k] = float(v[j, i])
                    for k, v in self.residuals[law].items():
                        row[f"{law}_{k}"] = float(v[j, i])
                out.append(row)
        return out


def _nanmax(arrays: Iterable[np.ndarray]) -> float:
    vals = np.concatenate([np.ravel(a) for a in arrays])
    return float(np.nanmax(vals)) if np.any(np.isfinite(vals)) else 0.0


def build_tables(fits: Iterable[FitResult]) -> list[KTable]:
    """Group fits by plate and arrange them on each plate's (nu, E) grid.

    Every (E, nu) of a plate's grid must have a fit of every law that appears for that
    plate; all fits of one plate must share the indenter radius and the weighting.

    Parameters
    ----------
    fits : iterable of FitResult
        The fits.

    Returns
    -------
    list of KTable
        One table per plate.

    Raises
    ------
    SswError
        If two fits of one law share a grid point, or a plate's grid is incomplete or
        mixed.
    """
    groups: dict[tuple[str, float], dict[tuple[float, float, str], FitResult]] = {}
    for fr in fits:
        sc = fr.scene
        t = float(sc.get("plate_thickness") or 0.0)
        key = ("none" if t == 0 else str(sc.get("plate_material")), t)
        cell = (float(sc["soil_E"]), float(sc["soil_nu"]), fr.law)
        if cell in groups.setdefault(key, {}):
            raise SswError(f"two {fr.law} fits for plate {key} at E, nu = {cell[:2]}")
        groups[key][cell] = fr
    return [_table(mat, t, cells) for (mat, t), cells in sorted(groups.items())]


def _table(mat: str, t: float, cells: dict[tuple[float, float, str], FitResult]) -> KTable:
    """One plate's table from its fits keyed by (E, nu, law)."""
    Es = np.unique([c[0] for c in cells])
    nus = np.unique([c[1] for c in cells])
    laws = [law for law in LAWS if any(c[2] == law for c in cells)]
    missing = [(E, nu, law) for law in laws for nu in nus for E in Es if (E, nu, law) not in cells]
    if missing:
        raise SswError(
            f"plate {group_name(mat, t)}: {len(missing)} fits missing on the (E, nu) grid, "
            f"e.g. E = {missing[0][0]:g} Pa, nu = {missing[0][1]:g}, law {missing[0][2]}"
        )
    first = next(iter(cells.values()))
    if any(fr.radius != first.radius or fr.weighting != first.weighting for fr in cells.values()):
        raise SswError(f"plate {group_name(mat, t)}: fits differ in radius or weighting")

    def grid(fn: Any, law: str) -> NDArray[np.float64]:
        return np.array([[fn(cells[(E, nu, law)]) for E in Es] for nu in nus], dtype=float)

    return KTable(
        plate_material=mat,
        plate_thickness=t,
        radius=first.radius,
        soil_E=Es,
        soil_nu=nus,
        params={
            law: {p: grid(lambda fr, p=p: fr.params[p], law) for p in LAWS[law].params}
            for law in laws
        },
        residuals={
            law: {r: grid(lambda fr, r=r: getattr(fr, r), law) for r in RESIDUALS} for law in laws
        },
        delta_lo=grid(lambda fr: fr.delta_lo, laws[0]),
        delta_hi=grid(lambda fr: fr.delta_hi, laws[0]),
        weighting=first.weighting,
    )


def write_tables(
    tables: list[KTable], h5_path: str | Path, csv_path: str | Path | None, inputs: dict
) -> None:
    """Write the tables to HDF5 (one group per plate) and, if given, CSV (one row per scene).

    Parameters
    ----------
    tables : list of KTable
        The tables.
    h5_path : str or pathlib.Path
        The HDF5 file, written atomically.
    csv_path : str or pathlib.Path or None
        The CSV file, or None.
    inputs : dict
        The provenance inputs to record.
    """
    with atomic_h5(h5_path, kind=KIND, inputs=inputs) as f:
        for tb in tables:
            g = f.create_group(tb.name)
            g.attrs.update(
                plate_material=tb.plate_material,
                plate_thickness=tb.plate_thickness,
                radius=tb.radius,
                weighting=tb.weighting,
            )
            for k, v in tb.interp_error().items():
                g.attrs[f"interp_error_{k}"] = v
            write_dataset(g, "soil_E", tb.soil_E, "Pa", "soil Young's modulus axis")
            write_dataset(g, "soil_nu", tb.soil_nu, "1", "soil Poisson's ratio axis")
            write_dataset(g, "delta_lo", tb.delta_lo, "m", "fit range start, (n_nu, n_E)")
            write_dataset(g, "delta_hi", tb.delta_hi, "m", "fit range end, (n_nu, n_E)")
            for law, ps in tb.params.items():
                lg = g.create_group(law)
                lg.attrs["formula"] = LAWS[law].formula
                for (p, v), unit in zip(ps.items(), LAWS[law].units, strict=True):
                    write_dataset(lg, p, v, unit, f"{p} of {LAWS[law].formula}, (n_nu, n_E)")
                for r, v in tb.residuals[law].items():
                    write_dataset(lg, r, v, "1", "relative force residual of the fit")
    if csv_path is not None:
        write_rows_csv([r for tb in tables for r in tb.rows()], csv_path)


def load_tables(path: str | Path) -> tuple[list[KTable], dict[str, Any]]:
    """All tables of an HDF5 file written by :func:`write_tables`, and its inputs.

    Parameters
    ----------
    path : str or pathlib.Path
        The HDF5 file.

    Returns
    -------
    tables : list of KTable
        The tables.
    inputs : dict
        The file's recorded inputs.

    Raises
    ------
    SswError
        If there is no file at ``path``.
    """
    import h5py

    p = Path(path)
    if not p.is_file():
        raise SswError(f"no K table at {p}")
    tables = []
    with h5py.File(p, "r") as f:
        check_kind(f, KIND)
        inputs = read_inputs(f)
        for name in f:
            g = f[name]
            laws = [k for k in g if isinstance(g[k], h5py.Group)]
            tables.append(
                KTable(
                    plate_material=str(g.attrs["plate_material"]),
                    plate_thickness=float(g.attrs["plate_thickness"]),
                    radius=float(g.attrs["radius"]),
                    soil_E=g["soil_E"][()],
                    soil_nu=g["soil_nu"][()],
                    params={law: {q: g[law][q][()] for q in LAWS[law].params} for law in laws},
                    residuals={law: {r: g[law][r][()] for r in RESIDUALS} for law in laws},
                    delta_lo=g["delta_lo"][()],
                    delta_hi=g["delta_hi"][()],
                    weighting=str(g.attrs["weighting"]),
                )
            )
    return tables, inputs
