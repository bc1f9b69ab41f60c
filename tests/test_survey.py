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
