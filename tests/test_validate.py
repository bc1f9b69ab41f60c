"""Validation rule (thesis Tables 2 and 3): identities of the forward/inverse pair, the
recording path through the simulated NI 9234, the thesis's own percentages, the CLI."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from ssw.chain.params import ChainParams
from ssw.cli import main
from ssw.config import load_config
from ssw.daq.backend import run_session
from ssw.daq.settings import DaqSettings
from ssw.daq.simulated import SimulatedBackend
from ssw.tof import api
from ssw.validation.table import pct, validate_samples

PARAMS = ChainParams()
CFG = load_config()


def cfg_with(samples):
    cfg = copy.deepcopy(CFG)
    cfg["validation"]["samples"] = samples
    return cfg


def test_thesis_table3_percentages_follow_from_its_moduli():
    """Table 3 prints 3, 1, 1 %: |39-38|/38, |122-123|/123, |442-445|/445 rounded."""
    got = [abs(pct(m, e)) for m, e in [(39, 38), (122, 123), (442, 445)]]
    assert np.round(got).tolist() == [3, 1, 1]


def test_model_tof_as_measurement_inverts_to_the_manufacturer_modulus():
    """If the 'measured' TOF is the model's own, E comes back and both differences vanish."""
    E, nu = 123e6, 0.33
    t = float(api.tof(E, nu, PARAMS))
    rows = validate_samples(cfg_with([{"id": "X", "material": "pcf15", "tof_published": t}]),
                            PARAMS, "hertz", {})
    r = rows[0]
    assert r.tof_sim == pytest.approx(t, rel=1e-12) and r.tof_diff_pct < 1e-9
    assert r.E_measured == pytest.approx(E, rel=1e-3) and r.E_diff_pct < 0.1
    assert r.tof_source == "published" and r.E_cov_pct is None


def test_published_means_invert_consistently_with_the_forward_model():
    rows = validate_samples(CFG, PARAMS, "hertz", {})
    assert [r.sample for r in rows] == ["PCF08", "PCF15", "PCF30"]
    for r in rows:
        assert r.tof_measured == r.tof_published
        back = float(api.tof(r.E_measured, r.nu, PARAMS))
        assert back == pytest.approx(r.tof_measured, rel=1e-4)
        assert r.tof_diff_pct == pytest.approx(abs(r.tof_measured - r.tof_sim) / r.tof_sim * 100)


def test_recorded_session_at_the_manufacturer_modulus(tmp_path):
    """A simulated session of PCF 30 at its own E: the measured TOF is within half a sample
    of the simulated one, so E is within the error that half a sample maps to through the
    local slope d ln TOF / d ln E of the model."""
    s = DaqSettings(hits=6, record_samples=1024, pretrigger_samples=64)
    E, nu = 445e6, 0.30
    path = run_session(SimulatedBackend(soil_E=E, soil_nu=nu, chain_params=PARAMS, seed=4),
                       s, tmp_path / "PCF30.h5", sample_id="PCF30", synthetic=True)
    rows = validate_samples(cfg_with([{"id": "PCF30", "material": "pcf30",
                                       "recordings": str(path)}]), PARAMS, "hertz", {})
    r = rows[0]
    half = 0.5 / s.sample_rate
    assert r.tof_source == "recording" and r.n_accepted == 6 and r.synthetic is True
    assert abs(r.tof_measured - r.tof_sim) < half
    T = api.tof(np.array([E / 1.05, E * 1.05]), nu, PARAMS)
    slope = abs(np.log(T[1] / T[0]) / np.log(1.05**2))
    assert r.E_diff_pct < 100 * (half / r.tof_sim) / slope
    assert len(r.E_per_hit) == 6 and r.E_cov_pct is not None


def test_cli_prints_the_contract(capsys, tmp_path):
    assert main(["validate", "--wall", "hertz", "--json", "--outdir", str(tmp_path)]) == 0
    out = json.loads(capsys.readouterr().out)
    keys = {"sample", "E_manufacturer", "nu", "tof_sim", "tof_measured", "tof_diff_pct",
            "E_measured", "E_cov_pct", "E_diff_pct"}
    assert len(out["samples"]) == 3 and all(keys <= set(s) for s in out["samples"])
    for name in ("validation.csv", "validation.h5", "fig10_tof_validation.png",
                 "fig9_tof_scatter.png", "table2_tof.csv", "table3_modulus.csv"):
        assert (tmp_path / name).stat().st_size > 0
    t2 = (tmp_path / "table2_tof.csv").read_text().splitlines()
    assert t2[0].startswith("# ssw ")  # the provenance line
    assert t2[2].startswith("PCF08,38,0.34,") and t2[2].endswith(",1.11")  # |1.78-1.80|/1.80
    header = (tmp_path / "validation.csv").read_text().splitlines()[1]
    assert "tof_sim [s]" in header and "E_measured [Pa]" in header


def test_shipped_example_recordings_are_synthetic_and_give_back_their_tof():
    """data/recordings: labelled synthetic; each TOF within half a sample of the chain TOF
    the simulated backend stored with every hit."""
    from pathlib import Path

    from ssw.daq.recording import read_recording
    from ssw.signal.tof import recording_tof

    files = sorted(Path(__file__).resolve().parent.parent.glob("data/recordings/*.h5"))
    assert [f.stem for f in files] == ["PCF08", "PCF15", "PCF30"]
    assert sum(f.stat().st_size for f in files) < 2e6
    for f in files:
        rec = read_recording(f)
        assert rec.meta["synthetic"] is True and "SYNTHETIC" in rec.meta["notes"]
        res = recording_tof(rec)
        truth = np.array([h.extra["true_tof"] for h in rec.hits])
        assert np.max(np.abs(res.tof - truth)) < 0.5 / rec.sample_rate


def test_inverse_range_is_cut_to_the_k_tables_soils():
    """The fit wall exists only over the K table's soils: the inverse must not leave them."""
    from types import SimpleNamespace

    from ssw.tof.inverse import E_RANGE
    from ssw.validation.table import inverse_range

    table = SimpleNamespace(soil_E=np.array([30e6, 240e6, 450e6]), K=lambda E, nu: 1.0)
    assert inverse_range("fit", {"k_table": table}, PARAMS) == (30e6, 450e6)
    assert inverse_range("fit", {"K": 1.2}, PARAMS) == E_RANGE
    assert inverse_range("hertz", {}, PARAMS) == E_RANGE
