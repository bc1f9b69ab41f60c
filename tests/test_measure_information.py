"""``ssw measure --information``: the TOF path unchanged to the digit by default; fits of the
features and of the whole waveform through the measurement model that recover E from a
chain recording within their interval, and a goodness of fit that flags recordings the
model does not explain (a clipped hit, a time offset the trigger did not remove, a hit on
a sample that yields) instead of turning them into a confident E."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from ssw.chain.params import chain_params
from ssw.cli import main
from ssw.daq.importers import read_any
from ssw.daq.model import Acquisition
from ssw.device import load_device
from ssw.measure import measure, measure_information

E_TRUE, NU = 123e6, 0.33  # PCF 15 (the simulated sample's library entry)
PARAMS = chain_params(load_device("thesis"))  # the CLI's default device


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    path = tmp_path_factory.mktemp("rec") / "p15.h5"
    assert main(["acquire", "--simulate", "--material", "pcf15", "--wall", "hertz",
                 "--hits", "4", "--sample", "P15", "--output", str(path), "--json"]) == 0
    return str(path)


def _run(capsys, argv):
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_default_is_the_tof_measurement_to_the_digit(capsys, recording):
    base = ["measure", recording, "--soil-nu", str(NU), "--wall", "hertz"]
    default = _run(capsys, base)
    tof = _run(capsys, [*base, "--information", "tof"])
    assert default == tof
    assert "chi2" not in default and "identified" not in default
    # the library function the TOF path has always called gives the same numbers
    m = measure([read_any(recording)], NU, PARAMS, "hertz", {})
    assert default["E"] == m.E and default["E_low"] == m.E_low
    assert default["E_high"] == m.E_high


def _fit(recording, level, edit=None):
    rec = read_any(recording)
    if edit is not None:
        rec = replace(rec, hits=(edit(rec.hits[0]), *rec.hits[1:]))
    m = measure([rec], NU, PARAMS, "hertz", {})
    return measure_information(m, [rec], level, PARAMS, "hertz", {},
                               acquisition=Acquisition(sample_rate=rec.sample_rate),
                               trigger_level=5.0, tof_scatter=1.53e-5, full_scale=445.0)


def test_the_waveform_fit_recovers_e_within_its_interval(recording):
    w = _fit(recording, "waveform")
    d = w.to_dict()
    assert not d["flagged"] and d["fit_converged"]
    assert w.E_low < E_TRUE < w.E_high
    assert abs(w.E / E_TRUE - 1) < 0.01
    assert "E[0]" in d["identified"]
    assert d["E_high"] / d["E_low"] < d["E_tof_high"] / d["E_tof_low"]


def _clip(h):
    """A sensor saturating at 60 % of the hit's peak, below the module's rails."""
    return replace(h, force=np.minimum(h.force, 0.6 * float(np.max(h.force))))


def _shift(h):
    """The wave 8 samples later than the record's trigger sample says."""
    return replace(h, force=np.concatenate([np.full(8, h.force[0]), h.force[:-8]]))


@pytest.mark.parametrize("edit", [_clip, _shift], ids=["clipped-hit", "untriggered-offset"])
def test_a_recording_the_model_cannot_explain_is_flagged(recording, edit):
    """Flagged by chi^2 with every sample explained: the chain's record covers the later
    times that a hit's negative delay reads (before, a delay below -3.4 us left the clipped
    hit's 149 reflected-wave samples without a model value, and the fit kept them out of
    chi^2)."""
    w = _fit(recording, "waveform", edit)
    d = w.to_dict()
    assert d["flagged"] and d["chi2_quantile"] > 0.999
    assert d["unexplained"] == 0
    assert any("FLAGGED: the model does not explain these records" in n for n in d["notes"])


@pytest.fixture(scope="module")
def yielding(recording):
    """The recording's hits replaced by hits on a PCF 15 that yields (von Mises at the
    grade's compressive strength, 4.9 MPa: the Hertz pressure under a 236 N hit is ~3x
    that): the chain with the plastic wall (:mod:`ssw.walls.plastic`), through the same
    acquisition (noise, jitter, quantization)."""
    from ssw.constitutive import model_from
    from ssw.daq.settings import DaqSettings, SimulationSettings
    from ssw.daq.simulated import sample_hit
    from ssw.tof import api

    rec = read_any(recording)
    wave = api.sensor_force(E_TRUE, NU, PARAMS, "plastic", soil_model=model_from(
        {"model": "von-mises", "yield_stress": 4.9e6}))
    settings = DaqSettings(simulation=SimulationSettings(noise_rms=Acquisition().noise,
                                                         trigger_jitter=2e-6))
    rng = np.random.default_rng(7)
    hits = []
    for h in rec.hits:
        s = sample_hit(wave, settings, rng, {})
        hits.append(replace(h, force=s.force, trigger_index=s.trigger_index))
    return replace(rec, hits=tuple(hits))


@pytest.mark.parametrize("level", ["waveform", pytest.param("features", marks=pytest.mark.slow)])
def test_a_hit_on_a_yielding_sample_is_flagged(yielding, level):
    """Hits on a sample that yields, fitted with the elastic wall, are flagged by the fit's
    chi^2 (the TOF alone gives an E 8 % high with nothing to say it is wrong)."""
    m = measure([yielding], NU, PARAMS, "hertz", {})
    w = measure_information(m, [yielding], level, PARAMS, "hertz", {},
                            acquisition=Acquisition(sample_rate=yielding.sample_rate),
                            trigger_level=5.0, tof_scatter=1.53e-5, full_scale=445.0)
    d = w.to_dict()
    assert d["flagged"] and d["chi2_quantile"] > 0.999
    assert any("FLAGGED" in n for n in d["notes"])


def test_calibrate_with_the_waveform_frees_what_the_records_identify(capsys, tmp_path,
                                                                     monkeypatch):
    """Two simulated references of the nominal device (the simulated backend runs the
    chain at its own step; the fit at another): the waveform calibration frees the device's
    globals it identifies and finds the nominal sensor mass, a zero dashpot and unit gain.
    The global start's grid is cut to the nominal point (the device is nominal; the grid's
    search is the slow honesty study's, tests/test_honesty.py)."""
    import ssw.calibration.start as start
    import ssw.calibration.waveform  # noqa: F401  (its re-exports bound before the patch)

    monkeypatch.setattr(start, "START_SENSOR_MASS", (1.0,))
    monkeypatch.setattr(start, "START_DAMPING", (0.0,))
    refs = []
    for mat, E, nu in (("pcf08", 38e6, 0.34), ("pcf30", 445e6, 0.30)):
        path = tmp_path / f"{mat}.h5"
        assert main(["acquire", "--simulate", "--material", mat, "--wall", "hertz", "--hits",
                     "3", "--sample", mat, "--output", str(path), "--json"]) == 0
        capsys.readouterr()
        refs += ["--reference-recording", f"{path},{E},{nu}"]
    # the device file states its striker weighed to 0.2 % (the acquisitions' device else)
    from ssw.device import load_device, write_device

    weighed = float(0.002 * PARAMS.masses[0])
    device = tmp_path / "device.yaml"
    write_device(device, load_device().with_(striker_mass_std=weighed))
    out = tmp_path / "cal.json"
    r = _run(capsys, ["calibrate", *refs, "--wall", "hertz", "--information", "waveform",
                      "--no-loo", "--device", str(device), "--output", str(out)])
    info = r["information"]
    assert info["level"] == "waveform" and "sensor_mass" in info["freed"]
    assert info["values"]["sensor_mass"] == pytest.approx(PARAMS.masses[PARAMS.sensor_index],
                                                          rel=0.01)
    assert abs(info["values"].get("damping", 0.0)) < 0.5
    assert info["gain"] == pytest.approx(1.0, rel=0.01)
    assert json.loads(out.read_text())["provenance"]["information"]["freed"] == info["freed"]
    # the waveform started from the features' calibration; without the references'
    # leave-one-out check (--no-loo) the file says its intervals lack that term
    assert info["from"]["level"] == "features"
    # both levels hold the striker to the device file's weighed mass, not the features'
    # fit of it: the prior's mean and the uncertainty the file states
    prior = [PARAMS.masses[0], weighed]
    assert info["prior"]["striker_mass"] == pytest.approx(prior, rel=1e-12)
    assert info["from"]["prior"]["striker_mass"] == pytest.approx(prior, rel=1e-12)
    assert any(w.startswith("RECORDS (waveform): measured globals held") and "striker_mass"
               in w for w in r["warnings"])
    assert any(w.startswith("RECORDS (waveform): no leave-one-out check")
               for w in r["warnings"])


def test_a_fit_whose_model_lacks_observations_the_record_has_is_flagged():
    """A fit whose model has no value for observations the record has (a pulse or a
    trigger crossing it does not produce: those rows drop out of chi^2, which then counts
    only the rest) is flagged whatever its chi^2 (before: a chi^2 of 10.3 on 1 degree of
    freedom, quantile 0.9986, passed unflagged with E's error 0)."""
    from ssw.calibration.waveform import Fit

    def fit_with(unexplained):
        return Fit(None, [], np.zeros(0), np.zeros((0, 0)), 10.26, 1, 0.9986, False, 43,
                   unexplained=unexplained)

    assert not fit_with(0).flagged
    assert fit_with(1016).flagged


def test_a_measured_global_s_prior_is_one_observation_of_its_offset(recording):
    """A measured global's prior (``Setup.prior``, the striker's weighed mass) is one row:
    ``(value - mean) / std`` in the fit's weighted residuals, its derivative ``1 / std`` in
    that global's column alone; without it the rows are the records' and the hits' priors."""
    from ssw.calibration.hits import Column, Hits, device_globals
    from ssw.calibration.observation import Setup, initial_state, observe

    rec = read_any(recording)
    smp = Hits.from_recording(rec, E=E_TRUE, nu=NU, full_scale=445.0)
    glob = device_globals(PARAMS)
    mean, std = 0.9 * glob["striker_mass"], 0.05 * glob["striker_mass"]
    setup = Setup(PARAMS, "hertz", {}, Acquisition(sample_rate=rec.sample_rate), "features",
                  [smp], 5.0, prior={"striker_mass": (mean, std)})
    state = initial_state(setup, glob, [E_TRUE], float(PARAMS.striker_velocity))
    setup.fix_step(state)
    with_prior = observe(setup, state)
    bare = observe(replace(setup, prior={}), state)
    assert with_prior.model.size == bare.model.size + 1
    last = with_prior.kind == "prior"
    assert np.count_nonzero(last) == 1 and last[-1]
    assert with_prior.model[-1] - with_prior.data[-1] == pytest.approx(
        glob["striker_mass"] - mean, rel=1e-12)
    assert with_prior.sigma[-1] == std
    col = with_prior.columns.index(Column("striker_mass"))
    row = with_prior.jacobian[-1]
    assert row[col] == 1.0 and np.count_nonzero(row) == 1
    np.testing.assert_array_equal(with_prior.model[:-1], bare.model)
