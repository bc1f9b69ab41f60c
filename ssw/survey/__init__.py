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

Modules: :mod:`ssw.survey.table` (the points' results, targets and verdicts),
:mod:`ssw.survey.geo` (the survey's plane and WGS84), :mod:`ssw.survey.figures` (the E
figure and the map), :mod:`ssw.survey.geojson` (the points for a GIS). Every public name of
them is importable from ``ssw.survey``.
"""

from __future__ import annotations

from ssw.survey.figures import (
    VERDICT_COLORS,
    VERDICT_MARKERS,
    fit_title,
    map_coordinates,
    map_figure,
    plot_map,
    plot_survey,
    synthetic_title,
)
from ssw.survey.geo import (
    WGS84_A,
    WGS84_F,
    Frame,
    local_to_wgs84,
    survey_frame,
    wgs84_to_local,
)
from ssw.survey.geojson import (
    survey_geojson,
    write_geojson,
)
from ssw.survey.table import (
    KIND,
    UNITS,
    VERDICTS,
    SurveyRow,
    point_checks_failed,
    point_target,
    point_wgs84,
    read_results,
    survey_table,
    verdict,
    verdict_reason,
    write_survey,
)

__all__ = [
    "KIND",
    "UNITS",
    "VERDICTS",
    "VERDICT_COLORS",
    "VERDICT_MARKERS",
    "WGS84_A",
    "WGS84_F",
    "Frame",
    "SurveyRow",
    "fit_title",
    "local_to_wgs84",
    "map_coordinates",
    "map_figure",
    "plot_map",
    "plot_survey",
    "point_checks_failed",
    "point_target",
    "point_wgs84",
    "read_results",
    "survey_frame",
    "survey_geojson",
    "survey_table",
    "synthetic_title",
    "verdict",
    "verdict_reason",
    "wgs84_to_local",
    "write_geojson",
    "write_survey",
]
