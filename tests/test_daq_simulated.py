"""The simulated NI 9234: filter, quantization, trigger, determinism and TOF round trips.

Round-trip tolerance: the peak-to-peak TOF of a record sampled at f_s is estimated by two
parabolic vertices, each within half a sample of the sampled maximum, and the module's
filter delay is common to both peaks; so every hit's TOF must lie within ``0.5 / f_s`` of
the waveform's own TOF (half a sample: 9.8 us at 51.2 kS/s).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from ssw.daq.backend import run_session
from ssw.daq.recording import read_recording
from ssw.daq.settings import DaqSettings, SimulationSettings
from ssw.daq.simulated import (
    PASS_EDGE,
    STOP_DB,
    STOP_EDGE,
    SimulatedBackend,
    analytic_waveform,
    antialias_fir,
    input_delay,
    lsb_volts,
)
from ssw.errors import DaqError, RecordingError
from ssw.signal.tof import recording_tof, session_tof

S = DaqSettings(record_samples=1024, pretrigger_samples=64)


def test_antialias_fir_meets_the_ni9234_mask():
    taps = antialias_fir(16)
    w, h = signal.freqz(taps, worN=2**15, fs=16.0)  # frequency in units of f_s
    mag = np.abs(h)
    assert np.max(np.abs(mag[w <= PASS_EDGE] - 1.0)) < 1e-3  # flat passband
    assert 20 * np.log10(np.max(mag[w >= STOP_EDGE])) < -STOP_DB + 1.0
    assert taps.size % 2 == 1 and np.allclose(taps, taps[::-1])  # linear phase


def test_quantization_is_24_bit_over_plus_minus_5_volts():
    assert lsb_volts() == pytest.approx(10.0 / 2**24)
    hit = next(SimulatedBackend(analytic_waveform(1.5e-3), seed=2).hits(S, 1))
    codes = hit.force * S.sensitivity / lsb_volts()
    np.testing.assert_allclose(codes, np.round(codes), atol=1e-6)


def test_record_starts_pretrigger_samples_before_the_trigger_crossing():
    for hit in SimulatedBackend(analytic_waveform(1.5e-3), seed=3).hits(S, 5):
        k = hit.trigger_index
        assert k == S.pretrigger_samples and hit.force.size == S.record_samples
        assert hit.force[k - 1] < S.trigger_level <= hit.force[k]


def test_same_seed_same_records_other_seed_different():
    wave = analytic_waveform(1.2e-3)
    a = [h.force for h in SimulatedBackend(wave, seed=5).hits(S, 3)]
    b = [h.force for h in SimulatedBackend(wave, seed=5).hits(S, 3)]
    c = [h.force for h in SimulatedBackend(wave, seed=6).hits(S, 3)]
    np.testing.assert_array_equal(np.array(a), np.array(b))
    assert not np.array_equal(np.array(a), np.array(c))


def test_input_delay_of_the_module():
    assert input_delay(51200.0) == pytest.approx(38.4 / 51200.0 + 4.5e-6)


@pytest.mark.parametrize("rate", [51200.0, 25600.0])
def test_analytic_round_trip_within_half_a_sample(tmp_path, rate):
    tof = 1.46e-3
    s = DaqSettings(sample_rate=rate, record_samples=512, pretrigger_samples=32, hits=8)
    path = run_session(SimulatedBackend(analytic_waveform(tof), seed=11), s, tmp_path / "a.h5",
                       sample_id="analytic", synthetic=True)
    res = recording_tof(read_recording(path))
    assert res.n_accepted == 8
    assert np.max(np.abs(res.tof - tof)) < 0.5 / rate


def test_chain_round_trip_within_half_a_sample(tmp_path):
    """Simulated recordings of the three foams give the chain's TOF back."""
    from ssw.chain.params import ChainParams
    from ssw.tof import api

    params = ChainParams()
    s = DaqSettings(record_samples=1024, pretrigger_samples=64, hits=5)
    for E, nu in [(38e6, 0.34), (123e6, 0.33), (445e6, 0.30)]:
        b = SimulatedBackend(soil_E=E, soil_nu=nu, chain_params=params, seed=1)
        truth = float(api.tof(E, nu, params))
        assert b.true_tof == pytest.approx(truth)
        res = session_tof([h.force for h in b.hits(s, s.hits)], s.sample_rate,
                          s.pretrigger_samples)
        assert res.n_accepted == s.hits
        assert np.max(np.abs(res.tof - truth)) < 0.5 / s.sample_rate


def test_overrange_is_flagged_and_rejected(tmp_path):
    t, f = analytic_waveform(1.5e-3)
    path = run_session(SimulatedBackend((t, 20 * f), seed=1), S, tmp_path / "big.h5",
                       sample_id="x", n_hits=2)
    with pytest.raises(RecordingError, match="clipped"):
        read_recording(path)


def test_no_trigger_is_a_daq_error():
    t, f = analytic_waveform(1.5e-3)
    s = DaqSettings(trigger_level=200.0, simulation=SimulationSettings(noise_rms=0.0))
    with pytest.raises(DaqError, match="no trigger"):
        next(SimulatedBackend((t, f), seed=1).hits(s, 1))


def test_striker_speed_scatter_moves_each_hits_tof_and_is_recovered():
    """Faster strikers give stronger, faster waves (V_s ~ F_m^(1/6)): TOF falls with speed;
    every hit's TOF is still recovered within half a sample of its own wave's TOF."""
    from ssw.chain.params import ChainParams

    s = DaqSettings(record_samples=1024, pretrigger_samples=64,
                    simulation=SimulationSettings(striker_velocity_cov=0.08))
    b = SimulatedBackend(soil_E=123e6, soil_nu=0.33, chain_params=ChainParams(), seed=2)
    hits = list(b.hits(s, 5))
    v = np.array([h.extra["striker_velocity"] for h in hits])
    truth = np.array([h.extra["true_tof"] for h in hits])
    res = session_tof([h.force for h in hits], s.sample_rate, s.pretrigger_samples)
    assert np.max(np.abs(res.tof - truth)) < 0.5 / s.sample_rate
    order = np.argsort(v)
    assert np.all(np.diff(truth[order]) < 0)


def test_recorded_peaks_lag_the_wave_by_the_modules_input_delay():
    """Sample k of a record is at t_first_sample + k/f_s on the wave's clock; the incident
    peak (at 1 ms in the analytic wave) must appear 38.4/f_s + 4.5 us later."""
    from ssw.signal.peaks import PeakRule, pick_peaks

    s = DaqSettings(record_samples=512, pretrigger_samples=32,
                    simulation=SimulationSettings(noise_rms=0.0, trigger_jitter=0.0))
    for hit in SimulatedBackend(analytic_waveform(1.5e-3, t_incident=1e-3), seed=9).hits(s, 4):
        pp = pick_peaks(hit.force, s.sample_rate, 0.0, PeakRule())
        seen = hit.extra["t_first_sample"] + pp.t_incident
        assert seen - 1e-3 == pytest.approx(input_delay(s.sample_rate), abs=0.5 / s.sample_rate)
