"""Figures of the fits: analogues of the thesis's Figs 5-7 (PNG, written atomically).

* ``curves``: force vs indentation of several scenes with each scene's bare-soil Hertz law
  (Figs 5 and 6), and below it the ratio ``F / F_H``;
* ``deviation``: deviation from Hertz at ``fit.delta_ref`` per scene, with the thesis's
  stated values where it gives them;
* ``k``: K vs soil E for each nu (Fig 7): the fitted nodes and the interpolant, with the
  fits' max relative residual.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ssw import hertz
from ssw.curve import read_curve
from ssw.fit.deviation import deviation_rows
from ssw.fit.fitting import scene_inputs
from ssw.plotting import pyplot, save_png


def _label(sc: dict[str, Any]) -> str:
    t = float(sc.get("plate_thickness") or 0.0)
    plate = "no plate" if t == 0 else f"{sc.get('plate_material')} {t * 1e3:g} mm"
    return f"{plate}, E {float(sc['soil_E']) / 1e6:g} MPa"


def _save(fig: Any, path: str | Path) -> None:
    save_png(fig, path, dpi=130, bbox_inches="tight")


def _figure(nrows: int = 1) -> tuple[Any, Any]:
    return pyplot().subplots(nrows, 1, figsize=(6.4, 3.2 * nrows + 0.6), squeeze=False)


def plot_curves(paths: list[str], output: str, cfg: dict[str, Any], title: str = "") -> None:
    """Force vs indentation and the ratio to bare-soil Hertz, one line per curve.

    Parameters
    ----------
    paths : list of str
        The input files.
    output : str
        The PNG file to write.
    cfg : dict
        The validated study config.
    title : str
        The figure's title; empty: a default.
    """
    fig, ax = _figure(2)
    for p in paths:
        c = read_curve(p, extras=False)
        sc = scene_inputs(c)
        F_H = hertz.force(
            c.delta, hertz.effective_modulus(sc["soil_E"], sc["soil_nu"]), sc["radius"]
        )
        (line,) = ax[0, 0].plot(c.delta * 1e3, c.force, label=_label(sc))
        ax[0, 0].plot(c.delta * 1e3, F_H, ls=":", color=line.get_color())
        ok = F_H > 0
        ax[1, 0].semilogx(c.delta[ok] * 1e3, c.force[ok] / F_H[ok], color=line.get_color())
    ax[1, 0].axvline(cfg["fit"]["delta_ref"] * 1e3, color="0.5", lw=0.8)
    ax[0, 0].set(
        xlabel="indentation (mm)",
        ylabel="force (N)",
        title=title or "FEM curves (solid) and bare-soil Hertz (dotted)",
    )
    ax[1, 0].set(xlabel="indentation (mm)", ylabel="F / F_Hertz")
    ax[0, 0].legend(fontsize=7)
    _save(fig, output)


def plot_deviation(paths: list[str], output: str, cfg: dict[str, Any], title: str = "") -> None:
    """Deviation from Hertz at ``fit.delta_ref`` per scene, with the thesis's values.

    Parameters
    ----------
    paths : list of str
        The input files.
    output : str
        The PNG file to write.
    cfg : dict
        The validated study config.
    title : str
        The figure's title; empty: a default.
    """
    curves = [read_curve(p, extras=False) for p in paths]
    kinds = {float(scene_inputs(c).get("plate_thickness") or 0.0) for c in curves}
    rows = deviation_rows(
        curves, "thickness" if len(kinds) > 1 else "materials", cfg["fit"]["delta_ref"]
    )
    fig, ax = _figure(1)
    x = np.arange(len(rows))
    ax[0, 0].bar(x - 0.2, [r["deviation"] for r in rows], 0.4, label=f"ssw ({cfg['material_set']})")
    th = [np.nan if r["thesis_deviation"] is None else r["thesis_deviation"] for r in rows]
    ax[0, 0].bar(x + 0.2, th, 0.4, label="thesis", color="0.6")
    ax[0, 0].set_xticks(x, [_label(r) for r in rows], rotation=20, fontsize=7)
    ax[0, 0].set(
        ylabel=f"F/F_H - 1 at {cfg['fit']['delta_ref'] * 1e3:g} mm",
        title=title or "Deviation from Hertz",
    )
    ax[0, 0].set_yscale("symlog", linthresh=0.1)
    ax[0, 0].legend(fontsize=8)
    _save(fig, output)


def plot_k(paths: list[str], output: str, cfg: dict[str, Any], title: str = "") -> None:
    """K vs soil E for each nu: nodes, interpolant and the fits' max relative residual.

    Parameters
    ----------
    paths : list of str
        The input files; the first is the K table (HDF5).
    output : str
        The PNG file to write.
    cfg : dict
        The validated study config.
    title : str
        The figure's title; empty: a default.
    """
    from ssw.fit.table import load_tables

    tables, _ = load_tables(paths[0])
    fig, ax = _figure(2)
    for tb in tables:
        if "k_hertz" not in tb.params:
            continue
        Ef = np.geomspace(tb.soil_E[0], tb.soil_E[-1], 400)
        for j, nu in enumerate(tb.soil_nu):
            (ln,) = ax[0, 0].semilogx(
                tb.soil_E / 1e6,
                tb.params["k_hertz"]["K"][j],
                "o",
                ms=3,
                label=f"{tb.name}, nu {nu:g}",
            )
            ax[0, 0].semilogx(Ef / 1e6, tb.K(Ef, nu), color=ln.get_color(), lw=1)
            for law, ls in zip(tb.residuals, ("-", "--", ":"), strict=False):
                ax[1, 0].loglog(
                    tb.soil_E / 1e6,
                    tb.residuals[law]["max_rel_residual"][j],
                    ls=ls,
                    color=ln.get_color(),
                    label=f"{law}, nu {nu:g}",
                )
    err = tables[0].interp_error().get("K", float("nan")) if tables else float("nan")
    ax[0, 0].set(
        xlabel="soil E (MPa)",
        ylabel="K",
        title=title or f"K(E, nu) fits; stated interpolation error {err:.2%}",
    )
    ax[1, 0].set(xlabel="soil E (MPa)", ylabel="max |F_fit/F - 1| on the fit range")
    ax[0, 0].legend(fontsize=7)
    ax[1, 0].legend(fontsize=6, ncol=2)
    _save(fig, output)


PLOTS: dict[str, Callable[[list[str], str, dict[str, Any], str], None]] = {
    "curves": plot_curves,
    "deviation": plot_deviation,
    "k": plot_k,
}
