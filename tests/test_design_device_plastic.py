"""The device design's plastic check (``--plastic-hits``, ``design.device.plastic_hits``):
the finalists struck on a yielding sample through their yielding plate. The record of the
struck device equals a separate :func:`ssw.walls.hits.run_hits` of the same device, sample
and plate laws built here from the library and the design's soil strength; a device that
cannot be struck keeps the reason; a bad hit count is refused by name."""

from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from conftest import run_device_design

from ssw.cli import main

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "config" / "config.yaml"
SPACE = {"bead_materials": ["chrome_steel"], "bead_diameters": [9.525e-3], "beads": [12],
         "sensor_positions": [0.5], "plate_materials": ["pla"],
         "striker_mass_ratio": {"range": [0.5, 1.0], "scan": 2},
         "drop_height": {"range": [2e-3, 8e-3], "scan": 1},
         "plate_thickness": {"range": [1e-4, 1.5e-4], "scan": 1},
         "finalists": 1, "refine_evaluations": 0, "moduli": 2, "plate_yield_limit": 3.0}


@pytest.fixture(scope="module")
def struck(tmp_path_factory):
    d = tmp_path_factory.mktemp("plastic")
    return run_device_design(d, SPACE, "--no-reference", "--plastic-hits", "2"), d


def test_plastic_record_equals_a_separate_run_of_run_hits(struck):
    from ssw.chain.params import chain_params, numerics_of
    from ssw.config import device_of, library, load_config
    from ssw.constitutive import VonMises
    from ssw.design.space import DevicePoint
    from ssw.walls.hits import run_hits
    from ssw.walls.plastic import plastic_wall

    res, _ = struck
    rec = res["recommended"]
    chk = rec["plastic"]
    assert chk is not None and chk["error"] is None and chk["hits"] == 2
    assert [c["label"] for c in res["plastic_check"]] == [rec["label"]]  # one finalist
    cfg = load_config(str(CONFIG))
    mats = library(cfg)
    base = chain_params(device_of(cfg), mats, **numerics_of(cfg))
    params = DevicePoint.from_dict(rec).params(base, mats)
    # the soil of the largest elastic soil yield index, at the design's strength 0.01 E
    E = rec["soil_E"][int(np.argmax(rec["soil_yield_E"]))]
    pla = mats["pla"].strength
    wall = plastic_wall(params, E, 0.3, soil_model=VonMises(0.01 * E),
                        plate_model=VonMises(pla.yield_stress, pla.hardening or 0.0))
    hits = run_hits(params, wall, 2)
    assert chk["soil_E"] == E
    assert chk["soil_yield_stress"] == pytest.approx(0.01 * E, rel=1e-12)
    assert chk["plate_dent"] == pytest.approx(hits.plate_thinning[-1, 0], rel=1e-9)
    assert chk["soil_set"] == pytest.approx(hits.interface_set[-1, 0], rel=1e-9)
    assert chk["tof_drift"] == pytest.approx(hits.tof[1, 0] - hits.tof[0, 0], rel=1e-9)
    assert [r["tof"] for r in chk["rows"]] == pytest.approx(hits.tof[:, 0], rel=1e-9)
    # the sample yields at 0.01 E under a 9.5 mm bead: a set that grows, a TOF that moves
    assert chk["soil_set"] > 0 and chk["tof_drift"] != 0


def test_plastic_columns_in_the_table(struck):
    res, d = struck
    text = [x for x in (d / "design.csv").read_text().splitlines() if not x.startswith("#")]
    rows = list(csv.DictReader(text))
    hit = [r for r in rows if r["plastic_plate_dent"]]
    assert len(hit) == 1 and hit[0]["recommended"] == "True"
    assert float(hit[0]["plastic_tof_drift"]) == pytest.approx(
        res["recommended"]["plastic"]["tof_drift"], rel=1e-5)
    assert all(r["plastic_soil_set"] == "" for r in rows if r["recommended"] == "False")


def test_a_plate_without_strength_keeps_the_reason(struck):
    """Not struck is said, not left blank: a plate material with no yield stress."""
    from ssw.config import library, load_config
    from ssw.design.device_eval import DeviceCandidate
    from ssw.design.device_spec import DeviceSpec
    from ssw.design.hits_check import device_hits_check

    res, _ = struck
    spec = DeviceSpec.from_dict(res["spec"])
    cand = DeviceCandidate.from_dict(res["recommended"], spec.limits)
    mats = library(load_config(str(CONFIG)))
    mats = {**mats, "pla": replace(mats["pla"], strength=None)}
    out = device_hits_check(spec, None, mats, cand, 2)
    assert out["error"] and "materials.pla.strength" in out["error"]
    assert out["plate_dent"] is None and out["rows"] == []


def test_bad_hit_count_is_refused_by_name(capsys):
    assert main(["design", "--space", "device", "--config", str(CONFIG), "--calibration",
                 "none", "--soil-E", "20e6:200e6", "--soil-nu", "0.3",
                 "--plastic-hits", "1"]) == 2
    assert "plastic_hits" in capsys.readouterr().err
