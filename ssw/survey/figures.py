"""What a survey draws: each point's E with its interval against its target, coloured by
verdict (:func:`plot_survey`), and the map of the points in the survey's plane with a scale
bar (:func:`map_figure`, :func:`plot_map`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ssw.survey.geo import Frame, wgs84_to_local
from ssw.survey.table import VERDICTS, SurveyRow

#: How each verdict is drawn (the E figure and the map): colour and marker.
VERDICT_COLORS = {"pass": "tab:green", "fail": "tab:red", "inconclusive": "tab:orange",
                  "no target": "tab:gray"}
VERDICT_MARKERS = {"pass": "o", "fail": "X", "inconclusive": "s", "no target": "^"}


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


