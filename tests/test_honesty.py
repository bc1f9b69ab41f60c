"""Honesty under model error: recordings made by an INDEPENDENT chain (scipy's DOP853 on the
chain's equations, tests/chain_dop853.py) of devices "as built", through the modelled
acquisition (:mod:`ssw.daq.model`: coupling, anti-alias filter, input delay, the NI 9234's
noise floor, quantization, a trigger with jitter), 5 hits per sample with a 3 % scatter of
the striker speed, the references' TOFs as precise as their hits make them (the standard
error of 5 hits' mean).

The device ``as_built`` departs from every law ssw offers (:data:`DEVICES`): its sensor
particle is 1.4x a bead's mass and its two contacts are 0.8x as stiff as a bead's (a bead
cut around a piezoelectric disc); the striker is 3 % heavier than a bead; every bead
contact dissipates by Tsuji's law (``c d^(1/4) d'``, ``c`` = 80 N s/m^1.25: about a
4 N s/m dashpot at these overlaps, :func:`test_the_as_built_dissipation_is_of_a_dashpots_size`)
and the wall's contact by Hunt and Crossley's (``c F d'``, 0.5 s/m: a coefficient of
restitution of ~0.9 at the wall's closing speeds). ssw's model has a constant dashpot, no
sensor stiffness, a Hertz wall.

Calibrated on three foams (38, 123, 445 MPa): the TOF level through ``ssw calibrate
--reference-recording FILE.csv,E,nu`` (CSV files, the command line), its references
rejecting the model (chi^2 beyond its 95 % quantile) so that it carries the model-error
term (:mod:`ssw.calibration.model_error`); then the features (from the start grid of the
sensor's mass and the dashpot; the model's discrepancy fitted where the floor exceeds the
chain's own error) and the whole waveform (from the features' calibration), each with the
model-error floor their residuals call for
(:func:`ssw.calibration.records.calibrate_levels`). Four samples it never saw (20-800 MPa)
are measured at every level, and through the records' calibrations a clipped hit, an
untriggered time offset and hits on a sample that yields. What is asserted is what an honest
answer needs: every level calibrates; the TOF level's unseen E inside its 95 % interval,
whose budget carries the model term; at the features or the waveform level, unflagged,
every unseen E inside its interval, within 5 %, the interval at least 2x narrower than the
TOF level's; through that level the clipped and the yielding recordings flagged, the offset
one flagged or without effect on E.

``python tests/test_honesty.py`` prints the table (the full study: 20-30 min of CPU;
``--help`` for a cut one); ``test_the_as_built_device_is_honest_small`` is its smaller
variant in the default suite (the TOF and features levels, 3 hits a sample, the unseen 20
MPa alone, the start grid cut to one point, no bad records: 113-143 s on 2 cores,
2026-11-29).

Measured (2026-11-29, ``python tests/test_honesty.py``, the full start grid and its
refinements, 27 min of wall time on 2 cores shared with other work): the references reject
the TOF model (chi^2 763 on 2 degrees of freedom), ``tau`` = 2.75 %; the features
calibration holds the striker to its weighed mass (its prior,
:data:`ssw.calibration.hits.GLOBAL_PRIORS`: 1.007x a bead, gain 1.033) and corrects the
model by its discrepancy (:mod:`ssw.calibration.discrepancy`); the unseen 20, 80, 250 and
800 MPa come out -4.5, -1.9, +0.3 and +4.9 % inside TOF intervals 64-122 % wide and -1.6,
+1.5, -0.3 and -3.0 % inside features intervals 25-47 % wide, none flagged; the clipped and
the yielding records flagged, the offset one moving E by 3e-4. The waveform level answers
-20 (flagged), -6, +19 and +27 % inside intervals 1020 % wide (its leave-one-out term 62 %):
honest, of no use on this device. Without the striker's prior the features calibration
traded the striker (0.77x) for the gain (1.38) and put 800 MPa 18 % low. The smaller
variant: -4.7 % inside 63 % at the TOF level, -1.3 % inside 24 % at the features level,
254 s with other work beside it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from chain_dop853 import BEAD_MASS, sensor_signal

#: Devices as built (:func:`chain_dop853.sensor_signal`'s keywords). ``as_built``: outside
#: every law ssw offers (module docstring); ``dashpot``: the former study's device, inside
#: ssw's dashpot family (its sensor 1.5x a bead, a 5 N s/m dashpot in every contact).
DEVICES = {
    "as_built": {"sensor_mass": 1.4 * BEAD_MASS, "sensor_stiffness": 0.8,
                 "striker_mass": 1.03 * BEAD_MASS, "law": "tsuji", "damping": 80.0,
                 "wall_law": "hunt_crossley", "wall_damping": 0.5, "preload": 0.0},
    "dashpot": {"sensor_mass": 1.5 * BEAD_MASS, "damping": 5.0, "preload": 0.0},
}
V, COV, HITS = 0.5, 0.03, 5
FOAMS = [(38.0e6, 0.34), (123.0e6, 0.33), (445.0e6, 0.30)]
UNSEEN = [(20.0e6, 0.35), (80.0e6, 0.30), (250.0e6, 0.30), (800.0e6, 0.28)]
LEVELS = ("tof", "features", "waveform")
#: The records' trigger level (N), a hit's TOF scatter (s: the thesis's), the rails (N).
TRIGGER, SCATTER, FULL_SCALE = 5.0, 1.53e-5, 445.0


def record(path: Path, E: float, nu: float, seed: int, device: dict, hits: int = HITS
           ) -> Path:
    """A session of ``hits`` hits of the DOP853 chain of ``device`` through the modelled
    acquisition (HDF5)."""
    from ssw.daq.model import Acquisition, tabulated
    from ssw.daq.recording import RecordingWriter
    from ssw.daq.settings import DaqSettings, SimulationSettings
    from ssw.daq.simulated import sample_hit

    settings = DaqSettings(simulation=SimulationSettings(
        noise_rms=Acquisition().noise, trigger_jitter=2e-6))
    rng = np.random.default_rng(seed)
    with RecordingWriter(path, settings, {"sample_id": path.stem, "synthetic": True},
                         overwrite=True) as w:
        for _ in range(hits):
            v = V * (1.0 + COV * rng.normal())
            t, s = sensor_signal(E, nu, v, **device)
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


def yielding(path: Path, cal, hits: int = HITS) -> object:
    """Hits on a sample of the last unseen modulus that yields (von Mises, 5 MPa), by ssw's
    chain with the plastic wall (:mod:`ssw.walls.plastic`) of the device as ``cal`` sees it,
    through the same acquisition."""
    from ssw.constitutive import model_from
    from ssw.daq.model import Acquisition
    from ssw.daq.recording import RecordingWriter, read_recording
    from ssw.daq.settings import DaqSettings, SimulationSettings
    from ssw.daq.simulated import sample_hit
    from ssw.tof import api

    E, nu = UNSEEN[-1]
    p = cal.chain_params()
    settings = DaqSettings(simulation=SimulationSettings(
        noise_rms=Acquisition().noise, trigger_jitter=2e-6))
    rng = np.random.default_rng(300)
    with RecordingWriter(path, settings, {"sample_id": path.stem, "synthetic": True},
                         overwrite=True) as w:
        for _ in range(hits):
            v = V * (1.0 + COV * rng.normal())
            wave = api.sensor_force(E, nu, p.with_(striker_velocity=v), "plastic",
                                    soil_model=model_from({"model": "von-mises",
                                                           "yield_stress": 5e6}))
            w.append(sample_hit(wave, settings, rng, {"striker_velocity": v}))
    return read_recording(path)


def _tof_calibration(folder: Path, refs: list[Path]):
    """The TOF level through the command line: the references as CSV files."""
    import json

    from ssw.calibration import load_calibration
    from ssw.cli import main
    from ssw.daq.importers import write_any
    from ssw.daq.recording import read_recording
    from ssw.device import load_device, write_device

    device = load_device("thesis").with_(plate_thickness=0.0, plate_material="none",
                                         striker_velocity=0.45, preload=3.0)
    dev_file = folder / "device.yaml"
    write_device(dev_file, device)
    argv = ["calibrate", "--device", str(dev_file), "--law", "hertz", "--calibration", "none"]
    for path, (E, nu) in zip(refs, FOAMS, strict=True):
        csv = write_any(path.with_suffix(".csv"), read_recording(path))
        argv += ["--reference-recording", f"{csv},{E!r},{nu!r}"]
    out = folder / "tof.json"
    from contextlib import redirect_stdout
    from io import StringIO

    buf = StringIO()
    with redirect_stdout(buf):
        rc = main([*argv, "--output", str(out), "--json"])
    assert rc == 0, "ssw calibrate refused the references"
    return load_calibration(out), json.loads(buf.getvalue())


def study(folder: Path, device: str = "as_built", hits: int = HITS,
          unseen: list[tuple[float, float]] | None = None, levels: tuple[str, ...] = LEVELS,
          start_grid: tuple | None = None, refine_levels: int | None = None,
          bad: bool = True) -> list[dict]:
    """Calibrate on FOAMS (the TOF level through the command line; then the records' levels),
    measure the unseen samples at every level: one row per sample and level, then one per
    bad recording and level, then one per calibration."""
    from ssw.calibration.records import calibrate_levels
    from ssw.calibration.waveform import Hits
    from ssw.daq.model import Acquisition
    from ssw.daq.recording import read_recording
    from ssw.measure import measure, measure_information

    built = DEVICES[device]
    unseen = UNSEEN if unseen is None else unseen
    paths = [record(folder / f"ref{j}.h5", E, nu, 100 + j, built, hits)
             for j, (E, nu) in enumerate(FOAMS)]
    cal, out = _tof_calibration(folder, paths)
    cals = {"tof": cal}
    samples = [Hits.from_recording(read_recording(p), E=E, nu=nu, full_scale=FULL_SCALE)
               for p, (E, nu) in zip(paths, FOAMS, strict=True)]
    if len(levels) > 1:
        cals.update(calibrate_levels(cal, samples, Acquisition(), levels[-1],
                                     trigger_level=TRIGGER, tof_scatter=SCATTER, wall="hertz",
                                     start_grid=start_grid, refine_levels=refine_levels))

    def fitted(c, rec, nu, level):
        m = measure([rec], nu, c.chain_params(), "hertz", {}, calibration=c)
        if level == "tof":
            return m
        info = c.provenance["information"]
        return measure_information(
            m, [rec], level, c.chain_params(), "hertz", {}, acquisition=Acquisition(),
            trigger_level=TRIGGER, tof_scatter=SCATTER, full_scale=FULL_SCALE,
            gain=info["gain"], floor=info["floor"], covariance=info["covariance"],
            model_loo=info.get("model_loo"), discrepancy=info.get("discrepancy"))

    rows = []
    for j, (E, nu) in enumerate(unseen):
        rec = read_recording(record(folder / f"s{j}.h5", E, nu, 200 + j, built, hits))
        for level in levels:
            r = fitted(cals[level], rec, nu, level)
            d = r.to_dict()
            rows.append({"E_true": E, "level": level, "E": r.E, "E_low": r.E_low,
                         "E_high": r.E_high, "error_pct": 100 * (r.E / E - 1),
                         "width_pct": 100 * (r.E_high / r.E_low - 1),
                         "inside": bool(r.E_low <= E <= r.E_high),
                         "flagged": bool(d.get("flagged", False)),
                         "contributions_pct": d["contributions_pct"],
                         "chi2_per_dof": (d["chi2"] / d["chi2_dof"]) if "chi2" in d else None,
                         "identified": sorted({k.split("[")[0] for k in d.get("identified",
                                                                               {})})})
    if bad:  # recordings the model cannot explain, through the records' calibrations
        E, nu = unseen[-1]
        cases = {"clipped": edited(rec, _clip), "offset": edited(rec, _shift),
                 "yielding": yielding(folder / "yield.h5", cals[levels[-1]], hits)}
        for name, b in cases.items():
            for level in levels[1:]:
                d = fitted(cals[level], b, nu, level).to_dict()
                rows.append({"case": name, "level": level, "E": d["E"],
                             "flagged": bool(d["flagged"]),
                             "inside": bool(d["E_low"] <= E <= d["E_high"]),
                             "chi2_per_dof": d["chi2"] / d["chi2_dof"]})
    for level, c in cals.items():
        info = c.provenance.get("information") or {}
        rows.append({"calibration": level, "parameters": dict(c.parameters),
                     "at_bound": dict(c.at_bound), "model_error": c.model_error,
                     "warnings": list(c.warnings), "loo": [
                         {"E": r["E"], "E_predicted": r["E_predicted"]} for r in c.loo],
                     "information": {k: v for k, v in info.items()
                                     if k not in ("start", "from",
                                                  "striker_velocity_per_hit")}})
    rows.append({"cli": {k: out[k] for k in ("model_error", "warnings", "parameters")}})
    return rows


def check(rows: list[dict], levels: tuple[str, ...]) -> list[str]:
    """Assert what every level must give under model error, and return the records' levels
    that also give the sharper answer (module docstring).

    Every level calibrated; the TOF level's references reject the model (its term in the
    file, the command's output and every TOF interval) and each unseen E is inside its TOF
    interval; at every records' level each unseen E is inside its interval or flagged.
    Sharper: unflagged, inside, within 5 %, at least 2x narrower than the TOF's interval;
    through such a level the clipped and the yielding recordings are flagged, the offset
    one flagged or without effect on E.
    """
    from ssw.modulus import MODEL_TERM

    cal = {r["calibration"]: r for r in rows if "calibration" in r}
    assert set(cal) == set(levels), cal.keys()
    assert cal["tof"]["model_error"] is not None, cal["tof"]  # the references reject it
    cli = next(r["cli"] for r in rows if "cli" in r)
    assert cli["model_error"] and cli["warnings"][0].startswith("MODEL ERROR"), cli
    samples = [r for r in rows if "E_true" in r]
    tof = {}
    for r in samples:
        if r["level"] == "tof":
            assert r["inside"], r
            assert r["contributions_pct"][MODEL_TERM] > 0, r
            tof[r["E_true"]] = r["width_pct"]
        else:
            assert r["inside"] or r["flagged"], r

    def sharper(level: str) -> bool:
        return all(not r["flagged"] and r["inside"] and abs(r["error_pct"]) < 5.0
                   and 2.0 * r["width_pct"] <= tof[r["E_true"]]
                   for r in samples if r["level"] == level)

    good = [level for level in levels[1:] if sharper(level)]
    for r in rows:
        if "case" in r and r["level"] in good:
            # the features are differences of times within a record: a time offset the
            # trigger did not remove does not change them (nor E); the waveform flags it
            assert r["flagged"] or (r["case"] == "offset" and r["inside"]), r
    return good


def test_the_as_built_dissipation_is_of_a_dashpots_size():
    """Tsuji's c = 80 N s/m^1.25 in the bead contacts damps the incident solitary wave
    between dashpots of 3 and 5 N s/m (its pulse at the sensor, 10 contacts down: the
    peak force lies between theirs), so the study's coefficients are of a real chain's
    size; the wall's Hunt-Crossley coefficient of 0.5 s/m keeps the reflected pulse within
    the dashpots' range too (on 445 MPa, its reflected-to-incident peak ratio is within
    that of no dissipation and that of a 10 N s/m dashpot at the wall)."""
    from chain_dop853 import chain_tof

    def peak(**kw) -> float:
        return float(np.max(sensor_signal(123e6, 0.33, V, t_end=1.5e-3, **kw)[1]))

    tsuji = peak(law="tsuji", damping=80.0)
    assert peak(damping=5.0) < tsuji < peak(damping=3.0)
    # the as-built device's first pulse: TOF defined (its reflected pulse found)
    assert np.isfinite(chain_tof(445e6, 0.30, V, **DEVICES["as_built"]))


def test_the_as_built_device_is_honest_small(tmp_path):
    """The study's smaller variant (module docstring): the TOF and features levels, 3 hits a
    sample, the unseen 20 MPa alone (below every reference: where the waveform's per-sample
    floor alone left E 27 % low inside a 10 % interval, unflagged), the features' start
    grid cut to the full grid's best point (1.4 x a bead, 8 N s/m: the grid's search is the
    slow study's), no bad records. Both levels calibrate and are honest: the TOF level's
    interval, with its model term, holds the true E (without the term it would be under 1 %
    wide around an E 4.7 % low); the features level, through the model's discrepancy,
    which the references' features call for (their floor beyond the chain's own error),
    and the striker held to its weighed mass, is also the sharper answer: within 5 % and
    at least 2x narrower (measured 2026-11-29: -1.3 % inside 24 %, the TOF level's 63 %)."""
    levels = ("tof", "features")
    rows = study(tmp_path, hits=3, unseen=[UNSEEN[0]], levels=levels,
                 start_grid=((1.4,), (8.0,)), refine_levels=0, bad=False)
    assert check(rows, levels) == ["features"]
    feat = next(r for r in rows if r.get("calibration") == "features")
    assert feat["information"]["discrepancy"] is not None, feat["warnings"]
    assert any(w.startswith("MODEL ERROR (features)") for w in feat["warnings"])


@pytest.mark.slow
def test_the_as_built_device_is_honest_at_every_level(tmp_path):
    """The full study on the device outside every law (module docstring): every level
    calibrates and is honest, and the features level is the sharper answer
    (:func:`check`)."""
    assert "features" in check(study(tmp_path), LEVELS)


@pytest.mark.slow
def test_inside_the_dashpot_family_the_features_narrow_the_interval(tmp_path):
    """The full study on the device whose departures ssw's dashpot family contains (its
    sensor 1.5x a bead, 5 N s/m dashpots): honest at every level, and the features give
    every unseen E within 5 %, inside an interval at least 2x narrower than the TOF's."""
    assert "features" in check(study(tmp_path, "dashpot"), LEVELS)


def main(argv: list[str] | None = None) -> list[dict]:
    """The study's table (``python tests/test_honesty.py --help``)."""
    import argparse
    import json
    import tempfile

    ap = argparse.ArgumentParser(description="the honesty study's table")
    ap.add_argument("--device", choices=sorted(DEVICES), default="as_built",
                    help="the recorded device (module docstring)")
    ap.add_argument("--hits", type=int, default=HITS, help="hits per sample")
    ap.add_argument("--levels", default=",".join(LEVELS),
                    help="the levels, comma-separated, from tof (default: all three)")
    ap.add_argument("--start-grid", metavar="SENSOR,DISSIPATION",
                    help="the features' start cut to one point: the sensor's mass (x a "
                         "bead) and the dissipation coefficient (default: the full grid)")
    ap.add_argument("--refine", type=int, default=None,
                    help="refinements of the start (default: the calibration's)")
    ap.add_argument("--no-bad", action="store_true", help="no bad records")
    a = ap.parse_args(argv)
    levels = tuple(a.levels.split(","))
    grid = (None if a.start_grid is None else
            tuple((float(v),) for v in a.start_grid.split(",")))
    with tempfile.TemporaryDirectory() as d:
        rows = study(Path(d), a.device, a.hits, levels=levels, start_grid=grid,
                     refine_levels=a.refine, bad=not a.no_bad)
    for r in rows:
        if "calibration" in r or "cli" in r:
            print(json.dumps(r))
        elif "case" in r:
            print(f"{r['case']:9} {r['level']:9} E {r['E'] / 1e6:8.2f} flagged "
                  f"{r['flagged']!s:5} chi2/dof {r['chi2_per_dof']:.4g}")
        else:
            c2 = r["chi2_per_dof"]
            print(f"{r['E_true'] / 1e6:6.0f} MPa {r['level']:9} E {r['E'] / 1e6:8.2f} "
                  f"[{r['E_low'] / 1e6:8.2f}, {r['E_high'] / 1e6:8.2f}] err "
                  f"{r['error_pct']:+6.2f} % width {r['width_pct']:6.2f} % inside "
                  f"{r['inside']!s:5} flagged {r['flagged']!s:5} chi2/dof "
                  f"{'-' if c2 is None else f'{c2:.3g}'} budget "
                  + ", ".join(f"{k} {v:.3g}" for k, v in r["contributions_pct"].items()))
    good = check(rows, levels)
    print("honest at every level; sharper than the TOF at:", ", ".join(good) or "none")
    return rows


if __name__ == "__main__":
    main()
