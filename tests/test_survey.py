"""Survey studies: conformity verdicts, the table and its files, the figures, refusals."""

from __future__ import annotations

import json

import h5py
import numpy as np
import pytest

from ssw.cli import main
from ssw.config import check_points
from ssw.errors import ConfigError
from ssw.survey import point_target, survey_table, verdict


@pytest.mark.parametrize(("lo", "hi", "target", "expected"), [
    (110e6, 130e6, 100e6, "pass"),  # the whole interval above the target
    (100e6, 130e6, 100e6, "pass"),  # its low end on the target
    (80e6, 95e6, 100e6, "fail"),  # the whole interval below
    (90e6, 110e6, 100e6, "inconclusive"),  # straddles
    (90e6, 110e6, None, "no target"),
])
def test_verdicts_follow_the_interval_and_the_target(lo, hi, target, expected):
    assert verdict(lo, hi, target) == expected


def test_target_from_a_lab_modulus_and_a_required_ratio():
    assert point_target({"target_E": 5e7}) == 5e7
    assert point_target({"reference_E": 1e8, "required_ratio": 0.9}) == pytest.approx(9e7)
    assert point_target({"reference_E": 1e8}) == 1e8
    assert point_target({}) is None


@pytest.mark.parametrize(("points", "field"), [
    ([{"id": "a b", "soil_nu": 0.3}], "survey.points[0].id"),
    ([{"id": "A", "soil_nu": 0.3}, {"id": "A", "soil_nu": 0.3}], "survey.points[1].id"),
    ([{"id": "A", "soil_nu": 0.3, "target_E": 1e8, "reference_E": 1e8}], "survey.points[0]"),
    ([{"id": "A", "soil_nu": 0.3, "x": 1.0}], "survey.points[0].x/y"),
    ([{"id": "A", "soil_nu": [0.4, 0.3]}], "survey.points[0].soil_nu"),
])
def test_bad_points_are_refused_naming_the_field(points, field):
    with pytest.raises(ConfigError) as exc:
        check_points(points)
    assert str(exc.value).startswith(field)


def _result(E, lo, hi, synthetic=True):
    return {"E": E, "E_low": lo, "E_high": hi, "E_u_pct": 2.0, "tof_mean": 1.5e-3,
            "tof_sem": 1e-6, "n_accepted": 8, "n_hits": 8, "nu": 0.3, "nu_range": None,
            "synthetic": synthetic}


POINTS = [
    {"id": "P1", "recordings": ["a.h5"], "soil_nu": 0.3, "x": 0.0, "y": 0.0,
     "target_E": 80e6, "layer": "lift 1"},
    {"id": "P2", "recordings": ["b.h5"], "soil_nu": [0.25, 0.35], "x": 10.0, "y": 5.0,
     "reference_E": 150e6, "required_ratio": 0.9},
    {"id": "P3", "recordings": ["c.h5"], "soil_nu": 0.3, "x": 20.0, "y": 0.0},
]
RESULTS = [_result(100e6, 95e6, 105e6), _result(120e6, 110e6, 131e6),
           _result(60e6, 55e6, 66e6)]


def test_survey_table_rows():
    rows = survey_table(POINTS, RESULTS)
    assert [r.verdict for r in rows] == ["pass", "fail", "no target"]
    assert rows[1].target_E == pytest.approx(135e6) and rows[1].ratio == pytest.approx(0.8)
    assert rows[0].layer == "lift 1" and rows[2].target_E is None


def test_survey_table_cli_writes_the_files(tmp_path, capsys):
    import yaml

    cfg = tmp_path / "c.yaml"
    cfg.write_text(yaml.safe_dump({"survey": {"title": "t", "points": POINTS}}))
    files = []
    for pt, r in zip(POINTS, RESULTS, strict=True):
        f = tmp_path / f"{pt['id']}.json"
        f.write_text(json.dumps(r))
        files.append(str(f))
    out = tmp_path / "out"
    rc = main(["survey-table", *files, "--config", str(cfg), "--csv", str(out / "s.csv"),
               "--h5", str(out / "s.h5"), "--plot", str(out / "e.png"), "--map",
               str(out / "m.png"), "--json"])
    assert rc == 0
    res = json.loads(capsys.readouterr().out)
    assert res["verdicts"] == {"pass": 1, "fail": 1, "inconclusive": 0, "no target": 1}
    lines = (out / "s.csv").read_text().splitlines()
    assert lines[0].startswith("# ssw ")  # the provenance line
    head = lines[1]
    assert "E [Pa]" in head and "verdict" in head and "x [m]" in head
    with h5py.File(out / "s.h5") as f:
        assert f.attrs["ssw_kind"] == "survey"
        np.testing.assert_allclose(f["E"][()], [100e6, 120e6, 60e6])
        assert f["E"].attrs["units"] == "Pa"
        assert [v.decode() for v in f["verdict"][()]] == ["pass", "fail", "no target"]
    for png in ("e.png", "m.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_missing_point_result_is_named(tmp_path):
    import yaml

    cfg = tmp_path / "c.yaml"
    cfg.write_text(yaml.safe_dump({"survey": {"points": POINTS}}))
    (tmp_path / "P1.json").write_text(json.dumps(RESULTS[0]))
    with pytest.raises(ConfigError, match="missing"):
        from argparse import Namespace

        from ssw.cli.survey import run_table

        run_table(Namespace(results=[str(tmp_path / "P1.json")], config=str(cfg),
                            csv=str(tmp_path / "s.csv"), h5=str(tmp_path / "s.h5"),
                            plot=None, map=None))


# ---------------------------------------------------------------------- where the points are
def _meridian_arc(lat1_deg: float, lat2_deg: float) -> float:
    """Length (m) of the WGS84 meridian between two latitudes: the integral of the meridian
    radius of curvature M = a (1 - e^2) / (1 - e^2 sin^2 phi)^1.5 (independent of ssw's
    ECEF round trip)."""
    from scipy.integrate import quad

    from ssw.survey import WGS84_A, WGS84_F

    e2 = WGS84_F * (2 - WGS84_F)
    return quad(lambda p: WGS84_A * (1 - e2) / (1 - e2 * np.sin(p) ** 2) ** 1.5,
                np.radians(lat1_deg), np.radians(lat2_deg), epsabs=1e-9, epsrel=1e-14)[0]


def test_a_frame_tied_to_wgs84_gives_latitude_and_longitude():
    from ssw.survey import WGS84_A, WGS84_F, Frame, local_to_wgs84, wgs84_to_local

    frame = Frame("grid", origin_latitude=45.0, origin_longitude=7.0, x_azimuth=90.0)
    # 1 km north along the tangent plane: the meridian arc to its latitude is 1 km less
    # d^3 / 3R^2 (8e-6 m)
    lat, lon = local_to_wgs84(0.0, 1000.0, frame)
    assert lon == pytest.approx(7.0, abs=1e-12)
    assert _meridian_arc(45.0, float(lat)) == pytest.approx(1000.0, abs=1e-4)
    # 1 m east and north: the local radii of curvature (first order, exact to 1e-7 m here)
    e2 = WGS84_F * (2 - WGS84_F)
    phi = np.radians(45.0)
    n_radius = WGS84_A / np.sqrt(1 - e2 * np.sin(phi) ** 2)
    m_radius = WGS84_A * (1 - e2) / (1 - e2 * np.sin(phi) ** 2) ** 1.5
    lat, lon = local_to_wgs84(1.0, 1.0, frame)
    assert float(lon) - 7.0 == pytest.approx(np.degrees(1 / (n_radius * np.cos(phi))), rel=1e-6)
    assert float(lat) - 45.0 == pytest.approx(np.degrees(1 / m_radius), rel=1e-6)
    # x pointing north (azimuth 0) puts x where y was with x east; y then points west
    north = Frame("grid", 45.0, 7.0, x_azimuth=0.0)
    np.testing.assert_allclose(local_to_wgs84(1000.0, 0.0, north),
                               local_to_wgs84(0.0, 1000.0, frame), rtol=0, atol=1e-12)
    assert float(local_to_wgs84(0.0, 10.0, north)[1]) < 7.0
    # and back: east/north offsets of those points (the same ECEF, inverted)
    x, y = np.array([0.0, 30.0, -250.0]), np.array([0.0, 40.0, 120.0])
    lat, lon = local_to_wgs84(x, y, frame)
    east, northing = wgs84_to_local(lat, lon, 45.0, 7.0)
    np.testing.assert_allclose(east, x, atol=1e-6)
    np.testing.assert_allclose(northing, y, atol=1e-6)
    with pytest.raises(ConfigError, match="origin"):
        local_to_wgs84(0.0, 0.0, Frame("grid"))


def test_a_half_given_origin_is_refused():
    from ssw.survey import survey_frame

    with pytest.raises(ConfigError, match="both or neither"):
        survey_frame({"frame": {"origin_latitude": 45.0}})
    assert survey_frame({}).name == "local x/y" and not survey_frame({}).georeferenced


GEO_FRAME = {"name": "site grid A", "origin_latitude": -0.2, "origin_longitude": -78.5,
             "x_azimuth": 90.0}


def _run_table(tmp_path, survey, *extra, rc=0):
    import yaml

    tmp_path.mkdir(parents=True, exist_ok=True)
    cfg = tmp_path / "c.yaml"
    cfg.write_text(yaml.safe_dump({"survey": survey}))
    files = []
    for pt, r in zip(survey["points"], RESULTS, strict=True):
        f = tmp_path / f"{pt['id']}.json"
        f.write_text(json.dumps(r))
        files.append(str(f))
    out = tmp_path / "out"
    got = main(["survey-table", *files, "--config", str(cfg), "--csv", str(out / "s.csv"),
               "--h5", str(out / "s.h5"), "--geojson", str(out / "s.geojson"), *extra])
    assert got == rc
    return out


def test_a_georeferenced_survey_fills_the_csv_and_writes_wgs84_geojson(tmp_path, capsys):
    """Points given by x/y in a frame tied to WGS84: the CSV's latitude/longitude are
    filled, and the GeoJSON holds [longitude, latitude] (RFC 7946), one feature per point
    with its verdict and E in Pa."""
    from ssw.h5io import read_rows_csv
    from ssw.survey import Frame, local_to_wgs84

    out = _run_table(tmp_path, {"title": "t", "frame": GEO_FRAME, "points": POINTS})
    capsys.readouterr()
    rows = read_rows_csv(out / "s.csv")
    frame = Frame(**GEO_FRAME)
    for pt, row in zip(POINTS, rows, strict=True):
        lat, lon = local_to_wgs84(pt["x"], pt["y"], frame)
        assert float(row["latitude [deg]"]) == pytest.approx(float(lat), abs=1e-9)
        assert float(row["longitude [deg]"]) == pytest.approx(float(lon), abs=1e-9)
    gj = json.loads((out / "s.geojson").read_text())
    assert gj["type"] == "FeatureCollection" and gj["frame"]["wgs84"] is True
    assert "crs" not in gj  # RFC 7946 has no crs member
    feats = gj["features"]
    assert [f["id"] for f in feats] == ["P1", "P2", "P3"]
    for f, pt, r in zip(feats, POINTS, RESULTS, strict=True):
        lon, lat = f["geometry"]["coordinates"]   # RFC 7946: longitude first
        assert f["geometry"]["type"] == "Point"
        assert lon == pytest.approx(-78.5 + pt["x"] / 111320.0, abs=1e-5)   # Quito: x east
        assert lat == pytest.approx(-0.2 + pt["y"] / 110574.0, abs=1e-5)
        assert f["properties"]["E_Pa"] == r["E"] and f["properties"]["x_m"] == pt["x"]
    assert [f["properties"]["verdict"] for f in feats] == ["pass", "fail", "no target"]
    assert not list(out.glob("*.tmp*")) and not list(out.glob(".*"))


def test_a_survey_in_local_coordinates_names_its_frame_in_the_geojson(tmp_path, capsys):
    out = _run_table(tmp_path, {"title": "t", "frame": {"name": "site grid A"},
                                "points": POINTS})
    capsys.readouterr()
    gj = json.loads((out / "s.geojson").read_text())
    assert gj["frame"]["wgs84"] is False and gj["frame"]["name"] == "site grid A"
    assert "NOT WGS84" in gj["frame"]["note"] and gj["frame"]["coordinates"] == "x, y (m)"
    for f, pt in zip(gj["features"], POINTS, strict=True):
        assert f["geometry"]["coordinates"] == [pt["x"], pt["y"]]
        assert f["properties"]["frame"] == "site grid A"
        assert f["properties"]["E_low_Pa"] < f["properties"]["E_Pa"] < \
            f["properties"]["E_high_Pa"]
    # no point with coordinates: no map, no GeoJSON (and the command says why)
    bare = [{k: v for k, v in p.items() if k not in ("x", "y")} for p in POINTS]
    _run_table(tmp_path / "bare", {"points": bare}, rc=2)
    assert "--geojson" in capsys.readouterr().err and not (tmp_path / "bare" / "out").exists()


def test_the_map_title_fits_and_names_synthetic_data_once():
    """A long title wraps to lie within the figure; "(SYNTHETIC data)" is not repeated when
    the title says so already; the map has a scale bar and a legend of the verdicts."""
    from matplotlib.transforms import Bbox
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    from ssw.survey import Frame, map_figure

    rows = survey_table(POINTS, RESULTS)
    long = ("Example lift (SYNTHETIC data, data/survey_example): compaction control of "
            "lift 3 of the northern embankment, station 12+300 to 12+450")
    for title in (long, "Example lift (SYNTHETIC data, data/survey_example)", ""):
        fig = map_figure(rows, title, Frame("site grid A"))
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        text = fig._suptitle
        box = text.get_window_extent(renderer)
        assert Bbox.intersection(box, fig.bbox) is not None
        assert fig.bbox.x0 <= box.x0 and box.x1 <= fig.bbox.x1, (title, box, fig.bbox)
        assert fig.bbox.y0 <= box.y0 and box.y1 <= fig.bbox.y1, (title, box, fig.bbox)
        assert text.get_text().lower().count("synthetic") == 1
        ax = fig.axes[0]
        bars = [a for a in ax.artists if isinstance(a, AnchoredSizeBar)]
        assert len(bars) == 1 and bars[0].txt_label.get_text().endswith(" m")
        labels = [t.get_text() for t in fig.legends[0].get_texts()]
        assert labels == ["pass (1)", "fail (1)", "no target (1)"]
        import matplotlib.pyplot as plt

        plt.close(fig)
