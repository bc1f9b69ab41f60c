"""Honesty under model error: recordings made by an INDEPENDENT chain (scipy's DOP853 on the
chain's equations, tests/chain_dop853.py) of a device the model does not describe exactly
(its sensor particle 1.5x a bead's mass, a 5 N s/m dashpot in every contact), through the
modelled acquisition (:mod:`ssw.daq.model`: coupling, anti-alias filter, input delay, the
NI 9234's noise floor, quantization, a trigger with jitter), 5 hits per sample with a 3 %
scatter of the striker speed. Calibrated on three foams (TOF level: striker speed and
preload free; the features then free what they identify, from the grid of sensor mass and
dashpot, with the model-error floor their residuals call for), then four samples it never
saw (20-800 MPa) measured at both levels, and through the features' calibration a clipped
hit, an untriggered time offset and hits on a sample that yields. What is asserted is what
an honest answer needs: the TOF level's unseen E inside its 95 % interval with the model
term its calibration states (the references' chi^2 is above its degrees of freedom, below
its 95 % quantile: the term is stated, not added; ssw.modulus.model_discrepancy); the
features unflagged, inside, within 5 % and at least 2x narrower than the TOF's interval with
that term (the TOF's interval that covers); the clipped
and the yielding recordings flagged, the offset one flagged or without effect on E.
``python tests/test_honesty.py`` prints the table."""

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
#: The levels compared (the whole waveform is not: its calibration from the features' one
#: was not robust under this model error, docs/instrument.md)
LEVELS = ("tof", "features")


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


def _clip(h):
    """A sensor saturating at 60 % of the hit's peak, below the module's rails."""
    from dataclasses import replace

    return replace(h, force=np.minimum(h.force, 0.6 * float(np.max(h.force))))


def _shift(h):
    """The wave 8 samples later than the record's trigger sample says."""
    from dataclasses import replace

    return replace(h, force=np.concatenate([np.full(8, h.force[0]), h.force[:-8]]))


def edited(rec, edit):
    """``rec`` with its first hit edited."""
    from dataclasses import replace

    return replace(rec, hits=(edit(rec.hits[0]), *rec.hits[1:]),
                   path=f"{rec.path}.{edit.__name__}")


def yielding(path: Path, cal) -> object:
    """HITS hits on a sample of the last unseen modulus that yields (von Mises, 5 MPa),
    by ssw's chain with the plastic wall (:mod:`ssw.walls.plastic`) of the misspecified
    device, through the same acquisition."""
    from ssw.constitutive import model_from
    from ssw.daq.model import Acquisition
    from ssw.daq.recording import RecordingWriter, read_recording
    from ssw.daq.settings import DaqSettings, SimulationSettings
    from ssw.daq.simulated import sample_hit
    from ssw.tof import api

    E, nu = UNSEEN[-1]
    p = cal.chain_params(damping=MISFIT["damping"]).with_(
        sensor_mass=MISFIT["sensor_mass"], preload=MISFIT["preload"])
    settings = DaqSettings(simulation=SimulationSettings(
        noise_rms=Acquisition().noise, trigger_jitter=2e-6))
    rng = np.random.default_rng(300)
    with RecordingWriter(path, settings, {"sample_id": path.stem, "synthetic": True},
                         overwrite=True) as w:
        for _ in range(HITS):
            v = V * (1.0 + COV * rng.normal())
            wave = api.sensor_force(E, nu, p.with_(striker_velocity=v), "plastic",
                                    soil_model=model_from({"model": "von-mises",
                                                           "yield_stress": 5e6}))
            w.append(sample_hit(wave, settings, rng, {"striker_velocity": v}))
    return read_recording(path)


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
    from ssw.modulus import model_discrepancy

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
    # the features from the global start
    f = calibrate_records(samples, cal.chain_params(), "hertz", {}, Acquisition(), "features",
                          5.0, 1.53e-5)
    cals["features"] = with_fit(cal, f, "features")
    def fitted(c, rec, level):
        info = c.provenance["information"]
        m = measure([rec], rec_nu[rec.path], c.chain_params(), "hertz", {}, calibration=c)
        return measure_information(
            m, [rec], level, c.chain_params(), "hertz", {}, acquisition=Acquisition(),
            trigger_level=5.0, tof_scatter=1.53e-5, full_scale=445.0, gain=info["gain"],
            floor=info["floor"], covariance=info["covariance"])

    disc = model_discrepancy(cal)
    u_model = disc[0] if disc is not None else 0.0
    rows, rec_nu = [], {}
    for j, (E, nu) in enumerate(UNSEEN):
        rec = read_recording(record(folder / f"s{j}.h5", E, nu, 200 + j))
        rec_nu[rec.path] = nu
        for level in LEVELS:
            c = cals[level]
            m = measure([rec], nu, c.chain_params(), "hertz", {}, calibration=c)
            r = m if level == "tof" else fitted(c, rec, level)
            d = r.to_dict()
            # the interval with the TOF calibration's stated model term in quadrature
            half = np.hypot(0.5 * np.log(r.E_high / r.E_low), 1.959964 * u_model)
            rows.append({"E_true": E, "level": level, "E": r.E, "E_low": r.E_low,
                         "inside_with_model_term": bool(abs(np.log(E / r.E)) <= half),
                         "E_high": r.E_high, "error_pct": 100 * (r.E / E - 1),
                         "width_pct": 100 * (r.E_high / r.E_low - 1),
                         "width_with_model_term_pct": 100 * (np.exp(2 * half) - 1),
                         "inside": bool(r.E_low <= E <= r.E_high),
                         "flagged": bool(d.get("flagged", False)),
                         "chi2_per_dof": (d["chi2"] / d["chi2_dof"]) if "chi2" in d else None,
                         "identified": sorted({k.split("[")[0] for k in d.get("identified",
                                                                               {})})})
    # recordings the model cannot explain, through the calibrations of the records
    bad = {"clipped": edited(rec, _clip), "offset": edited(rec, _shift),
           "yielding": yielding(folder / "yield.h5", cal)}
    for name, b in bad.items():
        rec_nu[b.path] = UNSEEN[-1][1]
        for level in LEVELS[1:]:
            d = fitted(cals[level], b, level).to_dict()
            rows.append({"case": name, "level": level, "E": d["E"],
                         "flagged": bool(d["flagged"]),
                         "inside": bool(d["E_low"] <= UNSEEN[-1][0] <= d["E_high"]),
                         "chi2_per_dof": d["chi2"] / d["chi2_dof"]})
    for level, c in cals.items():
        rows.append({"calibration": level, "parameters": dict(c.parameters),
                     "at_bound": dict(c.at_bound),
                     "information": c.provenance.get("information")})
    return rows


@pytest.mark.slow
def test_every_unseen_modulus_is_inside_its_interval_and_the_records_narrow_it(tmp_path):
    """The TOF level's unseen E inside its interval with the stated model term; every other
    level's inside its interval or flagged; the features or the waveform give, unflagged,
    every E inside an interval at least 2x narrower than the TOF's (with its model term, the
    TOF's interval that covers) and within 5 %; through
    those calibrations a clipped hit and hits on a yielding sample are flagged, an
    untriggered time offset flagged or without effect on E."""
    out = study(tmp_path)
    rows = [r for r in out if "E_true" in r]
    for r in rows:
        assert r["inside"] or r["flagged"] or r["level"] == "tof", r
        if r["level"] == "tof":
            # the references' chi^2 is above its degrees of freedom, below its 95 %
            # quantile: the model term is stated in a note, to be added in quadrature
            # (ssw.modulus.model_discrepancy); with it every unseen E is inside
            assert r["inside_with_model_term"], r
    # the TOF level's interval that covers: with its stated model term (on the grid its own
    # interval at 20 MPa is 0.93 % wide and misses the true E; with the term, 15.6 %)
    tof = {r["E_true"]: r["width_with_model_term_pct"] for r in rows if r["level"] == "tof"}

    def honest(level: str) -> bool:
        return all(not r["flagged"] and r["inside"] and abs(r["error_pct"]) < 5.0
                   and 2.0 * r["width_pct"] <= tof[r["E_true"]]
                   for r in rows if r["level"] == level)

    good = [level for level in LEVELS[1:] if honest(level)]
    assert good, rows
    for r in out:
        if "case" in r and r["level"] in good:
            # the features are differences of times within a record: a time offset the
            # trigger did not remove does not change them (nor E); the waveform flags it
            # (tests/test_measure_information.py)
            assert r["flagged"] or (r["case"] == "offset" and r["inside"]), r


if __name__ == "__main__":
    import argparse
    import json
    import tempfile

    ap = argparse.ArgumentParser(description="the honesty study's table; the recorded device "
                                 "off the features' start grid with the options")
    ap.add_argument("--sensor-mass", type=float, default=1.5,
                    help="the recorded device's sensor particle, in beads' masses")
    ap.add_argument("--damping", type=float, default=5.0,
                    help="the recorded device's dashpot in every contact, N s/m")
    a = ap.parse_args()
    MISFIT.update(sensor_mass=a.sensor_mass * BEAD_MASS, damping=a.damping)
    with tempfile.TemporaryDirectory() as d:
        out = study(Path(d))
    print(json.dumps(out[-len(LEVELS):], indent=1))
    for r in out:
        if "case" in r:
            print(f"{r['case']:9} {r['level']:9} E {r['E'] / 1e6:8.2f} flagged "
                  f"{r['flagged']!s:5} chi2/dof {r['chi2_per_dof']:.4g}")
        if "E_true" not in r:
            continue
        print(f"{r['E_true'] / 1e6:6.0f} MPa {r['level']:9} E {r['E'] / 1e6:8.2f} "
              f"[{r['E_low'] / 1e6:8.2f}, {r['E_high'] / 1e6:8.2f}] err {r['error_pct']:+6.2f} % "
              f"width {r['width_pct']:6.2f} % inside {r['inside']!s:5} flagged "
              f"{r['flagged']!s:5} chi2/dof {r['chi2_per_dof']} id {','.join(r['identified'])}")
