"""A survey's table: each point's result gathered from its ``ssw measure`` JSON
(:func:`read_results`), its target (:func:`point_target`) and its verdict from its 95 %
interval (:func:`verdict`, :mod:`ssw.survey`), one :class:`SurveyRow` a point
(:func:`survey_table`), written as CSV and HDF5 (:func:`write_survey`).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ssw.errors import ConfigError
from ssw.h5io import atomic_h5, write_dataset, write_rows_csv
from ssw.survey.geo import Frame, local_to_wgs84

KIND = "survey"
VERDICTS = ("pass", "fail", "inconclusive", "no target")


@dataclass(frozen=True)
class SurveyRow:
    """One test point's result (SI; ratio dimensionless).

    Parameters
    ----------
    id : str
        The point's id.
    E : float
        The point's Young's modulus, Pa.
    E_low : float
        The interval's low end, Pa.
    E_high : float
        The interval's high end, Pa.
    E_u_pct : float
        The relative uncertainty of ``E``, %.
    target_E : float or None
        The point's target, Pa.
    reference_E : float or None
        The point's reference modulus, Pa.
    ratio : float or None
        ``E / reference_E``.
    verdict : str
        The verdict (:func:`verdict`).
    missing_terms : str
        The budget terms the interval lacks (empty when complete).
    tof_mean : float
        The mean TOF, s.
    tof_sem : float
        Its standard error, s (NaN: unknown).
    n_accepted : int
        Hits accepted.
    n_hits : int
        Hits recorded.
    nu : float
        The soil's Poisson's ratio used.
    nu_lo : float or None
        The low end of its range.
    nu_hi : float or None
        The high end of its range.
    x : float or None
        The point's x, m.
    y : float or None
        The point's y, m.
    latitude : float or None
        WGS84 latitude, degrees.
    longitude : float or None
        WGS84 longitude, degrees.
    layer : str or None
        The soil layer tested.
    synthetic : bool
        Whether the recordings are synthetic.
    checks_failed : str
        The measurement's failing checks, joined by ``"; "``.
    reason : str
        Why the verdict is inconclusive, when it is.
    """

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
    checks_failed: str = ""  # the measurement's failing checks (ssw.validity), "; "-joined
    reason: str = ""  # why the verdict is inconclusive, when it is


def point_target(point: dict[str, Any]) -> float | None:
    """``target_E``, or ``required_ratio x reference_E``, or None (Pa).

    Parameters
    ----------
    point : dict
        The survey point (``target_E``, ``reference_E``, ``required_ratio``; Pa).

    Returns
    -------
    float or None
        The target modulus, Pa; None when the point has no target.
    """
    if point.get("target_E") is not None:
        return float(point["target_E"])
    if point.get("reference_E") is not None:
        return float(point.get("required_ratio", 1.0)) * float(point["reference_E"])
    return None


def verdict(E_low: float, E_high: float, target: float | None, complete: bool = True,
            failed: tuple[str, ...] | list[str] = ()) -> str:
    """The conformity verdict of an interval against a target (:mod:`ssw.survey`).

    Parameters
    ----------
    E_low : float
        The interval's low end, Pa.
    E_high : float
        Its high end, Pa.
    target : float or None
        The point's target, Pa (None: no target).
    complete : bool
        Whether the interval has every term of its budget (False: inconclusive).
    failed : sequence of str
        The measurement's failing checks (:mod:`ssw.validity`; any: inconclusive).

    Returns
    -------
    str
        One of ``VERDICTS``: ``pass``, ``fail``, ``inconclusive``, ``no target``.
    """
    if target is None:
        return "no target"
    if not complete or failed:
        return "inconclusive"
    if E_low >= target:
        return "pass"
    if E_high < target:
        return "fail"
    return "inconclusive"


def verdict_reason(E_low: float, E_high: float, target: float | None, complete: bool,
                   failed: tuple[str, ...] | list[str], missing: str = "") -> str:
    """Why :func:`verdict` is ``inconclusive`` ("" otherwise): the failing checks, the
    missing budget terms, or the interval straddling the target (same parameters, Pa;
    ``missing`` the missing terms in words).

    Parameters
    ----------
    E_low : float
        The interval's low end, Pa.
    E_high : float
        Its high end, Pa.
    target : float or None
        The point's target, Pa (None: no target).
    complete : bool
        Whether the interval has every term of its budget.
    failed : sequence of str
        The measurement's failing checks.
    missing : str
        The missing budget terms, in words.

    Returns
    -------
    str
        The reasons, joined by ``" | "``; empty unless the verdict is ``inconclusive``.
    """
    if verdict(E_low, E_high, target, complete, failed) != "inconclusive":
        return ""
    why = []
    if failed:
        why.append("checks failed: " + "; ".join(failed))
    if not complete:
        why.append(f"interval incomplete: {missing}" if missing else "interval incomplete")
    if not why:
        why.append("the interval straddles the target")
    return " | ".join(why)


def point_wgs84(point: dict[str, Any], frame: Frame) -> tuple[float | None, float | None]:
    """A point's WGS84 latitude and longitude (degrees): its own, else from its x/y in a
    georeferenced frame (:func:`local_to_wgs84`), else None.

    Parameters
    ----------
    point : dict[str, Any]
        The config entry (``latitude``/``longitude``, ``x``/``y``).
    frame : Frame
        The survey's frame.

    Returns
    -------
    latitude : float or None
        Degrees.
    longitude : float or None
        Degrees.
    """
    if point.get("latitude") is not None:
        return float(point["latitude"]), float(point["longitude"])
    if point.get("x") is not None and frame.georeferenced:
        lat, lon = local_to_wgs84(point["x"], point["y"], frame)
        return float(lat), float(lon)
    return None, None


def survey_table(points: list[dict[str, Any]], results: list[dict[str, Any]],
                 frame: Frame | None = None) -> list[SurveyRow]:
    """One row per point from its config entry and its ``ssw measure --json`` result.

    Parameters
    ----------
    points : list[dict[str, Any]]
        The config's ``survey.points``.
    results : list[dict[str, Any]]
        Their ``ssw measure --json`` results, in the same order.
    frame : Frame or None
        The survey's frame: with a WGS84 origin, points given by x/y get their latitude
        and longitude (:func:`point_wgs84`). None: a frame without origin.

    Returns
    -------
    list[SurveyRow]
        One per point, with its verdict.

    Raises
    ------
    ConfigError
        Not one result per point.
    """
    if len(points) != len(results):
        raise ConfigError("survey results", len(results), f"one per point ({len(points)})")
    frame = frame or Frame()
    rows = []
    for pt, r in zip(points, results, strict=True):
        tgt = point_target(pt)
        ref = pt.get("reference_E")
        rng = r.get("nu_range")
        lat, lon = point_wgs84(pt, frame)
        missing = "; ".join(f"{k}: {v}" for k, v in (r.get("missing_terms") or {}).items())
        failed = point_checks_failed(r)
        lo, hi, complete = float(r["E_low"]), float(r["E_high"]), not r.get("missing_terms")
        rows.append(SurveyRow(
            id=pt["id"], E=float(r["E"]), E_low=lo, E_high=hi,
            E_u_pct=float(r["E_u_pct"]), target_E=tgt,
            reference_E=None if ref is None else float(ref),
            ratio=None if ref is None else float(r["E"]) / float(ref),
            verdict=verdict(lo, hi, tgt, complete, failed),
            missing_terms=missing,
            tof_mean=float(r["tof_mean"]),
            tof_sem=float("nan") if r.get("tof_sem") is None else float(r["tof_sem"]),
            n_accepted=int(r["n_accepted"]), n_hits=int(r["n_hits"]), nu=float(r["nu"]),
            nu_lo=None if rng is None else float(rng[0]),
            nu_hi=None if rng is None else float(rng[1]),
            x=pt.get("x"), y=pt.get("y"), latitude=lat, longitude=lon,
            layer=pt.get("layer"),
            synthetic=bool(r.get("synthetic", False)),
            checks_failed="; ".join(failed),
            reason=verdict_reason(lo, hi, tgt, complete, failed, missing),
        ))
    return rows


def point_checks_failed(result: dict[str, Any]) -> list[str]:
    """The failing checks of a point's ``ssw measure --json`` result (its ``validity``
    entries, :func:`ssw.validity.describe`); none for a result without checks.

    Parameters
    ----------
    result : dict
        The point's ``ssw measure --json`` result.

    Returns
    -------
    list of str
        One description per failing check.
    """
    from ssw.validity import describe

    return [describe(e) for e in result.get("validity") or [] if not e.get("holds", True)]


UNITS = {"E": "Pa", "E_low": "Pa", "E_high": "Pa", "E_u_pct": "%", "target_E": "Pa",
         "reference_E": "Pa", "ratio": "1", "tof_mean": "s", "tof_sem": "s",
         "n_accepted": "1", "n_hits": "1", "nu": "1", "nu_lo": "1", "nu_hi": "1", "x": "m",
         "y": "m", "latitude": "deg", "longitude": "deg"}


def write_survey(csv_path: str | Path, h5_path: str | Path, rows: list[SurveyRow],
                 inputs: dict[str, Any]) -> None:
    """The survey table as CSV (``name [unit]`` headers) and HDF5 (one dataset per column).

    Parameters
    ----------
    csv_path : str or pathlib.Path
        The CSV file.
    h5_path : str or pathlib.Path
        The HDF5 file.
    rows : list of SurveyRow
        The points' results.
    inputs : dict
        What the table was made from, stored as the HDF5 file's inputs.
    """
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



def read_results(paths: list[str | Path]) -> list[dict[str, Any]]:
    """The ``ssw measure --json`` results of the points.

    Parameters
    ----------
    paths : list of str or pathlib.Path
        The result files, one per point.

    Returns
    -------
    list of dict
        The results, in the order of ``paths``.

    Raises
    ------
    ssw.errors.ConfigError
        When a file cannot be read or is not JSON.
    """
    out = []
    for p in paths:
        try:
            out.append(json.loads(Path(p).read_text()))
        except (OSError, ValueError) as exc:
            raise ConfigError("survey result", str(p), f"a `ssw measure --json` file ({exc})") \
                from exc
    return out
