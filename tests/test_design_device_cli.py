"""``ssw design --space device``: the recommended device is dominated by no feasible
candidate (resolution, sample yield, mass), the base (thesis) device is among the candidates
with the TOF ``ssw tof`` prints for it, the outputs are written, bad input is refused by
name. A small space (two bead materials, one diameter, eight scan points) keeps it fast; the
default space is timed by ``ssw bench design``.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from conftest import run_device_design

from ssw.cli import main

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "config" / "config.yaml"
SPACE = {"bead_materials": ["chrome_steel", "tungsten_carbide"], "bead_diameters": [9.525e-3],
         "beads": [12], "sensor_positions": [0.5], "plate_materials": ["pla"],
         "striker_mass_ratio": {"range": [0.5, 1.0], "scan": 2},
         "drop_height": {"range": [2e-3, 8e-3], "scan": 2},
         "plate_thickness": {"range": [1e-4, 1.5e-4], "scan": 1},
         "finalists": 1, "refine_evaluations": 3, "moduli": 2,
         "plate_yield_limit": 3.0}


@pytest.fixture(scope="module")
def design(tmp_path_factory):
    d = tmp_path_factory.mktemp("device")
    return run_device_design(d, SPACE, "--plot", str(d / "design.png")), d


def _dominates(a, b):
    keys = ("resolution", "soil_yield_index", "mass")
    return all(a[k] <= b[k] for k in keys) and any(a[k] < b[k] for k in keys)


def test_no_feasible_candidate_dominates_the_recommended(design):
    res, _ = design
    rec = res["recommended"]
    feasible = [c for c in res["candidates"] if c["feasible"]]
    assert rec["feasible"] and len(feasible) >= 2  # the check is not vacuous
    assert not any(_dominates(c, rec) for c in feasible)
    assert rec["resolution"] == min(c["resolution"] for c in feasible)
    assert rec["reasons"] and res["pareto_soil"] and res["pareto_mass"]
    # the fronts hold no dominated device
    for front, key in ((res["pareto_soil"], "soil_yield_index"), (res["pareto_mass"], "mass")):
        for a in front:
            assert not any(b["resolution"] <= a["resolution"] and b[key] < a[key]
                           for b in front)


def test_base_device_is_a_candidate_with_the_tof_of_ssw_tof(design, capsys):
    res, _ = design
    ref = res["reference"]
    assert ref is not None and ref["source"] == "reference" and ref["step"] == "own"
    assert any(c["source"] == "reference" for c in res["candidates"])
    capsys.readouterr()
    assert main(["tof", "--config", str(CONFIG), "--calibration", "none", "--law", "fem",
                 "--soil-E", repr(ref["soil_E"][0]), "--soil-nu", "0.3", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert ref["tof_E"][0] == pytest.approx(out["tof"], rel=1e-9)
    assert ref["dtof_dE_E"][0] == pytest.approx(out["dtof_dE"], rel=1e-7)


def test_outputs_written(design):
    res, d = design
    lines = (d / "design.csv").read_text().splitlines()
    rows = [x for x in lines if not x.startswith("#")]
    assert len(rows) == 1 + len(res["candidates"])
    table = list(csv.DictReader(rows))
    assert sum(r["recommended"] == "True" for r in table) == 1
    # each device's checks (ssw.validity), the worst over the soils, after its flags
    assert list(table[0])[-1] == "checks_failed" and "check_bead_yield" in table[0]
    assert all(r["check_bead_yield"] for r in table)
    assert (d / "design.png").stat().st_size > 1000


@pytest.mark.parametrize(("flags", "field"), [
    (["--materials", "pla"], "--materials"),
    (["--family", "abc"], "--family"),
    (["--family", "0.01"], "--family"),
    (["--family", "0.009525:pla", "--plastic-hits", "2"], "--plastic-hits"),
    (["--part", "0/2", "--merge", "a.json"], "--family/--part"),
    (["--part", "x"], "--part"),
])
def test_bad_input_is_refused_by_name(flags, field, capsys):
    assert main(["design", "--space", "device", "--config", str(CONFIG), "--calibration",
                 "none", "--soil-E", "20e6:200e6", "--soil-nu", "0.3", *flags]) == 2
    assert field in capsys.readouterr().err


def test_merge_ranks_the_same(design):
    """--merge of a result (the workflow's family jobs) ranks its candidates as the run
    did: the same recommended device and numbers (round trip of the JSON records)."""
    res, d = design
    out = d / "merged.json"
    assert main(["design", "--space", "device", "--config", str(CONFIG), "--merge",
                 str(d / "design.json"), "--output", str(out)]) == 0
    merged = json.loads(out.read_text())
    assert merged["recommended"]["label"] == res["recommended"]["label"]
    assert merged["recommended"]["resolution"] == res["recommended"]["resolution"]
    assert len(merged["candidates"]) == len(res["candidates"])
    assert merged["reference"]["tof_E"] == res["reference"]["tof_E"]


def test_merged_plastic_check_refuses_another_base_device(design, capsys):
    """The table strikes the devices of the merged runs' chain: a --config/--calibration
    whose base device is not theirs is refused by name, not struck with other numerics."""
    _, d = design
    assert main(["design", "--space", "device", "--merge", str(d / "design.json"),
                 "--plastic-hits", "2", "--config", str(CONFIG), "--calibration", "none",
                 "--striker-velocity", "0.3"]) == 2
    assert "--config/--calibration" in capsys.readouterr().err
