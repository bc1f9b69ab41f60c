"""The virtual prototype of a designed device (:mod:`ssw.design.prototype`): simulated
recordings (the simulated DAQ: striker scatter, noise, anti-alias filter), the ``ssw
calibrate`` and ``ssw measure`` library paths at the TOF level; each unseen sample's true
E inside its 95 % interval, the achieved interval widths within 30 % of the predicted ones
(:mod:`ssw.design.predict` with the calibration's covariance and the terms ``ssw measure``
states), and each hit's achieved TOF scatter of the predicted size. The reduced prototype
(two unseen samples) runs by default; the whole one (four) through the command line is
slow."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import run_device_design

from ssw.cli import main

SPACE = {"bead_materials": ["chrome_steel"], "bead_diameters": [9.525e-3], "beads": [12],
         "sensor_positions": [0.5], "plate_materials": ["pla"],
         "striker_mass_ratio": {"range": [0.5, 1.0], "scan": 1},
         "drop_height": {"range": [2e-3, 8e-3], "scan": 2},
         "plate_thickness": {"range": [1e-4, 1.5e-4], "scan": 1},
         "finalists": 1, "refine_evaluations": 0, "moduli": 2, "plate_yield_limit": 3.0}
#: The done-when band: achieved interval widths within 30 % of the predicted ones.
WIDTH_BAND = 0.3
#: A standard deviation from 5 hits (4 degrees of freedom) lies within a factor 3 of the
#: true one with probability above 0.99 (chi-square with 4 dof: P(s/sigma < 1/3) = 0.0016,
#: P(s/sigma > 3) < 1e-6).
SCATTER_FACTOR = 3.0


def _check(rows):
    assert rows
    for r in rows:
        assert r["inside"], r
        assert abs(r["width_ratio"] - 1.0) <= WIDTH_BAND, r
        ratio = r["tof_std_achieved"] / r["tof_scatter_predicted"]
        assert 1 / SCATTER_FACTOR < ratio < SCATTER_FACTOR, r


@pytest.fixture(scope="module")
def design(tmp_path_factory):
    d = tmp_path_factory.mktemp("proto")
    return run_device_design(d, SPACE), d


def test_reduced_prototype(design, tmp_path):
    from ssw.chain.params import numerics_of
    from ssw.cli._device import contact_for_bead
    from ssw.config import device_of, library, load_config
    from ssw.daq.settings import settings_from_config
    from ssw.design.device_file import designed_device
    from ssw.design.prototype import run_prototype

    res, d = design
    cfg = load_config(str(d / "config.yaml"))
    mats = library(cfg)
    dev = designed_device(res, res["recommended"], device_of(cfg), mats, "prototype")
    out = run_prototype(dev, mats, numerics_of(cfg),
                        {"contact": contact_for_bead(cfg, dev.bead_radius)},
                        settings_from_config(cfg, dev), (20e6, 200e6), 0.3, tmp_path,
                        unseen=2)
    _check(out["unseen"])
    # the calibration finds the device's striker speed within its interval's reach
    v = float(np.sqrt(2 * 9.80665 * res["recommended"]["drop_height"]))
    assert out["calibration"]["striker_velocity"] == pytest.approx(v, rel=0.01)


@pytest.mark.slow
def test_full_prototype_through_the_command_line(design, tmp_path, capsys):
    _, d = design
    out = tmp_path / "p.json"
    capsys.readouterr()
    assert main(["design", "--space", "device", "--config", str(d / "config.yaml"),
                 "--calibration", "none", "--merge", str(d / "design.json"), "--prototype",
                 str(tmp_path / "rec"), "--output", str(out)]) == 0
    got = json.loads(out.read_text())["prototype"]
    assert len(got["unseen"]) == 4 and len(got["references"]) == 3
    _check(got["unseen"])
    assert "virtual prototype" in capsys.readouterr().out
