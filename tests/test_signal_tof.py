"""TOF from waveforms: parabolic interpolation, peak rule, delays, rejection and statistics.

Truth: analytic sech^2 pulses with known peak times (a parabola's vertex; the convergence
order of three-point parabolic interpolation at a smooth symmetric maximum, O(dt^3)).
"""

from __future__ import annotations

import numpy as np
import pytest

from ssw.daq.simulated import sech2
from ssw.errors import RecordingError
from ssw.signal.filters import lowpass
from ssw.signal.live import LiveTof
from ssw.signal.peaks import PeakError, PeakRule, parabolic_vertex, pick_peaks, refine_peak
from ssw.signal.tof import TofOptions, session_tof

W = 40e-6  # s, pulse width (a solitary wave at the sensor lasts ~0.1 ms)


def record(rate, t_peaks, heights, n_pre=64, duration=4e-3, width=W):
    """Sum of sech^2 pulses sampled at ``rate`` (t = 0 at sample 0)."""
    t = np.arange(int(duration * rate)) / rate
    y = np.zeros_like(t)
    for tp, h in zip(t_peaks, heights, strict=True):
        y += h * sech2((t - tp) / width)
    return y


def test_parabolic_vertex_is_exact_on_a_parabola():
    k = np.arange(10.0)
    y = 3.0 - 0.7 * (k - 4.3) ** 2
    pos, height = parabolic_vertex(y, 4)
    assert pos == pytest.approx(4.3, abs=1e-12) and height == pytest.approx(3.0, abs=1e-12)


def test_parabolic_error_converges_at_third_order():
    """At a smooth symmetric maximum the vertex error scales as dt^3 (odd terms vanish)."""
    rates = 51200.0 * 2.0 ** np.arange(4)
    worst = []
    for fs in rates:
        errs = []
        for phase in np.linspace(0.0, 1.0, 11)[:-1]:
            t0 = 1e-3 + phase / fs
            y = record(fs, [t0], [1.0])
            pos, _ = parabolic_vertex(y, int(np.argmax(y)))
            errs.append(pos / fs - t0)
        worst.append(np.max(np.abs(errs)))
    slope = np.polyfit(np.log(rates), np.log(worst), 1)[0]
    assert slope == pytest.approx(-3.0, abs=0.2)
    assert worst[0] < 0.5 / rates[0]  # never worse than half a sample


def test_upsampled_vertex_beats_the_parabola_on_a_band_limited_pulse():
    """A sech^2 pulse 3.5 samples wide at half height: x16 band-limited interpolation puts
    the vertex within a hundredth of a sample at every phase, the parabola alone within
    half a sample only (its error is O(dt^3) with a large constant at this width)."""
    rate = 51200.0
    worst = {1: 0.0, 16: 0.0}
    for phase in np.linspace(0.0, 1.0, 16, endpoint=False):
        t0 = 1e-3 + phase / rate
        y = record(rate, [t0], [1.0])
        for up in worst:
            pos, h = refine_peak(y, int(np.argmax(y)), up)
            worst[up] = max(worst[up], abs(pos / rate - t0))
            if up == 16:
                assert h == pytest.approx(1.0, rel=1e-3)
    assert worst[16] < 0.01 / rate < worst[1] < 0.5 / rate


def test_upsampling_removes_the_parabola_bias_on_the_chains_pulses():
    """The chain's pulses on PCF 08 (38 MPa) are asymmetric: the parabola on the samples is
    biased one way (every hit's TOF short by 0.5-2 us here); after x16 interpolation the TOF
    of each simulated NI 9234 record matches the TOF of the analog signal it sampled (the
    module's anti-alias output, picked on its 16x finer grid) to noise level."""
    from ssw.chain.params import ChainParams
    from ssw.chain.tof import pick_peaks as chain_peaks
    from ssw.daq.settings import DaqSettings
    from ssw.daq.simulated import SimulatedBackend

    s = DaqSettings(hits=8)
    b = SimulatedBackend(soil_E=38e6, soil_nu=0.34, chain_params=ChainParams(), seed=3)
    t_fine, y_fine = b.analog(s)
    truth = float(chain_peaks(t_fine, y_fine).tof)
    forces = [h.force for h in b.hits(s, s.hits)]
    err = {up: session_tof(forces, s.sample_rate, s.pretrigger_samples,
                           opts=TofOptions(upsample=up)).tof - truth for up in (1, 16)}
    assert abs(np.mean(err[16])) < 0.3e-6 and np.max(np.abs(err[16])) < 0.5e-6
    assert np.all(err[1] < -0.5e-6)  # the bias the upsampling removes, beyond its bound


def test_live_hook_gives_the_session_statistics_hit_by_hit():
    rate = 51200.0
    rng = np.random.default_rng(2)
    d = np.array([-4e-6, 1e-6, 3e-6, 2e-4])  # the last one is an outlier
    forces = [record(rate, [1.5e-3, 1.5e-3 + 1.46e-3 + di], [60.0, 25.0])
              + rng.normal(0.0, 0.02, int(4e-3 * rate)) for di in d]
    seen = []
    live = LiveTof(rate, 64, TofOptions(), estimate=lambda m, s: {"E": m, "E_low": m - s,
                                                                   "E_high": m + s})
    reports = [live.add(f) for f in forces]
    for r in reports[:3]:
        seen.append(r.tof)
        assert r.tof_mean == pytest.approx(np.mean(seen), rel=1e-12)
    assert reports[1].tof_sem == pytest.approx(np.std(seen[:2], ddof=1) / np.sqrt(2))
    assert reports[3].tof is None and "outlier" in reports[3].reason
    final = session_tof(forces, rate, 64)
    assert reports[3].tof_mean == pytest.approx(final.mean, rel=1e-12)
    assert reports[3].n_accepted == final.n_accepted == 3
    assert reports[3].estimate["E"] == reports[3].tof_mean


@pytest.mark.parametrize("rate", [51200.0, 25600.0, 12800.0])
@pytest.mark.parametrize("phase", [0.0, 0.37, 0.81])
def test_tof_of_two_pulses_within_half_a_sample(rate, phase):
    t_i = 1e-3 + phase / rate
    tof = 1.46e-3  # s, PCF 15 (thesis Table 2)
    y = record(rate, [t_i, t_i + tof], [60.0, 25.0])
    pp = pick_peaks(y, rate, noise=0.0, rule=PeakRule())
    assert abs(pp.tof - tof) < 0.5 / rate
    if rate == 51200.0:  # ~2 samples per pulse width: the vertex height is close too
        assert pp.f_incident == pytest.approx(60.0, rel=0.05)


def test_single_peak_and_flat_records_are_rejected():
    y = record(51200.0, [1e-3], [60.0])
    with pytest.raises(PeakError, match="single peak"):
        pick_peaks(y, 51200.0, 0.0, PeakRule())
    with pytest.raises(PeakError, match="no peak"):
        pick_peaks(np.zeros(100), 51200.0, 0.1, PeakRule())


def test_primary_reflected_pulse_is_taken_even_if_a_later_one_is_larger():
    """Soft media split the reflection (Yang et al. 2011): TOF is the first pulse's."""
    y = record(51200.0, [1e-3, 2.2e-3, 2.6e-3], [60.0, 15.0, 30.0])
    pp = pick_peaks(y, 51200.0, 0.0, PeakRule())
    assert pp.tof == pytest.approx(1.2e-3, abs=0.5 / 51200.0)


def test_a_common_delay_cancels_in_the_peak_to_peak_tof():
    """A linear-phase FIR delays both pulses equally: the TOF does not change."""
    rate, tof = 51200.0, 1.15e-3
    y = record(rate, [1e-3, 1e-3 + tof], [60.0, 40.0])
    taps = np.hanning(9) / np.hanning(9).sum()  # symmetric: 4-sample delay
    delayed = np.convolve(y, taps)[: y.size]
    a = pick_peaks(y, rate, 0.0, PeakRule())
    b = pick_peaks(delayed, rate, 0.0, PeakRule())
    assert b.t_incident - a.t_incident == pytest.approx(4 / rate, abs=0.05 / rate)
    assert b.tof == pytest.approx(a.tof, abs=0.05 / rate)


def test_zero_phase_lowpass_does_not_shift_peaks():
    rate, tof = 51200.0, 1.8e-3
    y = record(rate, [1e-3, 1e-3 + tof], [60.0, 60.0])
    a = pick_peaks(y, rate, 0.0, PeakRule())
    b = pick_peaks(lowpass(y, rate, 8000.0), rate, 0.0, PeakRule())
    assert b.t_incident == pytest.approx(a.t_incident, abs=0.05 / rate)
    assert b.tof == pytest.approx(a.tof, abs=0.05 / rate)


def test_session_statistics_and_outlier_rule():
    """Hits with TOFs 1.46 ms + d_i; one hit 0.2 ms late is rejected as an outlier."""
    rate = 51200.0
    rng = np.random.default_rng(1)
    d = np.array([-6e-6, -2e-6, 0.0, 3e-6, 5e-6, 2e-4])
    forces = []
    for di in d:
        y = record(rate, [1.5e-3, 1.5e-3 + 1.46e-3 + di], [60.0, 25.0])
        forces.append(y + rng.normal(0.0, 0.02, y.size))
    res = session_tof(forces, rate, 64)
    assert res.accepted.tolist() == [True] * 5 + [False]
    assert "outlier" in res.reasons[0]
    true = 1.46e-3 + d[:5]
    assert res.mean == pytest.approx(true.mean(), abs=0.5 / rate)
    assert res.std == pytest.approx(np.std(true, ddof=1), abs=0.2 / rate)
    assert res.cov_pct == pytest.approx(100 * res.std / res.mean)


def test_bad_hits_are_reported_and_too_few_raise():
    rate = 51200.0
    good = record(rate, [1.5e-3, 3.0e-3], [60.0, 25.0])
    single = record(rate, [1.5e-3], [60.0])
    res = session_tof([good, single, good], rate, 64, clipped=[False, False, True],
                      opts=TofOptions(min_hits=1))
    assert res.n_accepted == 1
    assert any("single peak" in r for r in res.reasons) and any("clipped" in r for r in res.reasons)
    with pytest.raises(RecordingError, match="0 of 1 hits accepted"):
        session_tof([single], rate, 64, opts=TofOptions(min_hits=1))
    # by default three accepted hits are needed (the scatter is not estimable below)
    with pytest.raises(RecordingError, match="1 of 3 hits accepted, at least 3"):
        session_tof([good, single, good], rate, 64, clipped=[False, False, True])
