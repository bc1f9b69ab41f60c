"""TOF picking: sub-sample interpolation and the rule for split reflected pulses."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.chain.params import ChainParams
from ssw.chain.tof import pick_peaks, tof_from_signal
from ssw.errors import RecordingError
from ssw.tof import api


def _pulse(t, t0, amp, width):
    """A sech^2 pulse, the shape of a long-wave solitary wave (Nesterenko 2001)."""
    return amp / np.cosh((t - t0) / width) ** 2


def test_split_reflected_wave_picks_the_primary_pulse():
    """Soft soil: the reflected wave splits; the primary (earlier, here SMALLER) pulse is
    the reflected peak, not the larger secondary one nor the ripples before it."""
    t = np.arange(0, 5e-3, 1 / 51200)  # NI 9234 at full rate
    F = (
        4.0
        + _pulse(t, 0.8e-3, 200.0, 40e-6)
        + _pulse(t, 2.6e-3, 70.0, 50e-6)  # primary reflected
        + _pulse(t, 3.0e-3, 120.0, 50e-6)  # secondary reflected, larger
        + 6.0 * np.sin(2 * np.pi * 8e3 * t) * (t > 1.2e-3) * (t < 2.2e-3)  # ripples
    )
    pk = pick_peaks(t, F)
    assert pk.t_incident == pytest.approx(0.8e-3, abs=1e-6)
    assert pk.t_reflected == pytest.approx(2.6e-3, abs=1.5e-6)
    assert pk.tof == pytest.approx(1.8e-3, abs=2e-6)


def test_twin_peaked_reflected_pulse_takes_its_first_peak():
    t = np.arange(0, 5e-3, 1e-6)
    F = _pulse(t, 1e-3, 250.0, 30e-6) + _pulse(t, 3.0e-3, 128.0, 20e-6) + _pulse(
        t, 3.08e-3, 120.0, 20e-6
    )
    assert tof_from_signal(t, F) == pytest.approx(2.0e-3, abs=2e-7)


@pytest.mark.parametrize("shift", [0.0, 0.17, 0.5, 0.83])
def test_parabolic_interpolation_resolves_below_the_sample_step(shift):
    """At the NI 9234's 19.5 us step, peaks between samples are located to < 1 us."""
    dt = 1 / 51200
    t = np.arange(0, 4e-3, dt)
    t1, t2 = 1e-3 + shift * dt, 2.3e-3 + 0.37 * dt
    F = _pulse(t, t1, 200.0, 45e-6) + _pulse(t, t2, 150.0, 45e-6)
    assert tof_from_signal(t, F) == pytest.approx(t2 - t1, abs=1e-6)


def test_columns_are_picked_independently():
    t = np.arange(0, 4e-3, 2e-6)
    F = np.stack([_pulse(t, 1e-3, 100, 30e-6) + _pulse(t, 1e-3 + d, 60, 30e-6)
                  for d in (1e-3, 1.5e-3, 2e-3)], axis=1)
    np.testing.assert_allclose(tof_from_signal(t, F), [1e-3, 1.5e-3, 2e-3], atol=1e-8)


def test_no_reflection_is_an_error():
    t = np.arange(0, 4e-3, 2e-6)
    with pytest.raises(RecordingError, match="reflected"):
        pick_peaks(t, _pulse(t, 1e-3, 100, 30e-6))


def test_chain_with_gravity_splits_soft_soil_reflections_and_picks_the_first():
    """In the simulated device (gravity on) a 10 MPa soil reflects two pulses; the picked
    peak is the first one: no local maximum above 20 % of the reflected maximum lies
    between the incident pulse's end and the picked time."""
    p = ChainParams(striker_velocity=0.5246)
    t, F = api.sensor_signal(10e6, 0.3, p)
    pk = pick_peaks(t, F)
    s = F - F[0]
    is_max = np.r_[False, (s[1:-1] > s[:-2]) & (s[1:-1] >= s[2:]), False]
    between = is_max & (t > pk.t_incident + 0.3e-3) & (t < pk.t_reflected - t[1])
    assert np.all(s[between] < 0.2 * pk.f_reflected)
    later = t > pk.t_reflected + 0.2e-3
    assert np.max(s[later]) > 0.4 * pk.f_reflected  # a secondary pulse exists


@pytest.mark.parametrize("split", [0.2, 0.7])
def test_recordings_and_simulations_share_one_peak_rule(split):
    """One rule (ssw.signal.rule) for both pickers: on a noiseless record with a split
    reflection, ssw.signal.peaks (a measured record's picker, without upsampling) and
    ssw.chain.tof pick the same samples and so the same parabolic vertices, with the
    default rule (the primary pulse) and with a split share that skips it (the secondary
    pulse, 0.4 ms later)."""
    from ssw.signal.peaks import pick_peaks as record_peaks
    from ssw.signal.rule import PeakRule

    rate = 51200.0
    t = np.arange(0, 5e-3, 1 / rate)
    F = (_pulse(t, 0.8e-3, 200.0, 40e-6) + _pulse(t, 2.6e-3, 70.0, 50e-6)
         + _pulse(t, 3.0e-3, 120.0, 50e-6))
    rule = PeakRule(split_fraction=split)
    rec = record_peaks(F, rate, 0.0, rule, upsample=1)
    sim = pick_peaks(t, F, rule=rule)
    assert rec.tof == pytest.approx(float(sim.tof), abs=1e-12)
    assert rec.tof == pytest.approx(1.8e-3 if split < 0.5 else 2.2e-3, abs=2e-6)
