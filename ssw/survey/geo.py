"""Where a survey's points are: the survey's plane (:class:`Frame`, ``survey.frame``) and
its exact link to WGS84 latitude and longitude through the plane tangent to the ellipsoid
at the frame's origin (:func:`local_to_wgs84`, :func:`wgs84_to_local`). Metres and degrees.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ssw.errors import ConfigError

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


