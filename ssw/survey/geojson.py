"""A survey's points for a GIS: a GeoJSON FeatureCollection (RFC 7946) with each point's
E, interval, target and verdict (:func:`survey_geojson`, :func:`write_geojson`);
longitude/latitude when every located point has them, else the local x/y with the frame
named.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ssw.survey.geo import Frame
from ssw.survey.table import SurveyRow


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


