"""Honesty under model error: recordings made by an INDEPENDENT chain (scipy's DOP853 on the
chain's equations, tests/chain_dop853.py) of a device the model does not describe exactly
(its sensor particle 1.5x a bead's mass, a 5 N s/m dashpot in every contact), through the
modelled acquisition (:mod:`ssw.daq.model`: coupling, anti-alias filter, input delay, the
NI 9234's noise floor, quantization, a trigger with jitter), 5 hits per sample with a 3 %
scatter of the striker speed. Calibrated on three foams (TOF level: striker speed and
preload free; the features and the waveform then free what they identify), then four
samples it never saw (20-800 MPa) measured at every level of information. What is
asserted is what an honest answer needs: at every level each unseen E is inside its 95 %
interval or the fit flags the recording (chi2 quantile beyond 0.999); the TOF level within
5 %. ``python tests/test_honesty.py`` prints the table."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from chain_dop853 import BEAD_MASS, sensor_signal

MISFIT = {"sensor_mass": 1.5 * BEAD_MASS, "damping": 5.0, "preload": 0.0}
V, COV, HITS = 0.5, 0.03, 5
FOAMS = [(38.0e6, 0.34), (123.0e6, 0.33), (445.0e6, 0.30)]
UNSEEN = [(20.0e6, 0.35), (80.0e6, 0.30), (250.0e6, 0.30), (800.0e6, 0.28)]
NUMERICS = {"gravity": True, "steps_per_contact": 80, "t_max": 0.02, "damping": 0.0}
LEVELS = ("tof", "features", "waveform")


def record(path: Path, E: float, nu: float, seed: int) -> Path:
    """A session of HITS hits of the DOP853 chain through the modelled acquisition."""
    from ssw.daq.model import Acquisition, tabulated
    from ssw.daq.recording import RecordingWriter
    from ssw.daq.settings import DaqSettings, SimulationSettings
    from ssw.daq.simulated import sample_hit

    settings = DaqSettings(simulation=SimulationSettings(
        noise_rms=Acquisition().noise, trigger_jitter=2e-6))
    rng = np.random.default_rng(seed)
    with RecordingWriter(path, settings, {"sample_id": path.stem, "synthetic": True},
                         overwrite=True) as w:
        for _ in range(HITS):
            v = V * (1.0 + COV * rng.normal())
            t, s = sensor_signal(E, nu, v, **MISFIT)
            w.append(sample_hit((tabulated(t, s), float(t[-1])), settings, rng,
                                {"striker_velocity": v}))
    return path


def study(folder: Path) -> list[dict]:
    """Calibrate on FOAMS (TOF; then the features and the waveform refine it), measure
    UNSEEN at every level: one row per sample and level, then one per calibration."""
    from ssw.calibration import Reference, calibrate
    from ssw.calibration.waveform import Hits, calibrate_records, with_fit
    from ssw.daq.model import Acquisition
    from ssw.daq.recording import read_recording
    from ssw.device import load_device
    from ssw.materials import material_set
    from ssw.measure import measure, measure_information, pooled_tof

    device = load_device("thesis").with_(plate_thickness=0.0, plate_material="none",
                                         striker_velocity=0.45, preload=3.0)
    refs, recs = [], []
    for j, (E, nu) in enumerate(FOAMS):
        rec = read_recording(record(folder / f"ref{j}.h5", E, nu, 100 + j))
        recs.append(rec)
        pool = pooled_tof([rec])
        # the TOF's stated uncertainty: 0.5 % (tests/test_calibration.py's misfit device);
        # the hits' own standard error is smaller than the model's error on this device
        std = max(pool["tof_sem"], 0.005 * pool["tof_mean"])
        refs.append(Reference(E, nu, pool["tof_mean"], std, id=f"E{E / 1e6:g}"))
    cal = calibrate(refs, device, ["striker_velocity", "preload"], materials=material_set(),
                    numerics=NUMERICS, wall="hertz")
    cals = {"tof": cal}
    samples = [Hits.from_recording(r, E=E, nu=nu, full_scale=445.0)
               for r, (E, nu) in zip(recs, FOAMS, strict=True)]
    # the features from the global start; the whole waveform from the features' solution
    for level in LEVELS[1:]:
        start = cal if level == "features" else cals["features"]
        f = calibrate_records(samples, start.chain_params(), "hertz", {}, Acquisition(), level,
                              5.0, 1.53e-5, scan=level == "features")
        cals[level] = with_fit(cal, f, level)
    rows = []
    for j, (E, nu) in enumerate(UNSEEN):
        rec = read_recording(record(folder / f"s{j}.h5", E, nu, 200 + j))
        for level in LEVELS:
            c = cals[level]
            m = measure([rec], nu, c.chain_params(), "hertz", {}, calibration=c)
            r = m if level == "tof" else measure_information(
                m, [rec], level, c.chain_params(), "hertz", {}, acquisition=Acquisition(),
                trigger_level=5.0, tof_scatter=1.53e-5, full_scale=445.0,
                gain=c.provenance["information"]["gain"])
            d = r.to_dict()
            rows.append({"E_true": E, "level": level, "E": r.E, "E_low": r.E_low,
                         "E_high": r.E_high, "error_pct": 100 * (r.E / E - 1),
                         "width_pct": 100 * (r.E_high / r.E_low - 1),
                         "inside": bool(r.E_low <= E <= r.E_high),
                         "flagged": bool(d.get("flagged", False)),
                         "chi2_per_dof": (d["chi2"] / d["chi2_dof"]) if "chi2" in d else None,
                         "identified": sorted({k.split("[")[0] for k in d.get("identified",
                                                                               {})})})
    for level, c in cals.items():
        rows.append({"calibration": level, "parameters": dict(c.parameters),
                     "at_bound": dict(c.at_bound),
                     "information": c.provenance.get("information")})
    return rows


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason=(
    "measured 2026-11-26: the TOF level puts every unseen E inside its 95 % interval (the "
    "references' leave-one-out term, 3.7 %; intervals 15.6-21.0 % wide) with errors -3.95, "
    "-2.30, -0.73, +5.03 %; the features and waveform calibrations do not reach the true "
    "basin from the grid of sensor mass and dashpot (best point 1.7x, 9 N s/m; chi2 per "
    "degree of freedom ~1e8): every features and waveform measurement is flagged (errors "
    "9-78 %; two waveform fits for the model's lack of most of the records' samples), none "
    "is the narrower honest answer the issue asks for"))
def test_every_unseen_modulus_is_inside_its_interval_and_the_records_narrow_it(tmp_path):
    """At every level each unseen E is inside its interval or flagged; the TOF within 5 %;
    and the features or the waveform give, unflagged, every E inside an interval at least
    2x narrower than the TOF's and within 5 %."""
    rows = study(tmp_path)[:-len(LEVELS)]
    for r in rows:
        assert r["inside"] or r["flagged"], r
        if r["level"] == "tof":
            assert abs(r["error_pct"]) < 5.0, r
    tof = {r["E_true"]: r["width_pct"] for r in rows if r["level"] == "tof"}

    def honest(level: str) -> bool:
        return all(not r["flagged"] and r["inside"] and abs(r["error_pct"]) < 5.0
                   and 2.0 * r["width_pct"] <= tof[r["E_true"]]
                   for r in rows if r["level"] == level)

    assert honest("features") or honest("waveform")


if __name__ == "__main__":
    import json
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        out = study(Path(d))
    print(json.dumps(out[-len(LEVELS):], indent=1))
    for r in out[:-len(LEVELS)]:
        print(f"{r['E_true'] / 1e6:6.0f} MPa {r['level']:9} E {r['E'] / 1e6:8.2f} "
              f"[{r['E_low'] / 1e6:8.2f}, {r['E_high'] / 1e6:8.2f}] err {r['error_pct']:+6.2f} % "
              f"width {r['width_pct']:6.2f} % inside {r['inside']!s:5} flagged "
              f"{r['flagged']!s:5} chi2/dof {r['chi2_per_dof']} id {','.join(r['identified'])}")
