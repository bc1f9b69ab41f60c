"""The design's table (CSV) and figure (Pareto front of sensitivity against the sample's
yield index, and the sensitivity curves over the soil range)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

#: Columns of the candidates' table (the JSON's candidate fields; SI units).
COLUMNS = ("material", "thickness", "plate_diameter", "striker_velocity", "source",
           "sensitivity", "resolution", "plate_yield_index", "soil_yield_index",
           "soil_peak_strain", "mass_ratio", "feasible", "merit")


def check_columns(candidates: list[dict[str, Any]]) -> list[str]:
    """The checks (:data:`ssw.validity.RULES` order) any candidate's record carries.

    Parameters
    ----------
    candidates : list of dict of str to Any
        The candidates' JSON records.

    Returns
    -------
    list of str
        The check names.
    """
    from ssw.validity import RULES

    have = {e["check"] for c in candidates for e in c.get("validity", [])}
    return [k for k in RULES if k in have]


def table_text(result: dict[str, Any]) -> str:
    """The candidates of an ``ssw design`` result as CSV (best merit first; the recommended
    one flagged). After ``recommended``, each check's worst value over the soils
    (``check_<name>``, dimensionless; :mod:`ssw.validity`) and ``checks_failed`` (their
    names, ``;``-joined).

    Parameters
    ----------
    result : dict of str to Any
        The JSON of an ``ssw design`` result.

    Returns
    -------
    str
        The CSV text (SI units), one line per candidate after the header.
    """
    rec = result["recommended"]
    key = (rec["material"], rec["thickness"], rec["plate_diameter"], rec["striker_velocity"])
    checks = check_columns(result["candidates"])
    tail = [f"check_{k}" for k in checks] + (["checks_failed"] if checks else [])
    lines = [",".join((*COLUMNS, "recommended", *tail))]
    for c in result["candidates"]:
        mine = (c["material"], c["thickness"], c["plate_diameter"], c["striker_velocity"])
        vals = [c[k] for k in COLUMNS]
        line = (",".join(f"{v:.6g}" if isinstance(v, float) else str(v) for v in vals)
                + f",{mine == key}")
        if checks:
            got = {e["check"]: e for e in c.get("validity", [])}
            line += "," + ",".join("" if k not in got or got[k]["value"] is None
                                   else f"{got[k]['value']:.4g}" for k in checks)
            line += "," + ";".join(k for k in checks if k in got and not got[k]["holds"])
        lines.append(line)
    return "\n".join(lines) + "\n"


def write_table(path: str | Path, result: dict[str, Any], inputs: Any) -> None:
    """:func:`table_text` to ``path`` atomically, with its provenance line.

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file.
    result : dict of str to Any
        The JSON of an ``ssw design`` result.
    inputs : Any
        What the provenance line records (:func:`ssw.h5io.write_csv_text`).
    """
    from ssw.h5io import write_csv_text

    write_csv_text(path, table_text(result), inputs)


def plot(path: str | Path, result: dict[str, Any]) -> None:
    """Left: every candidate's worst-case sensitivity against its soil yield index (filled:
    the plate stays elastic and light; the Pareto front joined; the recommended ringed;
    the device's own plate a star). Right: the sensitivity curves over the soil range of
    the recommended plate, the device's, and each material's best.

    Parameters
    ----------
    path : str or pathlib.Path
        The PNG file.
    result : dict of str to Any
        The JSON of an ``ssw design`` result.
    """
    from ssw.plotting import pyplot, save_png

    plt = pyplot()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.4))
    mats = sorted({c["material"] for c in result["candidates"]})
    colors = {m: f"C{i}" for i, m in enumerate(mats)}
    for m in mats:
        cs = [c for c in result["candidates"] if c["material"] == m]
        ok = [c for c in cs if c["plate_yield_index"] <= 1 and not c["violations"]["mass_ratio"]]
        bad = [c for c in cs if c not in ok]
        ax.scatter([c["soil_yield_index"] for c in ok], [c["sensitivity"] for c in ok],
                   color=colors[m], label=f"{m} (plate elastic)" if ok else None, s=18)
        ax.scatter([c["soil_yield_index"] for c in bad], [c["sensitivity"] for c in bad],
                   facecolors="none", edgecolors=colors[m], s=18,
                   label=f"{m} (plate yields)" if bad else None)
    front = result.get("pareto", [])
    if front:
        ax.plot([c["soil_yield_index"] for c in front], [c["sensitivity"] for c in front],
                "k-", lw=0.8, label="Pareto front (elastic plates)")
    rec = result["recommended"]
    ax.scatter([rec["soil_yield_index"]], [rec["sensitivity"]], s=120, facecolors="none",
               edgecolors="k", lw=1.5, label=f"recommended: {_label(rec)}")
    ref = result.get("reference")
    if ref:
        ax.scatter([ref["soil_yield_index"]], [ref["sensitivity"]], marker="*", s=120,
                   color="k", label=f"device's plate: {_label(ref)}")
    ax.set_xscale("log")
    ax.set_xlabel("soil yield index (max peak von Mises / soil strength, elastic field)")
    ax.set_ylabel("worst-case sensitivity |d ln TOF / d ln E|")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    E = np.asarray(result["soil_E"], float)
    curves = [("recommended", rec)] + ([("device", ref)] if ref else [])
    for m in mats:
        cs = [c for c in result["candidates"] if c["material"] == m and c["source"] != "reference"]
        if cs:
            curves.append((f"best {m}", min(cs, key=lambda c: c["merit"])))
    for name, c in curves:
        bx.semilogx(E / 1e6, c["sensitivity_E"], label=f"{name}: {_label(c)}")
    bx.set_xlabel("soil E (MPa)")
    bx.set_ylabel("sensitivity |d ln TOF / d ln E|")
    bx.grid(alpha=0.3, which="both")
    bx.legend(fontsize=7)
    lo, hi = E[0], E[-1]
    fig.suptitle(f"ssw design: plates for soils {lo / 1e6:g}-{hi / 1e6:g} MPa "
                 f"(nu {result['spec']['soil_nu']:g})", fontsize=10)
    fig.tight_layout()
    save_png(fig, path, dpi=130)


def _label(c: dict[str, Any]) -> str:
    return f"{c['material']} {c['thickness'] * 1e3:.3g} mm"
