"""The device design's table (CSV) and figure: the Pareto fronts of resolution against the
sample's yield index and against the device's mass, the recommended and base devices."""

from __future__ import annotations

from pathlib import Path
from typing import Any

#: Columns of the candidates' table (the JSON's candidate fields; SI units).
COLUMNS = ("bead_material", "bead_diameter", "beads", "sensor_index", "sensor_mass_ratio",
           "striker_mass_ratio", "drop_height", "plate_material", "plate_thickness",
           "plate_diameter", "source", "step", "resolution", "sensitivity", "overlap_index",
           "round_trip_index", "detection_index", "range_index", "bead_yield_index",
           "plate_yield_index", "plate_mass_ratio", "mass", "length", "soil_yield_index",
           "feasible", "hard_feasible", "merit")
#: Columns of the plastic check (empty for a device not struck): the plate's dent and the
#: sample's set after the last hit (m), the TOF drift from the first hit to the last (s),
#: its size over the device's TOF uncertainty, the soil struck (Pa), why a device could
#: not be struck.
PLASTIC_COLUMNS = ("plate_dent", "soil_set", "tof_drift", "drift_over_u_tof", "soil_E",
                   "error")
_KEY = ("bead_material", "bead_diameter", "beads", "sensor_index", "sensor_mass_ratio",
        "striker_mass_ratio", "drop_height", "plate_material", "plate_thickness")


def table_text(result: dict[str, Any]) -> str:
    """The candidates of a device design as CSV (ranked; the recommended and the base
    device flagged; then each check's worst value over the soils, ``check_<name>``, and
    ``checks_failed``: :mod:`ssw.validity`).

    Parameters
    ----------
    result : dict of str to Any
        The JSON of an ``ssw design --space device`` result.

    Returns
    -------
    str
        The CSV text (SI units), one line per candidate after the header.
    """
    def key(c: dict[str, Any]) -> tuple[Any, ...]:
        return tuple(c[k] for k in _KEY)

    rec = key(result["recommended"])
    ref = key(result["reference"]) if result.get("reference") else None
    def cell(v: Any) -> str:
        if v is None:
            return ""
        if isinstance(v, float):
            return f"{v:.6g}"
        return '"' + str(v).replace('"', "'") + '"' if "," in str(v) else str(v)

    from ssw.design.output import check_columns

    checks = check_columns(result["candidates"])
    tail = [f"check_{k}" for k in checks] + (["checks_failed"] if checks else [])
    lines = [",".join((*COLUMNS, *(f"plastic_{k}" for k in PLASTIC_COLUMNS), "recommended",
                       "base_device", *tail))]
    for c in result["candidates"]:
        pl = c.get("plastic") or {}
        got = {e["check"]: e for e in c.get("validity", [])}
        vals = [c[k] for k in COLUMNS] + [pl.get(k) for k in PLASTIC_COLUMNS] + [
            key(c) == rec, key(c) == ref]
        if checks:  # each check's worst over the soils (ssw.validity), then the failing
            vals += [got[k]["value"] if k in got else None for k in checks]
            vals.append(";".join(k for k in checks if k in got and not got[k]["holds"]))
        lines.append(",".join(cell(v) for v in vals))
    return "\n".join(lines) + "\n"


def write_table(path: str | Path, result: dict[str, Any], inputs: Any) -> None:
    """:func:`table_text` to ``path`` atomically, with its provenance line.

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file.
    result : dict of str to Any
        The JSON of an ``ssw design --space device`` result.
    inputs : Any
        What the provenance line records (:func:`ssw.h5io.write_csv_text`).
    """
    from ssw.h5io import write_csv_text

    write_csv_text(path, table_text(result), inputs)


def plot(path: str | Path, result: dict[str, Any]) -> None:
    """Left: worst-case resolution against the soil yield index; right: against the mass.
    Devices with dE/E >= 1 (their TOF hardly moves with E) are left out. Filled: every hard
    limit met; hollow: one broken; the Pareto fronts joined; the
    recommended ringed; the base device a star. Written atomically (PNG).

    Parameters
    ----------
    path : str or pathlib.Path
        The PNG file.
    result : dict of str to Any
        The JSON of an ``ssw design --space device`` result.
    """
    from ssw.plotting import pyplot, save_png

    plt = pyplot()
    pred = result.get("prediction")
    fig, axes = plt.subplots(1, 3 if pred else 2, figsize=(16 if pred else 11, 4.4))
    # a device whose TOF hardly moves with E (dE/E >= 1: no measurement) is left out
    cands = [c for c in result["candidates"] if c["resolution"] < 1.0]
    mats = sorted({c["bead_material"] for c in cands})
    colors = {m: f"C{i}" for i, m in enumerate(mats)}
    rec, ref = result["recommended"], result.get("reference")
    for ax, xkey, front, xlabel in (
            (axes[0], "soil_yield_index", result["pareto_soil"],
             "soil yield index (peak von Mises / soil strength)"),
            (axes[1], "mass", result["pareto_mass"], "device mass (kg)")):
        for m in mats:
            ok = [c for c in cands if c["bead_material"] == m and c["hard_feasible"]]
            bad = [c for c in cands if c["bead_material"] == m and not c["hard_feasible"]]
            ax.scatter([c[xkey] for c in ok], [c["resolution"] for c in ok], s=12,
                       color=colors[m], label=f"{m} beads (hard limits met)" if ok else None)
            ax.scatter([c[xkey] for c in bad], [c["resolution"] for c in bad], s=12,
                       facecolors="none", edgecolors=colors[m], alpha=0.5,
                       label=f"{m} beads (a hard limit broken)" if bad else None)
        if front:
            ax.plot([c[xkey] for c in front], [c["resolution"] for c in front], "k-", lw=0.8,
                    label="Pareto front")
        ax.scatter([rec[xkey]], [rec["resolution"]], s=140, facecolors="none",
                   edgecolors="k", lw=1.5, label="recommended")
        if ref:
            ax.scatter([ref[xkey]], [ref["resolution"]], marker="*", s=140, color="k",
                       label="base (thesis) device")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("worst-case resolution dE/E")
        ax.grid(alpha=0.3, which="both")
    axes[0].legend(fontsize=6)
    if pred:
        _plot_prediction(axes[2], pred)
    lo, hi = result["spec"]["soil_E"]
    fig.suptitle(f"ssw design --space device: soils {lo / 1e6:g}-{hi / 1e6:g} MPa "
                 f"(nu {result['spec']['soil_nu']:g}); recommended: "
                 f"{result['recommended']['label']}", fontsize=9)
    fig.tight_layout()
    save_png(fig, path, dpi=130)


def _plot_prediction(ax: Any, pred: dict[str, Any]) -> None:
    """The predicted 95 % half-width of E per point against the soil's modulus, the
    recommended (solid) and the base device (dashed), at each level
    (:mod:`ssw.design.predict`)."""
    for name, style in (("recommended", "-"), ("reference", "--")):
        d = pred["devices"].get(name)
        if d is None:
            continue
        for lv, color in (("tof", "C0"), ("features", "C3")):
            hw = [float("nan") if v is None else 100 * v
                  for v in d[lv]["point"]["half_width"]]
            ax.plot(d["soil_E"], hw, style, color=color, marker="o", ms=3,
                    label=f"{name if name == 'recommended' else 'base'}, {lv}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("soil modulus E (Pa)")
    ax.set_ylabel(f"predicted 95 % half-width of E per {pred['point_hits']}-hit point (%)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=6)


def human(res: dict[str, Any]) -> str:
    """The recommended device beside the base device, and the reasons.

    Parameters
    ----------
    res : dict of str to Any
        The JSON of an ``ssw design --space device`` result.

    Returns
    -------
    str
        The text for the terminal (SI units unless a row names its own).
    """
    rec, ref = res["recommended"], res.get("reference")
    rows = [("resolution", "dE/E"), ("sensitivity", "min |dlnTOF/dlnE|"),
            ("soil_yield_index", "soil yield"), ("plate_yield_index", "plate yield"),
            ("bead_yield_index", "bead yield"), ("overlap_index", "pulse overlap"),
            ("round_trip_index", "round trip"), ("mass", "mass kg"), ("length", "length m")]
    lines = [f"{res['evaluations']} devices ({res['feasible']} feasible) in "
             f"{res['wall_time']:.1f} s wall, {res['cpu_time']:.1f} s CPU",
             f"recommended: {rec['label']}"]
    if ref:
        lines.append(f"base:        {ref['label']}")
    lines.append(f"{'':20s} {'recommended':>12s} {'base':>12s}")
    for k, name in rows:
        lines.append(f"{name:20s} {rec[k]:12.4g} " + (f"{ref[k]:12.4g}" if ref else ""))
    lines.append(f"{'feasible':20s} {rec['feasible']!s:>12s} "
                 + (f"{ref['feasible']!s:>12s}" if ref else ""))
    lines += [f"  - {r}" for r in rec["reasons"]]
    if rec.get("validity"):  # ssw.validity, the worst soil of the range
        lines.append("  checks failing on some soil of the range: "
                     + ("; ".join(rec["checks_failed"]) or "none"))
    if res.get("prediction"):  # ssw.design.predict
        from ssw.design.predict import human_lines

        lines += human_lines(res["prediction"])
    if res.get("prototype"):  # ssw.design.prototype
        pt = res["prototype"]
        lines.append(f"virtual prototype ({pt['hits']} hits per sample, striker scatter "
                     f"{100 * pt['striker_cov']:g} %): calibrated "
                     + ", ".join(f"{k} {v:.4g}" for k, v in pt["calibration"].items()))
        for r in pt["unseen"]:
            lines.append(f"  E {r['E_true'] / 1e6:.4g} MPa: measured {r['E'] / 1e6:.4g} MPa "
                         f"({100 * r['error']:+.3g} %), 95 % width {100 * r['width']:.3g} % "
                         f"(predicted {100 * r['width_predicted']:.3g} %), "
                         + ("inside" if r["inside"] else "OUTSIDE"))
    for chk in res.get("plastic_check") or []:
        head = (f"{chk['hits']} hits, {chk['label']} on E {chk['soil_E']:.4g} Pa (von Mises "
                f"Y {chk['soil_yield_stress']:.3g} Pa): ")
        if chk["error"]:
            lines.append(head + f"not struck ({chk['error']})")
        else:
            lines.append(head + f"plate dent {chk['plate_dent'] * 1e6:.3g} um, sample set "
                         f"{chk['soil_set'] * 1e6:.3g} um, TOF drift "
                         f"{chk['tof_drift'] * 1e6:.3g} us ({chk['drift_over_u_tof']:.3g} "
                         f"u_TOF)")
    return "\n".join(lines)
