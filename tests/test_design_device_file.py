"""``ssw design --output-device``: the recommended device (or a ranked one) as a device file
that every command takes. ``ssw tof --device FILE`` (a separate run of the chain at the
device's own step, on the fem wall) reproduces the TOF the design computed for it to
round-off; the file holds the candidate's design variables; the beads are named by
material (``--bead-material``), and a bead value that contradicts the named material is
refused by name.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import run_device_design

from ssw.cli import main

#: Round-off of a TOF between the design's run and a separate run of the same scene at the
#: same (own) time step (tests/test_design_cli.py's SAME_RTOL).
SAME_RTOL = 1e-9
#: The integrator's stated TOF error (relative; ssw.chain.integrate, against DOP853): a
#: candidate run at its batch's shared step against ``ssw tof`` at its own.
TOF_RTOL = 5e-5
SPACE = {"bead_materials": ["chrome_steel"], "bead_diameters": [9.525e-3], "beads": [12],
         "sensor_positions": [0.5], "plate_materials": ["pla"],
         "striker_mass_ratio": {"range": [0.5, 1.0], "scan": 2},
         "drop_height": {"range": [2e-3, 8e-3], "scan": 2},
         "plate_thickness": {"range": [1e-4, 1.5e-4], "scan": 1},
         "finalists": 1, "refine_evaluations": 2, "moduli": 2, "plate_yield_limit": 3.0}


@pytest.fixture(scope="module")
def design(tmp_path_factory):
    d = tmp_path_factory.mktemp("devfile")
    res = run_device_design(d, SPACE, "--output-device", str(d / "designed.yaml"))
    return res, d


def _tof(capsys, d, device, E):
    capsys.readouterr()
    assert main(["tof", "--config", str(d / "config.yaml"), "--calibration", "none",
                 "--device", str(device), "--law", "fem", "--soil-E", repr(E),
                 "--soil-nu", "0.3", "--json"]) == 0
    return json.loads(capsys.readouterr().out)["tof"]


def test_ssw_tof_of_the_device_file_is_the_designs(design, capsys):
    res, d = design
    rec = res["recommended"]
    assert rec["step"] == "own"
    for E, T in zip(rec["soil_E"], rec["tof_E"], strict=True):
        assert _tof(capsys, d, d / "designed.yaml", E) == pytest.approx(T, rel=SAME_RTOL)


def test_device_file_holds_the_candidate(design):
    from ssw.device import load_device
    from ssw.materials import material_set

    res, d = design
    rec = res["recommended"]
    dev = load_device(d / "designed.yaml")
    m_bead = 4 / 3 * np.pi * dev.bead_radius**3 * material_set()["chrome_steel"].density
    assert dev.name == "designed" and dev.bead_material == rec["bead_material"]
    assert (dev.beads, dev.sensor_index) == (rec["beads"], rec["sensor_index"])
    assert dev.bead_radius == pytest.approx(rec["bead_diameter"] / 2, rel=1e-15)
    assert dev.sensor_mass / m_bead == pytest.approx(rec["sensor_mass_ratio"], rel=1e-12)
    assert dev.striker_mass / m_bead == pytest.approx(rec["striker_mass_ratio"], rel=1e-12)
    assert dev.drop_height == pytest.approx(rec["drop_height"], rel=1e-12)
    assert (dev.plate_material, dev.plate_thickness) == (rec["plate_material"],
                                                         rec["plate_thickness"])
    assert dev.tof_scatter == res["spec"]["tof_scatter"]
    assert "assumed by ssw design" in dev.tof_scatter_source
    head = (d / "designed.yaml").read_text().splitlines()[0]
    assert head.startswith("# Device made by `ssw design --space device`")


def test_ranked_candidate_from_the_merged_json(design, capsys, tmp_path):
    res, d = design
    out = tmp_path / "second.yaml"
    assert main(["design", "--space", "device", "--config", str(d / "config.yaml"),
                 "--calibration", "none", "--merge", str(d / "design.json"),
                 "--output", str(tmp_path / "m.json"), "--output-device", str(out),
                 "--output-device-rank", "2"]) == 0
    second = res["candidates"][1]
    T = _tof(capsys, d, out, second["soil_E"][0])
    rtol = SAME_RTOL if second["step"] == "own" else TOF_RTOL
    assert T == pytest.approx(second["tof_E"][0], rel=rtol)
    assert T != pytest.approx(res["recommended"]["tof_E"][0], rel=1e-6)  # another device


def test_bad_rank_refused_by_name(design, capsys, tmp_path):
    _, d = design
    capsys.readouterr()
    rc = main(["design", "--space", "device", "--config", str(d / "config.yaml"),
               "--calibration", "none", "--merge", str(d / "design.json"),
               "--output-device", str(tmp_path / "x.yaml"), "--output-device-rank", "999"])
    assert rc == 2 and "--output-device-rank" in capsys.readouterr().err
    assert not (tmp_path / "x.yaml").exists()


def test_bead_material_flag_is_the_librarys_values(capsys):
    """``--bead-material`` gives the TOF of the library's density, E and nu stated by hand
    (hertz wall: no mesh); a contradicting value is refused naming both."""
    from ssw.materials import material_set

    m = material_set()["tungsten_carbide"]
    base = ["tof", "--calibration", "none", "--law", "hertz", "--soil-E", "5e7",
            "--soil-nu", "0.3", "--json"]
    out = []
    for flags in (["--bead-material", "tungsten_carbide"],
                  ["--bead-density", repr(m.density), "--bead-E", repr(m.E), "--bead-nu",
                   repr(m.nu)], []):
        capsys.readouterr()
        assert main([*base, *flags]) == 0
        out.append(json.loads(capsys.readouterr().out)["tof"])
    assert out[0] == out[1] and out[0] != pytest.approx(out[2], rel=1e-3)
    rc = main([*base, "--bead-material", "tungsten_carbide", "--bead-E", "2e11"])
    err = capsys.readouterr().err
    assert rc == 2 and "--bead-E" in err and "tungsten_carbide" in err
