"""The contacts' dissipation laws compared on the references' records
(:mod:`ssw.calibration.laws`, ``ssw calibrate --compare-laws``).

The records are made by the INDEPENDENT chain (scipy's DOP853 on the chain's equations,
tests/chain_dop853.py) of a device whose contacts dissipate by Hunt and Crossley's law,
through the modelled acquisition (tests/test_honesty.py's ``record``); fitted under the
dashpot and under Hunt-Crossley, the criteria must prefer the law that made them. The
criteria's arithmetic is checked against its definitions (Akaike 1974, Schwarz 1978).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from ssw.calibration.laws import INDISTINCT, LawScore, summarize
from ssw.errors import ConfigError


def _score(law: str, n2ll: float, k: int, n: int, unexplained: int = 0) -> LawScore:
    return LawScore(law, "u", 1.0, {}, n2ll, n2ll, k, n, n2ll + 2 * k,
                    n2ll + k * np.log(n), {}, True, unexplained)


def test_the_criteria_rank_by_their_definitions():
    """AIC = -2 ln L + 2 k and BIC = -2 ln L + k ln n: a law with one more parameter is
    preferred by AIC when it gains more than 2 in -2 ln L, by BIC only beyond ln n; a
    law leaving observations unexplained is not compared; within 2 of each other the
    laws are not told apart."""
    n = 400  # ln n = 5.99
    a, b = _score("dashpot", 100.0, 10, n), _score("hunt_crossley", 96.0, 11, n)
    r = summarize([a, b], "features")
    assert r["preferred"] == {"aic": "hunt_crossley", "bic": "dashpot"}
    assert r["laws"][0]["delta_aic"] == pytest.approx((100.0 + 20) - (96.0 + 22))
    assert r["laws"][1]["delta_bic"] == pytest.approx(96.0 - 100.0 + np.log(n))
    assert r["laws"][0]["delta_bic"] == 0.0
    assert "do not tell" in r["statement"]
    c = _score("kuwabara_kono", 10.0, 10, n, unexplained=3)
    r = summarize([a, b, c], "features")
    assert r["not_compared"] == ["kuwabara_kono"] and r["laws"][2]["delta_bic"] is None
    assert r["preferred"]["bic"] == "dashpot"
    d = _score("hunt_crossley", 100.0 - 2 * INDISTINCT - 10, 10, n)
    r = summarize([a, d], "features")
    assert r["preferred"] == {"aic": "hunt_crossley", "bic": "hunt_crossley"}
    assert r["distinct"] == {"aic": True, "bic": True}
    assert "prefer hunt_crossley" in r["statement"] and "not shown" in r["statement"]


def test_the_start_grid_spans_the_same_dissipation_under_every_law():
    """The dashpot's start grid unchanged (0-10 N s/m); another law's the same damping
    forces at the thesis chain's impact (its typical coefficient over the dashpot's)."""
    from ssw.calibration.waveform import START_DAMPING, start_damping
    from ssw.chain.dissipation import LAWS

    assert start_damping("dashpot") is START_DAMPING
    for name, law in LAWS.items():
        grid = np.array(start_damping(name))
        np.testing.assert_allclose(grid, np.array(START_DAMPING) * law.scale / 5.0,
                                   rtol=1e-15)
        assert grid.max() <= law.upper


def test_compare_laws_is_refused_at_the_tof_level(capsys):
    """TOFs do not identify the contacts' dissipation: --compare-laws asks for a records'
    level, and says so."""
    from ssw.cli import main

    rc = main(["calibrate", "--reference", "38e6,0.34,1.78e-3", "--calibration", "none",
               "--law", "hertz", "--free", "striker_velocity", "--no-loo",
               "--scan-points", "6", "--compare-laws", "--json"])
    err = capsys.readouterr().err
    assert rc != 0 and "--compare-laws" in err and "features or waveform" in err
    with pytest.raises(ConfigError, match="features"):
        from ssw.calibration.laws import compare_laws

        compare_laws([], None, "hertz", {}, None, "tof", trigger_level=5.0,
                     tof_scatter=1.5e-5)


@pytest.mark.slow
def test_the_records_of_a_hunt_crossley_device_prefer_its_law(tmp_path):
    """Three foams (38, 123, 445 MPa), 3 hits each, recorded by the DOP853 chain of a
    device whose every contact dissipates by Hunt and Crossley's law (c = 0.022 s/m: about
    a 9 N s/m dashpot at the impact, :data:`ssw.chain.dissipation.LAWS`), its sensor 1.4x
    a bead. Fitted at the features level under the dashpot and under Hunt-Crossley (each
    from its own start grid, refined once), both criteria prefer Hunt-Crossley by more
    than :data:`ssw.calibration.laws.INDISTINCT`, and its fitted coefficient is the
    device's within 10 %."""
    from chain_dop853 import BEAD_MASS
    from test_honesty import FOAMS, FULL_SCALE, SCATTER, TRIGGER, V, record

    from ssw.calibration.laws import compare_laws
    from ssw.calibration.waveform import Hits
    from ssw.chain.params import chain_params
    from ssw.daq.model import Acquisition
    from ssw.daq.recording import read_recording
    from ssw.device import load_device

    true_c = 0.022
    built = {"sensor_mass": 1.4 * BEAD_MASS, "law": "hunt_crossley", "damping": true_c,
             "preload": 0.0}
    samples = [Hits.from_recording(read_recording(
        record(tmp_path / f"ref{j}.h5", E, nu, 100 + j, built, 3)), E=E, nu=nu,
        full_scale=FULL_SCALE) for j, (E, nu) in enumerate(FOAMS)]
    params = chain_params(load_device("thesis").with_(
        plate_thickness=0.0, plate_material="none", striker_velocity=V, preload=0.0))
    r = compare_laws(samples, params, "hertz", {}, Acquisition(), "features",
                     trigger_level=TRIGGER, tof_scatter=SCATTER,
                     laws=("dashpot", "hunt_crossley"),
                     start_grid=((1.4,), (2.0, 5.0, 8.0)), refine_levels=1)
    rows = {row["law"]: row for row in r["laws"]}
    assert r["preferred"] == {"aic": "hunt_crossley", "bic": "hunt_crossley"}, rows
    assert r["distinct"] == {"aic": True, "bic": True}, rows
    assert rows["dashpot"]["delta_bic"] > INDISTINCT
    assert rows["hunt_crossley"]["coefficient"] == pytest.approx(true_c, rel=0.1), rows


def test_the_human_output_states_each_law_and_the_finding():
    """``ssw calibrate``'s human output prints each law's coefficient with its unit, chi^2,
    k, n and the criteria's differences, and the comparison's statement."""
    from ssw.cli.calibrate import _human

    r = summarize([_score("dashpot", 100.0, 10, 400),
                   _score("hunt_crossley", 80.0, 10, 400)], "features")
    text = _human({"device_name": "d", "wall": "hertz", "references": [], "parameters": {},
                   "parameter_std": {}, "at_bound": {}, "drop_height": 0.01,
                   "singular_values": [], "unidentified": [], "warnings": [], "loo": [],
                   "alternatives": [], "output": None, "law_comparison": r})
    lines = text.splitlines()
    dash = next(line for line in lines if line.strip().startswith("dashpot"))
    assert dash.split()[-2:] == ["20.0", "20.0"]  # its AIC and BIC above Hunt-Crossley's
    assert "prefer hunt_crossley" in lines[-1]
