"""``ssw design --space device --size N``: about N evaluations (the scan grown, the rest in
bounded searches from the best devices), a recommendation no worse than the default run's
(its merit: feasibility first, then the worst-case resolution), and the workflow's route
(``--family``, ``--part``, then ``--merge``) recommends what the single sized run does."""

from __future__ import annotations

import json

import pytest
from conftest import run_device_design

from ssw.cli import main

SPACE = {"bead_materials": ["chrome_steel"], "bead_diameters": [9.525e-3], "beads": [12],
         "sensor_positions": [0.5], "plate_materials": ["pla"],
         "striker_mass_ratio": {"range": [0.5, 1.0], "scan": 1},
         "drop_height": {"range": [2e-3, 8e-3], "scan": 2},
         "plate_thickness": {"range": [1e-4, 1.5e-4], "scan": 1},
         "finalists": 1, "refine_evaluations": 2, "moduli": 2, "plate_yield_limit": 3.0}
SIZE = 12
KEY = ("bead_material", "bead_diameter", "beads", "sensor_index", "sensor_mass_ratio",
       "striker_mass_ratio", "drop_height", "plate_material", "plate_thickness")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("default")
    big = tmp_path_factory.mktemp("sized")
    return (run_device_design(base, SPACE), run_device_design(big, SPACE, "--size",
                                                              str(SIZE)), big)


def test_size_spends_about_n_evaluations_and_recommends_no_worse(runs):
    from ssw.design.device_search import sized
    from ssw.design.device_spec import DeviceSpec
    from ssw.design.space import space_from_dict

    default, big, _ = runs
    space = space_from_dict(big["space"], big["space"]["plate_diameter_ratio"])
    assert space.size > space_from_dict(default["space"], 1.0).size
    planned = space.size + big["spec"]["finalists"] * big["spec"]["refine_evaluations"]
    assert planned <= SIZE
    # the reference device and the recommended one again at its own step come on top
    assert default["evaluations"] < big["evaluations"] <= SIZE + 2
    # the grown scan holds every scanned device of the default run
    keys = {tuple(c[k] for k in KEY) for c in big["candidates"] if c["source"] == "scan"}
    assert all(tuple(c[k] for k in KEY) in keys for c in default["candidates"]
               if c["source"] == "scan")
    assert sized(space, DeviceSpec.from_dict(big["spec"]), SIZE)[0].size == space.size
    assert big["recommended"]["merit"] <= default["recommended"]["merit"]


def test_parts_and_merge_recommend_what_the_single_run_does(runs, tmp_path):
    _, big, d = runs
    cfg = str(d / "config.yaml")
    common = ["design", "--space", "device", "--config", cfg, "--calibration", "none",
              "--soil-E", "20e6:200e6", "--soil-nu", "0.3", "--soil-yield-limit", "50",
              "--size", str(SIZE)]
    part = tmp_path / "part.json"
    assert main([*common, "--family", "9.525e-3:pla", "--part", "0/1", "--output",
                 str(part)]) == 0
    merged = tmp_path / "merged.json"
    assert main(["design", "--space", "device", "--config", cfg, "--merge", str(part),
                 "--output", str(merged)]) == 0
    got = json.loads(merged.read_text())
    assert got["recommended"]["label"] == big["recommended"]["label"]
    assert got["recommended"]["resolution"] == pytest.approx(
        big["recommended"]["resolution"], rel=1e-12)
