"""Survey studies: the moduli of many field test points, against their targets.

A survey (config section ``survey:``) lists test points: an id, the recordings of its hits,
the medium's Poisson's ratio (or a range), optional coordinates (``x``/``y`` in m, or
``latitude``/``longitude`` in degrees), a layer or lift, and what the point must reach:
a ``target_E`` (Pa), or a ``reference_E`` (the lab modulus of the compacted material, Pa)
with a ``required_ratio`` (compaction control: the field modulus relative to the lab one).

Each point is measured by ``ssw measure`` (one Snakemake job per point, its JSON result);
:func:`survey_table` gathers them, and each point gets a verdict from its 95 % interval
``[E_low, E_high]`` and its target ``E_t`` (a decision with the measurement's uncertainty in
view, as in ISO 14253-1's conformity zones):

* ``pass``: ``E_low >= E_t`` (the point meets the target even at the low end);
* ``fail``: ``E_high < E_t`` (it misses the target even at the high end);
* ``inconclusive``: the interval straddles the target (measure more hits, or accept the
  risk knowingly), or the interval lacks a term of its budget (``missing_terms`` of the
  measurement: too few hits to estimate the TOF's scatter, an uncalibrated device, a wall
  law without a stated error): an incomplete interval decides nothing;
* ``no target``: none was given.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ssw.errors import ConfigError
from ssw.h5io import atomic_h5, write_dataset, write_rows_csv

KIND = "survey"
VERDICTS = ("pass", "fail", "inconclusive", "no target")


@dataclass(frozen=True)
class SurveyRow:
    """One test point's result (SI; ratio dimensionless)."""

    id: str
    E: float
    E_low: float
    E_high: float
    E_u_pct: float
    target_E: float | None
    reference_E: float | None
    ratio: float | None  # E / reference_E
    verdict: str
    missing_terms: str  # the budget terms the interval lacks ("" when complete)
    tof_mean: float
    tof_sem: float
    n_accepted: int
    n_hits: int
    nu: float
    nu_lo: float | None
    nu_hi: float | None
    x: float | None
    y: float | None
    latitude: float | None
    longitude: float | None
    layer: str | None
    synthetic: bool


def point_target(point: dict[str, Any]) -> float | None:
    """``target_E``, or ``required_ratio x reference_E``, or None (Pa)."""
    if point.get("target_E") is not None:
        return float(point["target_E"])
    if point.get("reference_E") is not None:
        return float(point.get("required_ratio", 1.0)) * float(point["reference_E"])
    return None


def verdict(E_low: float, E_high: float, target: float | None, complete: bool = True) -> str:
    """The conformity verdict of an interval against a target (module docstring): an
    interval that lacks a term of its budget (``complete`` False) is inconclusive."""
    if target is None:
        return "no target"
    if not complete:
        return "inconclusive"
    if E_low >= target:
        return "pass"
    if E_high < target:
        return "fail"
    return "inconclusive"


def survey_table(points: list[dict[str, Any]], results: list[dict[str, Any]]) -> list[SurveyRow]:
    """One row per point from its config entry and its ``ssw measure --json`` result."""
    if len(points) != len(results):
        raise ConfigError("survey results", len(results), f"one per point ({len(points)})")
    rows = []
    for pt, r in zip(points, results, strict=True):
        tgt = point_target(pt)
        ref = pt.get("reference_E")
        rng = r.get("nu_range")
        rows.append(SurveyRow(
            id=pt["id"], E=float(r["E"]), E_low=float(r["E_low"]), E_high=float(r["E_high"]),
            E_u_pct=float(r["E_u_pct"]), target_E=tgt,
            reference_E=None if ref is None else float(ref),
            ratio=None if ref is None else float(r["E"]) / float(ref),
            verdict=verdict(float(r["E_low"]), float(r["E_high"]), tgt,
                            not r.get("missing_terms")),
            missing_terms="; ".join(f"{k}: {v}" for k, v in
                                    (r.get("missing_terms") or {}).items()),
            tof_mean=float(r["tof_mean"]),
            tof_sem=float("nan") if r.get("tof_sem") is None else float(r["tof_sem"]),
            n_accepted=int(r["n_accepted"]), n_hits=int(r["n_hits"]), nu=float(r["nu"]),
            nu_lo=None if rng is None else float(rng[0]),
            nu_hi=None if rng is None else float(rng[1]),
            x=pt.get("x"), y=pt.get("y"), latitude=pt.get("latitude"),
            longitude=pt.get("longitude"), layer=pt.get("layer"),
            synthetic=bool(r.get("synthetic", False)),
        ))
    return rows


UNITS = {"E": "Pa", "E_low": "Pa", "E_high": "Pa", "E_u_pct": "%", "target_E": "Pa",
         "reference_E": "Pa", "ratio": "1", "tof_mean": "s", "tof_sem": "s",
         "n_accepted": "1", "n_hits": "1", "nu": "1", "nu_lo": "1", "nu_hi": "1", "x": "m",
         "y": "m", "latitude": "deg", "longitude": "deg"}


def write_survey(csv_path: str | Path, h5_path: str | Path, rows: list[SurveyRow],
                 inputs: dict[str, Any]) -> None:
    """The survey table as CSV (``name [unit]`` headers) and HDF5 (one dataset per column)."""
    dicts = [asdict(r) for r in rows]
    named = [{(f"{k} [{UNITS[k]}]" if k in UNITS else k): ("" if v is None else v)
              for k, v in d.items()} for d in dicts]
    write_rows_csv(named, csv_path)
    with atomic_h5(h5_path, kind=KIND, inputs=inputs) as f:
        for k in dicts[0] if dicts else []:
            vals = [d[k] for d in dicts]
            if k in UNITS:
                arr = np.array([np.nan if v is None else v for v in vals], float)
                write_dataset(f, k, arr, UNITS[k])
            else:
                import h5py

                f.create_dataset(k, data=["" if v is None else str(v) for v in vals],
                                 dtype=h5py.string_dtype())


def plot_survey(path: str | Path, rows: list[SurveyRow], title: str = "") -> None:
    """E per point with its 95 % interval against its target, coloured by verdict."""
    from ssw.plotting import pyplot, save_png

    plt = pyplot()
    colors = {"pass": "tab:green", "fail": "tab:red", "inconclusive": "tab:orange",
              "no target": "tab:gray"}
    fig, ax = plt.subplots(figsize=(max(5.0, 0.6 * len(rows) + 2), 4.2))
    xs = np.arange(len(rows))
    for i, r in enumerate(rows):
        ax.errorbar(i, r.E / 1e6, yerr=[[(r.E - r.E_low) / 1e6], [(r.E_high - r.E) / 1e6]],
                    fmt="o", color=colors[r.verdict], capsize=4,
                    label=r.verdict if r.verdict not in [q.verdict for q in rows[:i]] else None)
        if r.target_E is not None:
            ax.plot([i - 0.3, i + 0.3], [r.target_E / 1e6] * 2, "k--", lw=1)
    ax.set_xticks(xs, [r.id for r in rows], rotation=45, ha="right")
    ax.set_ylabel("E (MPa), 95 % interval; dashed: target")
    syn = " (SYNTHETIC data)" if any(r.synthetic for r in rows) else ""
    ax.set_title((title or "Survey: modulus per test point") + syn)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_png(fig, path, dpi=150)


def plot_map(path: str | Path, rows: list[SurveyRow], title: str = "") -> bool:
    """Plan view of the points with coordinates, E as colour, verdict as marker; False (and
    no file) when no point has coordinates."""
    from ssw.plotting import pyplot, save_png

    xy = [(r.x, r.y, "m") for r in rows if r.x is not None]
    geo = [(r.longitude, r.latitude, "deg") for r in rows if r.latitude is not None]
    pts = xy if len(xy) >= len(geo) else geo
    if not pts:
        return False
    sel = [r for r in rows if (r.x is not None if pts is xy else r.latitude is not None)]
    plt = pyplot()
    markers = {"pass": "o", "fail": "X", "inconclusive": "s", "no target": "^"}
    fig, ax = plt.subplots(figsize=(5.6, 4.8))
    E = np.array([r.E for r in sel]) / 1e6
    vmin, vmax = float(E.min()), float(E.max())
    sc = None
    for v, mk in markers.items():
        idx = [i for i, r in enumerate(sel) if r.verdict == v]
        if idx:
            sc = ax.scatter([pts[i][0] for i in idx], [pts[i][1] for i in idx], c=E[idx],
                            vmin=vmin, vmax=vmax, marker=mk, s=90, cmap="viridis",
                            edgecolors="k", label=v)
    for i, r in enumerate(sel):
        ax.annotate(r.id, (pts[i][0], pts[i][1]), textcoords="offset points", xytext=(6, 6),
                    fontsize=8)
    if sc is not None:
        fig.colorbar(sc, ax=ax, label="E (MPa)")
    unit = pts[0][2]
    ax.set_xlabel("x (m)" if unit == "m" else "longitude (deg)")
    ax.set_ylabel("y (m)" if unit == "m" else "latitude (deg)")
    if unit == "m":
        ax.set_aspect("equal", adjustable="datalim")
    syn = " (SYNTHETIC data)" if any(r.synthetic for r in rows) else ""
    ax.set_title((title or "Survey plan view") + syn)
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save_png(fig, path, dpi=150)
    return True


def read_results(paths: list[str | Path]) -> list[dict[str, Any]]:
    """The ``ssw measure --json`` results of the points."""
    out = []
    for p in paths:
        try:
            out.append(json.loads(Path(p).read_text()))
        except (OSError, ValueError) as exc:
            raise ConfigError("survey result", str(p), f"a `ssw measure --json` file ({exc})") \
                from exc
    return out
