"""Figures of Stage I: force vs indentation of several scenes with the Hertz law of the soil.

The analogues of the thesis's Fig 5 (plate materials) and Fig 6 (plate thicknesses):
log-log force-indentation curves, each with the rigid-sphere Hertz law
``F_H = 4/3 E/(1-nu^2) sqrt(R) delta^1.5`` of its soil (Johnson 1985, eq. 4.22) dashed.
"""

from __future__ import annotations

from pathlib import Path

from ssw import hertz
from ssw.curve import ForceCurve
from ssw.h5io import atomic_path


def _label(c: ForceCurve, label_by: str) -> str:
    inp = c.inputs
    if inp.get("plate_thickness", 0) == 0:
        return "no plate"
    if label_by == "thickness":
        return f"{inp['plate_material']} {inp['plate_thickness'] * 1e3:g} mm"
    return f"{inp['plate_material']} ({inp['plate_thickness'] * 1e3:g} mm)"


def plot_curves(
    curves: list[ForceCurve], output: str | Path, label_by: str = "material", title: str = ""
) -> None:
    """Write a PNG of the curves (force N vs indentation mm) with their soils' Hertz laws.

    Parameters
    ----------
    curves : list of ForceCurve
        The curves (SI).
    output : str or pathlib.Path
        The PNG file, written atomically.
    label_by : str
        What the legend names (``material``, ...).
    title : str
        The figure's title; empty: none.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    soils = {}
    order = sorted(curves, key=lambda c: (c.inputs.get("plate_thickness", 0),
                                          c.inputs.get("plate_E") or 0))
    for c in order:
        ax.loglog(c.delta * 1e3, c.force, label=_label(c, label_by))
        soils[(c.inputs["soil_E"], c.inputs["soil_nu"], c.inputs["indenter_radius"])] = c.delta
    for (E, nu, R), d in soils.items():
        fh = hertz.force(d, hertz.effective_modulus(E, nu), R)
        ax.loglog(d * 1e3, fh, "k--", lw=1,
                  label=f"Hertz, soil E = {E / 1e6:g} MPa, nu = {nu:g}")
    ax.set_xlabel("indentation (mm)")
    ax.set_ylabel("force (N)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    with atomic_path(output) as tmp:
        fig.savefig(tmp, format="png", dpi=150)
    plt.close(fig)
