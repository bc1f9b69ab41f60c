"""The predicted measurement of ``ssw design --space device --predict``
(:mod:`ssw.design.predict`) against independent truth:

* its TOF level at the design's hits is the design's own resolution ``u_TOF / (TOF S)``
  (the batched run's forward sensitivity of the dense TOF, not ``ssw identify``'s
  separate run and Fisher matrix);
* the calibration's term is the first-order shift of the TOF-level estimator,
  ``(dTOF/d ln v) / (dTOF/d ln E)`` times the striker speed's relative standard error
  (``ssw.tof.api.tof_derivatives``, exact forward sensitivities);
* the model-error hook adds ``tau / S`` in quadrature, systematic (not averaged over hits);
* the per-point interval is the per-hit one over sqrt(hits) where nothing is systematic.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from conftest import run_device_design

from ssw.tof import api

SPACE = {"bead_materials": ["chrome_steel"], "bead_diameters": [9.525e-3], "beads": [12],
         "sensor_positions": [0.5], "plate_materials": ["pla"],
         "striker_mass_ratio": {"range": [0.5, 1.0], "scan": 1},
         "drop_height": {"range": [2e-3, 8e-3], "scan": 2},
         "plate_thickness": {"range": [1e-4, 1.5e-4], "scan": 1},
         "finalists": 1, "refine_evaluations": 0, "moduli": 2, "plate_yield_limit": 3.0}
#: Agreement of two exact first-order sensitivities of the same TOF computed by separate
#: runs (the integrator's round-off on a derivative, tests/test_design_device_cli.py).
DERIV_RTOL = 1e-6


@dataclass(frozen=True)
class _Calibration:
    """A calibration's covariance and model term, as ssw.calibration.Calibration states
    them (SI, over ``covariance_parameters``)."""

    covariance: np.ndarray
    covariance_parameters: tuple[str, ...]
    tau: float | None = None
    path: str = "stated"

    def covariance_array(self) -> np.ndarray:
        return self.covariance

    def model_term(self):
        return None if self.tau is None else type("T", (), {"tau": self.tau})()


@pytest.fixture(scope="module")
def design(tmp_path_factory):
    d = tmp_path_factory.mktemp("predict")
    return run_device_design(d, SPACE, "--predict", "--point-hits", "3"), d


@pytest.fixture(scope="module")
def chain(design):
    from ssw.chain.params import chain_params, numerics_of
    from ssw.config import device_of, library, load_config
    from ssw.daq.settings import settings_from_config
    from ssw.design.device_eval import scaled_contact
    from ssw.design.space import DevicePoint

    res, d = design
    cfg = load_config(str(d / "config.yaml"))
    mats = library(cfg)
    dev = device_of(cfg)
    base = chain_params(dev, mats, **numerics_of(cfg))
    rec = res["recommended"]
    p = DevicePoint.from_dict(rec).params(base, mats)
    wall = {"contact": scaled_contact({**cfg["contact"], "interface": p.plate_interface},
                                      p.bead_radius / base.bead_radius)}
    return p, wall, settings_from_config(cfg, dev)


def test_tof_level_is_the_designs_resolution(design):
    res, _ = design
    rec, pred = res["recommended"], res["prediction"]["devices"]["recommended"]
    assert res["spec"]["hits"] == 3 and res["prediction"]["point_hits"] == 3
    sigma = np.asarray(pred["tof"]["point"]["sigma_lnE"])
    assert sigma == pytest.approx(np.asarray(rec["resolution_E"]), rel=DERIV_RTOL)
    # the features level sees E, and a point of 3 hits narrows the noise by sqrt(3)
    hit = np.asarray(pred["features"]["hit"]["sigma_lnE"])
    assert np.all(np.isfinite(hit)) and np.all(hit > 0)
    assert np.asarray(pred["features"]["point"]["sigma_lnE"]) == pytest.approx(
        hit / np.sqrt(3), rel=1e-12)
    assert "reference" in res["prediction"]["devices"]


def test_calibration_and_model_error_terms(design, chain):
    from ssw.design.predict import predict

    res, _ = design
    rec = res["recommended"]
    p, wall, settings = chain
    E, nu = rec["soil_E"][0], 0.3
    rel_v, tau = 0.01, 0.02
    cal = _Calibration(np.array([[(rel_v * p.striker_velocity) ** 2]]), ("striker_velocity",),
                       tau=tau)
    scatter = np.array([3e-5])
    T = np.array([rec["tof_E"][0]])
    out = predict(p, wall, np.array([E]), nu, settings, tof=T, tof_scatter=scatter,
                  noise_rms=0.05, bias=np.zeros(1), calibration=cal, model_error=tau)
    td = api.tof_derivatives(E, nu, p, "fem", **wall)
    dT_dlnE = float(td.dtof["E"]) * E
    dT_dlnv = float(td.dtof["striker_velocity"]) * p.striker_velocity
    tof = out["tof"]
    assert tof.noise_hit[0] == pytest.approx(scatter[0] / abs(dT_dlnE), rel=DERIV_RTOL)
    assert tof.calibration[0] == pytest.approx(abs(dT_dlnv / dT_dlnE) * rel_v,
                                               rel=DERIV_RTOL)
    assert tof.systematic[0] == pytest.approx(tau * T[0] / abs(dT_dlnE), rel=DERIV_RTOL)
    # systematic terms do not average over hits
    assert tof.sigma(10**9)[0] == pytest.approx(np.hypot(tof.calibration[0],
                                                         tof.systematic[0]), rel=1e-6)
    # the features level: the calibration's term is there, and no TOF model error
    assert out["features"].calibration[0] > 0 and out["features"].systematic[0] == 0


def test_features_objective_ranks_by_the_predicted_interval(design, tmp_path):
    """``--objective features`` recommends the device of the pool whose worst per-point
    features interval is smallest; the resolution's recommended device is in the pool."""
    import json

    from ssw.cli import main

    res, d = design
    out = tmp_path / "obj.json"
    assert main(["design", "--space", "device", "--config", str(d / "config.yaml"),
                 "--calibration", "none", "--merge", str(d / "design.json"), "--objective",
                 "features", "--objective-pool", "2", "--output", str(out)]) == 0
    got = json.loads(out.read_text())
    ranking = got["objective_ranking"]["candidates"]
    assert len(ranking) == 2 and ranking[0]["worst_half_width"] <= ranking[1][
        "worst_half_width"]
    assert got["recommended"]["label"] == ranking[0]["label"]
    hw = got["prediction"]["devices"]["recommended"]["features"]["point"]["half_width"]
    assert max(hw) == pytest.approx(ranking[0]["worst_half_width"], rel=1e-12)
    assert res["recommended"]["label"] in [r["label"] for r in ranking]
