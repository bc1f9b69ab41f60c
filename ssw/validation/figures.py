"""Figures of the validation: Fig 10 (measured vs simulated TOF on the foams) and Fig 9
(TOF scatter of repeated hits). Matplotlib with the Agg backend; files written atomically."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ssw.plotting import pyplot, save_png
from ssw.validation.table import SampleResult

#: Thesis Fig 9: TOF standard deviation of three hits on a soil sample (2.03 g/cm3, 14.31 %
#: moisture), unmodified device and with the 0.4 mm PLA plate, s.
FIG9_STD_NO_PLATE = 6.56e-5
FIG9_STD_PLATE = 1.53e-5


def plot_fig10(path: str | Path, rows: list[SampleResult],
               curves: dict[float, tuple[np.ndarray, np.ndarray]],
               sweep_curves: dict[float, tuple[np.ndarray, np.ndarray]] | None = None) -> None:
    """TOF vs E: the model's curve at each sample's nu, simulated and measured points.

    ``curves`` maps nu to ``(E, TOF)`` (Pa, s) from the chain model; ``sweep_curves`` the
    same from the workflow's stored sweep (thesis Fig 8), drawn dashed.

    Parameters
    ----------
    path : str or Path
        The PNG file.
    rows : list of SampleResult
        The validation rows (their simulated, measured and published TOFs).
    curves : dict of float to tuple of numpy.ndarray
        nu -> ``(E, TOF)`` (Pa, s) of the chain model.
    sweep_curves : dict of float to tuple of numpy.ndarray or None
        nu -> ``(E, TOF)`` (Pa, s) of the stored sweep, or None.
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for nu, (E, T) in sorted((sweep_curves or {}).items()):
        ax.plot(E / 1e6, T * 1e3, "--", lw=0.8, color="0.5")
        ax.annotate(f"sweep nu = {nu:g}", (E[0] / 1e6, T[0] * 1e3), fontsize=7, color="0.4")
    for nu, (E, T) in sorted(curves.items()):
        ax.plot(E / 1e6, T * 1e3, lw=1, label=f"model, nu = {nu:g}")
    E = np.array([r.E_manufacturer for r in rows]) / 1e6
    ax.plot(E, [r.tof_sim * 1e3 for r in rows], "o", mfc="none", ms=8, label="simulated (ssw)")
    yerr = [0.0 if r.tof_measured_std is None else r.tof_measured_std * 1e3 for r in rows]
    src = {r.tof_source for r in rows}
    ax.errorbar(E, [r.tof_measured * 1e3 for r in rows], yerr=yerr, fmt="s", capsize=3,
                label=f"measured ({', '.join(sorted(src))})")
    pub = [(e, r.tof_sim_published) for e, r in zip(E, rows, strict=True) if r.tof_sim_published]
    if pub:
        ax.plot(*np.array(pub).T * [[1], [1e3]], "x", ms=8, label="thesis simulated (Table 2)")
    for e, r in zip(E, rows, strict=True):
        ax.annotate(r.sample, (e, r.tof_measured * 1e3), textcoords="offset points",
                    xytext=(5, 5), fontsize=8)
    ax.set_xscale("log")
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("Young's modulus E (MPa)")
    ax.set_ylabel("TOF (ms)")
    ax.set_title("Measured and simulated TOF on the control foams (thesis Fig 10)")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    save_png(fig, path, dpi=120)


def plot_fig9(path: str | Path, rows: list[SampleResult]) -> None:
    """Per-hit TOF minus the session mean (us) for every sample with a recording, with the
    thesis's soil-sample standard deviations (no plate / PLA plate) as reference bands.

    Parameters
    ----------
    path : str or Path
        The PNG file.
    rows : list of SampleResult
        The validation rows (those with per-hit TOFs are drawn).
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for std, label, style in ((FIG9_STD_NO_PLATE, "thesis soil, no plate: std", ":"),
                              (FIG9_STD_PLATE, "thesis soil, PLA plate: std", "--")):
        ax.axhspan(-std * 1e6, std * 1e6, alpha=0.08)
        ax.axhline(std * 1e6, ls=style, lw=1, color="k", label=f"{label} {std * 1e6:.1f} us")
        ax.axhline(-std * 1e6, ls=style, lw=1, color="k")
    shown = [r for r in rows if r.tof_per_hit]
    for r in shown:
        t = np.asarray(r.tof_per_hit)
        tag = " (synthetic)" if r.synthetic else ""
        std = r.tof_measured_std or 0.0
        ax.plot(np.arange(1, t.size + 1), (t - t.mean()) * 1e6, "o-", ms=4,
                label=f"{r.sample}{tag}: std {std * 1e6:.2f} us")
    if not shown:
        ax.text(0.5, 0.5, "no recordings in the config: only the thesis's values",
                transform=ax.transAxes, ha="center")
    ax.set_xlabel("hit")
    ax.set_ylabel("TOF - session mean (us)")
    ax.set_title("TOF scatter of repeated hits (thesis Fig 9)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    save_png(fig, path, dpi=120)
