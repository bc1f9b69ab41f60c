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
  law without a stated error): an incomplete interval decides nothing; or a check of the
  measurement's assumptions fails (its ``validity``, :mod:`ssw.validity`: the sample
  yielded, the contact left small strain, ...): E was computed beyond its model, and the
  row's ``reason`` names the checks;
* ``no target``: none was given.

Where the points are: ``x``/``y`` (m) in the survey's own plane, named by ``survey.frame``
(:class:`Frame`); with the frame's origin in WGS84 (``origin_latitude``/``origin_longitude``)
and the direction of its x axis (``x_azimuth``), every point's x/y also gets its latitude and
longitude (:func:`local_to_wgs84`, exact for the plane tangent to the WGS84 ellipsoid at the
origin). :func:`write_geojson` writes the points for a GIS: RFC 7946 longitude/latitude when
every located point has them, else the local x/y with the frame named.
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
#: How each verdict is drawn (the E figure and the map): colour and marker.
VERDICT_COLORS = {"pass": "tab:green", "fail": "tab:red", "inconclusive": "tab:orange",
                  "no target": "tab:gray"}
VERDICT_MARKERS = {"pass": "o", "fail": "X", "inconclusive": "s", "no target": "^"}

#: The WGS84 ellipsoid: semi-major axis (m) and flattening (NIMA TR8350.2, 3rd ed. 2000,
#: Table 3.1).
WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563
_E2 = WGS84_F * (2.0 - WGS84_F)  # first eccentricity squared


@dataclass(frozen=True)
class Frame:
    """The plane of a survey's x/y coordinates (config ``survey.frame``).

    Parameters
    ----------
    name : str
        What x/y are measured from (a site grid, a peg line), named in the GeoJSON and on
        the map.
    origin_latitude : float or None
        WGS84 latitude of x = y = 0, degrees (None: the frame is not tied to the Earth).
    origin_longitude : float or None
        WGS84 longitude of x = y = 0, degrees.
    x_azimuth : float
        Direction of +x, degrees clockwise from true north (90: x east and y north); +y is
        90 degrees counter-clockwise of +x.
    """

    name: str = "local x/y"
    origin_latitude: float | None = None
    origin_longitude: float | None = None
    x_azimuth: float = 90.0

    @property
    def georeferenced(self) -> bool:
        """Whether the frame's origin is given in WGS84."""
        return self.origin_latitude is not None and self.origin_longitude is not None


def survey_frame(survey: dict[str, Any]) -> Frame:
    """The :class:`Frame` of a config's ``survey`` section.

    Parameters
    ----------
    survey : dict[str, Any]
        The section (``frame``: ``name``, ``origin_latitude``, ``origin_longitude``,
        ``x_azimuth``).

    Returns
    -------
    Frame
        Its frame (the defaults when the section has none).

    Raises
    ------
    ConfigError
        Only one of the origin's latitude and longitude is given.
    """
    fr = survey.get("frame") or {}
    lat, lon = fr.get("origin_latitude"), fr.get("origin_longitude")
    if (lat is None) != (lon is None):
        raise ConfigError("survey.frame.origin_latitude/origin_longitude", [lat, lon],
                          "both or neither")
    return Frame(name=str(fr.get("name") or Frame.name),
                 origin_latitude=None if lat is None else float(lat),
                 origin_longitude=None if lon is None else float(lon),
                 x_azimuth=float(fr.get("x_azimuth", 90.0)))


def _ecef(lat: Any, lon: Any) -> np.ndarray:
    """Earth-centred Earth-fixed coordinates (m, shape (..., 3)) of points on the WGS84
    ellipsoid (height 0) at latitude/longitude in radians."""
    n = WGS84_A / np.sqrt(1.0 - _E2 * np.sin(lat) ** 2)
    return np.stack([n * np.cos(lat) * np.cos(lon), n * np.cos(lat) * np.sin(lon),
                     n * (1.0 - _E2) * np.sin(lat)], axis=-1)


def _enu_axes(lat0: float, lon0: float) -> np.ndarray:
    """Rows: the east, north and up unit vectors at a point (radians), in ECEF."""
    sl, cl, sp, cp = np.sin(lon0), np.cos(lon0), np.sin(lat0), np.cos(lat0)
    return np.array([[-sl, cl, 0.0], [-sp * cl, -sp * sl, cp], [cp * cl, cp * sl, sp]])


def local_to_wgs84(x: Any, y: Any, frame: Frame) -> tuple[np.ndarray, np.ndarray]:
    """WGS84 latitude and longitude of points of a georeferenced frame's plane.

    The plane is tangent to the ellipsoid at the frame's origin; a point's east and north
    offsets are ``x sin(a) - y cos(a)`` and ``x cos(a) + y sin(a)`` (``a`` the x axis's
    azimuth), taken to ECEF and back to geodetic coordinates (Bowring's iteration, to
    1e-12 rad). The point's height above the ellipsoid (d^2 / 2R: 8 cm at 1 km) is dropped.

    Parameters
    ----------
    x : array_like
        Plan coordinates along the frame's x axis, m.
    y : array_like
        Plan coordinates along its y axis, m.
    frame : Frame
        A georeferenced frame.

    Returns
    -------
    latitude : numpy.ndarray
        Degrees, the shape of ``x``.
    longitude : numpy.ndarray
        Degrees, in [-180, 180).

    Raises
    ------
    ConfigError
        The frame has no origin.

    References
    ----------
    B. R. Bowring, "Transformation from spatial to geographical coordinates", Survey Review
    23 (181), 323-327 (1976).
    """
    if not frame.georeferenced:
        raise ConfigError("survey.frame.origin_latitude", frame.origin_latitude,
                          "a WGS84 origin to turn x/y into latitude and longitude")
    lat0, lon0 = np.radians(frame.origin_latitude), np.radians(frame.origin_longitude)
    az = np.radians(frame.x_azimuth)
    x, y = np.asarray(x, float), np.asarray(y, float)
    east = x * np.sin(az) - y * np.cos(az)
    north = x * np.cos(az) + y * np.sin(az)
    e, n, _ = _enu_axes(lat0, lon0)
    p = _ecef(lat0, lon0) + east[..., None] * e + north[..., None] * n
    lon = np.arctan2(p[..., 1], p[..., 0])
    rho = np.hypot(p[..., 0], p[..., 1])
    lat = np.arctan2(p[..., 2], rho * (1.0 - _E2))
    for _ in range(6):
        nu = WGS84_A / np.sqrt(1.0 - _E2 * np.sin(lat) ** 2)
        h = rho / np.cos(lat) - nu
        lat = np.arctan2(p[..., 2], rho * (1.0 - _E2 * nu / (nu + h)))
    return np.degrees(lat), (np.degrees(lon) + 180.0) % 360.0 - 180.0


def wgs84_to_local(latitude: Any, longitude: Any, lat0: float, lon0: float
                   ) -> tuple[np.ndarray, np.ndarray]:
    """East and north offsets (m) of WGS84 points in the plane tangent at a reference point.

    Parameters
    ----------
    latitude : array_like
        Degrees.
    longitude : array_like
        Degrees.
    lat0 : float
        The reference point's latitude, degrees.
    lon0 : float
        Its longitude, degrees.

    Returns
    -------
    east : numpy.ndarray
        m.
    north : numpy.ndarray
        m.
    """
    r0 = np.radians([lat0, lon0])
    d = (_ecef(np.radians(np.asarray(latitude, float)), np.radians(np.asarray(longitude, float)))
         - _ecef(*r0))
    e, n, _ = _enu_axes(*r0)
    return d @ e, d @ n


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
    """The conformity verdict of an interval against a target (module docstring).

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


def synthetic_title(title: str, rows: list[SurveyRow], default: str) -> str:
    """A figure's title: ``title`` (else ``default``), with "(SYNTHETIC data)" added when a
    point's recordings are synthetic and the title does not say so already.

    Parameters
    ----------
    title : str
        The title asked for (empty: ``default``).
    rows : list of SurveyRow
        The points' results.
    default : str
        The title without one asked for.

    Returns
    -------
    str
        The title.
    """
    text = title or default
    if any(r.synthetic for r in rows) and "synthetic" not in text.lower():
        text += " (SYNTHETIC data)"
    return text


def fit_title(fig: Any, text: str, fontsize: float = 11.0) -> Any:
    """Set ``text`` as the figure's title, wrapped onto as many lines as it needs to lie
    within the figure's width.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (a constrained layout makes room for the lines).
    text : str
        The title.
    fontsize : float
        Points.

    Returns
    -------
    matplotlib.text.Text
        The title.
    """
    import textwrap

    renderer = fig.canvas.get_renderer()
    width = max(len(text), 1)
    while True:
        title = fig.suptitle(textwrap.fill(text, width), fontsize=fontsize)
        extent = title.get_window_extent(renderer).width
        if extent <= 0.94 * fig.bbox.width or width <= 12:
            return title
        width = max(12, min(width - 1, int(width * 0.94 * fig.bbox.width / extent)))


def plot_survey(path: str | Path, rows: list[SurveyRow], title: str = "") -> None:
    """E per point with its 95 % interval against its target, coloured by verdict.

    Parameters
    ----------
    path : str or Path
        The PNG (written atomically).
    rows : list[SurveyRow]
        The survey table.
    title : str
        The survey's title.
    """
    from ssw.plotting import pyplot, save_png

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(max(5.0, 0.6 * len(rows) + 2), 4.2), layout="constrained")
    xs = np.arange(len(rows))
    for i, r in enumerate(rows):
        ax.errorbar(i, r.E / 1e6, yerr=[[(r.E - r.E_low) / 1e6], [(r.E_high - r.E) / 1e6]],
                    fmt="o", color=VERDICT_COLORS[r.verdict], capsize=4,
                    label=r.verdict if r.verdict not in [q.verdict for q in rows[:i]] else None)
        if r.target_E is not None:
            ax.plot([i - 0.3, i + 0.3], [r.target_E / 1e6] * 2, "k--", lw=1)
        if r.checks_failed:  # E computed beyond its model's assumptions
            ax.annotate("!", (i, r.E_high / 1e6), textcoords="offset points",
                        xytext=(0, 4), ha="center", fontsize=11, fontweight="bold",
                        color=VERDICT_COLORS["inconclusive"])
    ax.set_xticks(xs, [r.id for r in rows], rotation=45, ha="right")
    ax.set_ylabel("E (MPa), 95 % interval; dashed: target; !: a check failed")
    fit_title(fig, synthetic_title(title, rows, "Survey: modulus per test point"))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    save_png(fig, path, dpi=150)


def _nice_length(span: float) -> float:
    """A round length (1, 2 or 5 x 10^k) of about a quarter of ``span`` (m)."""
    target = max(span, 1e-9) / 4.0
    unit = 10.0 ** np.floor(np.log10(target))
    return float(max(m for m in (1.0, 2.0, 5.0) if m * unit <= target) * unit)


def map_coordinates(rows: list[SurveyRow], frame: Frame | None = None
                    ) -> tuple[list[SurveyRow], np.ndarray, tuple[str, str]] | None:
    """What the map draws: the located points, their plan coordinates (m) and axis labels.

    Points with x/y are drawn in the survey's frame when at least as many points have x/y
    as have latitude/longitude; otherwise the points with latitude/longitude are drawn as
    east/north offsets (m) from the first of them (:func:`wgs84_to_local`), so that both
    axes are metres and a scale bar holds.

    Parameters
    ----------
    rows : list[SurveyRow]
        The survey table.
    frame : Frame or None
        The survey's frame (its name labels the axes).

    Returns
    -------
    tuple or None
        ``(rows, xy, (xlabel, ylabel))`` with ``xy`` of shape (n, 2), m; None when no
        point has coordinates.
    """
    frame = frame or Frame()
    xy = [r for r in rows if r.x is not None]
    geo = [r for r in rows if r.latitude is not None]
    if not xy and not geo:
        return None
    if len(xy) >= len(geo):
        pts = np.array([[r.x, r.y] for r in xy], float)
        return xy, pts, (f"x (m), {frame.name}", "y (m)")
    lat0, lon0 = geo[0].latitude, geo[0].longitude
    east, north = wgs84_to_local([r.latitude for r in geo], [r.longitude for r in geo],
                                 lat0, lon0)
    return geo, np.column_stack([east, north]), (
        f"east (m) of {geo[0].id} ({lat0:.6f}, {lon0:.6f} WGS84)", "north (m)")


def map_figure(rows: list[SurveyRow], title: str = "", frame: Frame | None = None) -> Any:
    """Plan view of the located points: verdict as colour and marker, id and E beside each
    point, a scale bar, and the title wrapped to the figure's width.

    Parameters
    ----------
    rows : list[SurveyRow]
        The survey table.
    title : str
        The survey's title.
    frame : Frame or None
        The survey's frame (:func:`map_coordinates`).

    Returns
    -------
    matplotlib.figure.Figure or None
        The figure; None when no point has coordinates.
    """
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    from ssw.plotting import pyplot

    drawn = map_coordinates(rows, frame)
    if drawn is None:
        return None
    sel, pts, (xlabel, ylabel) = drawn
    span = float(np.ptp(pts, axis=0).max())
    pad = 0.2 * span if span > 0 else 5.0
    extent = np.ptp(pts, axis=0) + 2.0 * pad  # m, the drawn area
    plt = pyplot()
    # as tall as the points' layout needs (a strip of points: a low figure), within limits
    height = float(np.clip(5.6 * extent[1] / extent[0] + 2.2, 3.8, 6.4))
    fig, ax = plt.subplots(figsize=(6.4, height), layout="constrained")
    for v in VERDICTS:
        idx = [i for i, r in enumerate(sel) if r.verdict == v]
        if idx:
            ax.scatter(pts[idx, 0], pts[idx, 1], marker=VERDICT_MARKERS[v], s=110,
                       color=VERDICT_COLORS[v], edgecolors="k", zorder=3,
                       label=f"{v} ({len(idx)})")
    for (px, py), r in zip(pts, sel, strict=True):
        label = f"{r.id} {r.E / 1e6:.0f} MPa"
        if r.checks_failed:  # the names of the failing checks (ssw.validity)
            label += "\n! " + ", ".join(c.split(" ", 1)[0] for c in r.checks_failed.split("; "))
        ax.annotate(label, (px, py), textcoords="offset points", xytext=(7, 5), fontsize=8)
    # room around the points (at least 5 m each way), the same metre on both axes
    ax.update_datalim([pts.min(axis=0) - pad, pts.max(axis=0) + pad])
    ax.autoscale_view()
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    fig.legend(title="verdict", fontsize=8, title_fontsize=8, loc="outside lower center",
               ncols=4)
    fit_title(fig, synthetic_title(title, rows, "Survey plan view"))
    fig.canvas.draw()
    length = _nice_length(float(np.diff(ax.get_xlim())[0]))
    ax.add_artist(AnchoredSizeBar(ax.transData, length, f"{length:g} m", "lower right",
                                  pad=0.4, borderpad=0.6, sep=4, frameon=True,
                                  size_vertical=0.0))
    return fig


def plot_map(path: str | Path, rows: list[SurveyRow], title: str = "",
             frame: Frame | None = None) -> bool:
    """Write :func:`map_figure` as PNG (atomically).

    Parameters
    ----------
    path : str or Path
        The PNG.
    rows : list[SurveyRow]
        The survey table.
    title : str
        The survey's title.
    frame : Frame or None
        The survey's frame.

    Returns
    -------
    bool
        False (and no file) when no point has coordinates.
    """
    from ssw.plotting import save_png

    fig = map_figure(rows, title, frame)
    if fig is None:
        return False
    save_png(fig, path, dpi=150)
    return True


def _number(value: Any) -> float | None:
    """A finite float for JSON, else None (JSON has no NaN)."""
    if value is None:
        return None
    v = float(value)
    return v if np.isfinite(v) else None


def survey_geojson(rows: list[SurveyRow], frame: Frame | None = None, title: str = ""
                   ) -> dict[str, Any]:
    """The survey's points as a GeoJSON FeatureCollection (RFC 7946).

    Coordinates are WGS84 ``[longitude, latitude]`` (degrees, RFC 7946 section 3.1.1) when
    every point with coordinates has latitude and longitude (given, or from x/y in a
    georeferenced frame). Otherwise they are the frame's ``[x, y]`` (m), which RFC 7946
    does not define (section 4: another reference system only by prior arrangement, and
    no ``crs`` member since RFC 7946): the collection's foreign member ``frame`` then names
    it (``wgs84`` false, the frame's name, metres) and so does each feature's property
    ``frame``. A point without the chosen coordinates has a null geometry.

    Parameters
    ----------
    rows : list[SurveyRow]
        The survey table.
    frame : Frame or None
        The survey's frame.
    title : str
        The survey's title (the collection's ``name``).

    Returns
    -------
    dict[str, Any]
        The FeatureCollection; each feature's properties hold the point's id, verdict and
        moduli with their units in the names (``E_Pa``, ``E_low_Pa``, ``E_high_Pa``,
        ``target_E_Pa``, ``E_u_pct``), its failing checks (``checks_failed``, a list) and
        the reason of an inconclusive verdict (``reason``).
    """
    frame = frame or Frame()
    located = [r for r in rows if r.x is not None or r.latitude is not None]
    wgs84 = all(r.latitude is not None for r in located)
    if wgs84:
        about = {"wgs84": True, "coordinates": "longitude, latitude (degrees, WGS84)"}
        if any(r.x is not None for r in rows) and frame.georeferenced:
            about |= {"from_frame": frame.name, "origin_latitude": frame.origin_latitude,
                      "origin_longitude": frame.origin_longitude,
                      "x_azimuth_deg": frame.x_azimuth}
    else:
        about = {"wgs84": False, "name": frame.name, "coordinates": "x, y (m)",
                 "note": "NOT WGS84 longitude/latitude: plan coordinates (m) in the named "
                         "frame (RFC 7946 section 4); give survey.frame.origin_latitude and "
                         "origin_longitude to get WGS84"}
    features = []
    for r in rows:
        if wgs84 and r.latitude is not None:
            geometry = {"type": "Point",
                        "coordinates": [round(r.longitude, 8), round(r.latitude, 8)]}
        elif not wgs84 and r.x is not None:
            geometry = {"type": "Point", "coordinates": [float(r.x), float(r.y)]}
        else:
            geometry = None
        props = {"id": r.id, "verdict": r.verdict, "E_Pa": r.E, "E_low_Pa": r.E_low,
                 "E_high_Pa": r.E_high, "E_u_pct": _number(r.E_u_pct),
                 "target_E_Pa": _number(r.target_E), "ratio": _number(r.ratio),
                 "layer": r.layer, "n_accepted": r.n_accepted, "n_hits": r.n_hits,
                 "missing_terms": r.missing_terms or None, "synthetic": r.synthetic,
                 "checks_failed": r.checks_failed.split("; ") if r.checks_failed else [],
                 "reason": r.reason or None}
        if r.x is not None:
            props |= {"x_m": float(r.x), "y_m": float(r.y)}
        if not wgs84:
            props["frame"] = frame.name
        features.append({"type": "Feature", "id": r.id, "geometry": geometry,
                         "properties": props})
    return {"type": "FeatureCollection", "name": title or "survey", "frame": about,
            "features": features}


def write_geojson(path: str | Path, rows: list[SurveyRow], frame: Frame | None = None,
                  title: str = "") -> None:
    """Write :func:`survey_geojson` atomically (``.geojson``, UTF-8).

    Parameters
    ----------
    path : str or Path
        The file.
    rows : list[SurveyRow]
        The survey table.
    frame : Frame or None
        The survey's frame.
    title : str
        The survey's title.
    """
    from ssw.h5io import atomic_write_text

    atomic_write_text(path, json.dumps(survey_geojson(rows, frame, title), indent=1,
                                       allow_nan=False) + "\n")


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
