"""The thesis's Table 2: calibrate the striker speed on PCF 30 only, predict PCF 08 and 15.

Thesis simulated TOF (Torres Constante 2024, Table 2): 1.80 ms (38 MPa, nu 0.34),
1.46 ms (123 MPa, 0.33), 1.15 ms (445 MPa, 0.30). Our device: 20 beads of 3/4 in chrome
steel, sensor bead 10, gravity, Hertz wall (the plate's K table is a product of the
workflow, not an input of the tests). Stated tolerance of the predictions: 12 %. The
Hertz wall lacks the plate, which stiffens the contact most on soft soils (K > 1), so the
predictions are expected to run long for the soft foams; at calibration time (this
code, REFERENCE.md device) they came out +9.7 % (PCF 08) and +2.8 % (PCF 15).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ssw.chain.calibration import TABLE2, calibrate_striker_velocity
from ssw.chain.params import ChainParams
from ssw.config import load_config

ROOT = Path(__file__).resolve().parent.parent
TOLERANCE = 0.12


@pytest.fixture(scope="module")
def calibration():
    cfg = load_config(ROOT / "config" / "config.yaml")
    return calibrate_striker_velocity(ChainParams.from_config(cfg), "PCF30", "hertz"), cfg


def test_calibrated_foam_is_matched(calibration):
    cal, _ = calibration
    assert cal.tof["PCF30"] == pytest.approx(1.15e-3, rel=1e-5)


@pytest.mark.parametrize("foam", ["PCF08", "PCF15"])
def test_other_foams_are_predicted_within_tolerance(calibration, foam):
    cal, _ = calibration
    assert cal.tof[foam] == pytest.approx(cal.tof_thesis[foam], rel=TOLERANCE)


def test_predictions_keep_the_thesis_order(calibration):
    cal, _ = calibration
    tofs = [cal.tof[row[0]] for row in TABLE2]
    assert tofs[0] > tofs[1] > tofs[2]


def test_config_holds_the_calibrated_striker_speed(calibration):
    cal, cfg = calibration
    assert cfg["chain"]["striker_velocity"] == pytest.approx(cal.striker_velocity, rel=2e-3)


def test_foams_outside_the_k_table_are_skipped_with_the_reason():
    """A K table holding nu = 0.3 only (the CI study's) calibrates on PCF 30 and names why
    PCF 08 and PCF 15 (nu 0.34, 0.33) have no prediction, instead of failing the rule."""
    from ssw.errors import OutOfRangeError

    class OneNuTable:
        def K(self, E, nu):
            nu = np.asarray(nu, dtype=float)
            if np.any(nu != 0.3):
                raise OutOfRangeError("soil_nu must equal 0.3 -: the table has one value")
            return np.ones(np.broadcast_shapes(np.shape(E), nu.shape))

    cfg = load_config(ROOT / "config" / "config.yaml")
    params = ChainParams.from_config(cfg, fit_law="k_hertz")
    cal = calibrate_striker_velocity(params, "PCF30", "fit", k_table=OneNuTable())
    assert cal.tof["PCF30"] == pytest.approx(1.15e-3, rel=1e-5)
    assert cal.tof["PCF08"] is None and cal.tof["PCF15"] is None
    assert set(cal.skipped) == {"PCF08", "PCF15"}
    assert "one value" in cal.skipped["PCF08"]


def test_a_calibration_file_sets_the_striker_speed(tmp_path, capsys):
    """`--calibration FILE` (what the workflow passes) gives the TOF of that striker speed,
    and a file that is not a tof-calibrate result is refused, naming the option."""
    import json

    from ssw.chain.calibration import read_calibrated_velocity
    from ssw.cli import main
    from ssw.errors import ConfigError

    cal = tmp_path / "calibration.json"
    cal.write_text(json.dumps({"command": "tof-calibrate", "striker_velocity": 0.8}))
    assert read_calibrated_velocity(cal) == 0.8
    cfg = str(ROOT / "config" / "config.yaml")
    tof = []
    for extra in (["--calibration", str(cal)], ["--striker-velocity", "0.8"], []):
        assert main(["tof", "--config", cfg, "--law", "hertz", "--soil-E", "1e8",
                     "--soil-nu", "0.3", "--json", *extra]) == 0
        tof.append(json.loads(capsys.readouterr().out)["tof"])
    assert tof[0] == tof[1]
    assert tof[2] > tof[0]  # the config's 0.52 m/s is slower: a longer TOF
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"command": "tof", "tof": 1e-3}))
    with pytest.raises(ConfigError, match="--calibration"):
        read_calibrated_velocity(bad)
