"""Features of a hit's signal (ssw.signal.features) on pulses of known shape: sech^2 pulses
whose peak times, heights and widths are known in closed form, and derivatives against the
closed-form derivatives of those features with respect to the pulses' parameters."""

import numpy as np
import pytest

from ssw.signal.features import NAMES, pulse_features

W = 5e-5  # s, sech^2 width parameter: FWHM = 2 W acosh(sqrt 2)
H = 1 / 51200 / 16  # s, an upsampled record's step


def _pulses(t, pars):
    (ti, ai), (tr, ar), (ts, as_) = pars
    s = lambda x: 1 / np.cosh(x) ** 2  # noqa: E731
    return ai * s((t - ti) / W) + ar * s((t - tr) / W) + as_ * s((t - ts) / W)


def _dpulses(t, pars):
    """d/d(reflected time), d/d(reflected height): closed form."""
    (_, _), (tr, ar), _ = pars
    x = (t - tr) / W
    s2 = 1 / np.cosh(x) ** 2
    return np.stack([ar * 2 * s2 * np.tanh(x) / W, s2], axis=1)


PARS = ((1.0e-3, 10.0), (2.0e-3, 6.0), (2.6e-3, 2.0))


def test_features_of_known_pulses_and_their_derivatives():
    t = np.arange(0.0, 3.4e-3, H)
    y = _pulses(t, PARS)
    f = pulse_features(y, H, dy=_dpulses(t, PARS), noise=1e-3, rate=51200.0)
    got = f.as_dict()
    fwhm = 2 * W * np.arccosh(np.sqrt(2.0))
    expect = {"tof": 1.0e-3, "amplitude_ratio": 0.6, "secondary_tof": 1.6e-3,
              "secondary_ratio": 0.2, "width_incident": fwhm, "width_reflected": fwhm,
              "amplitude": 10.0}
    for name in NAMES:
        assert got[name] == pytest.approx(expect[name], rel=1e-4), name
    j = {n: f.jacobian[i] for i, n in enumerate(NAMES)}
    # the parabolic vertex's own bias varies with the peak's phase on the grid: its
    # derivative is 1 to ~(h / W)^2, not exactly
    assert j["tof"] == pytest.approx([1.0, 0.0], abs=1e-3)
    # per unit of a shift by W and of a height change by the reflected height
    scale = np.array([W, 6.0])
    assert j["amplitude_ratio"] * scale == pytest.approx([0.0, 0.6], abs=1e-4)
    assert j["amplitude"] * scale == pytest.approx([0.0, 0.0], abs=1e-6)
    # linear interpolation between samples at the crossings: exact to ~1e-2 W per W
    assert j["width_reflected"] * scale / W == pytest.approx([0.0, 0.0], abs=1e-2)
    assert np.all(np.isfinite(f.sigma)) and np.all(f.sigma > 0)


def test_a_missing_reflection_gives_nan_not_a_number_made_up():
    t = np.arange(0.0, 3.4e-3, H)
    y = _pulses(t, ((1.0e-3, 10.0), (2.0e-3, 0.0), (2.6e-3, 0.0)))
    f = pulse_features(y, H, noise=1e-3, rate=51200.0)
    assert np.isnan(f.values[0])


RATE = 51200.0  # S/s


def _ripple_record(dip):
    """Incident (100 N) and reflected (40 N) Gaussian pulses 3 samples wide, 1 ms apart,
    with one sample on the reflected pulse's rising flank pushed down to ``dip``: the
    sample before it (13.6 N, above the rule's 0.2 x 40 N and the 4 N noise floor) becomes
    a local maximum of prominence 13.6 - ``dip`` N, below the floor."""
    t = np.arange(400) / RATE
    w = 3.0 / RATE
    y = 100 * np.exp(-0.5 * ((t - 1e-3) / w) ** 2) + 40 * np.exp(-0.5 * ((t - 2e-3) / w) ** 2)
    k = round(2e-3 * RATE)
    assert y[k - 4] > 8.0 and y[k - 4] - dip < 4.0
    y[k - 3] = dip
    return y


@pytest.mark.parametrize("dip", [12.0, 11.0])
def test_features_and_measure_pick_the_same_peaks_of_a_record_with_a_ripple(dip):
    """``ssw measure``'s picker and the features calibration's extractor on one record: the
    same incident and reflected peaks (the ripple has no prominence above the noise floor,
    so neither takes it), their times within a hundredth of a sample; the noiseless
    assembly (no prominence test) takes the ripple, 0.09 ms early."""
    from ssw.signal.features import upsample
    from ssw.signal.peaks import UPSAMPLE, pick_peaks
    from ssw.signal.rule import RULE

    y = _ripple_record(dip)
    noise = 0.5  # N: floor 8 sigma = 4 N
    pair = pick_peaks(y, RATE, noise, RULE)
    up, h = upsample(y), 1 / (UPSAMPLE * RATE)
    f = pulse_features(up, h, noise=noise, rate=RATE)
    assert f.times["incident"] == pytest.approx(pair.t_incident, abs=0.01 / RATE)
    assert f.times["reflected"] == pytest.approx(pair.t_reflected, abs=0.01 / RATE)
    assert pair.t_reflected == pytest.approx(2e-3, abs=0.05 / RATE)
    plain = pulse_features(up, h, noise=noise, rate=RATE, prominence=False)
    assert plain.times["reflected"] < 2e-3 - 4 / RATE
    # the bound of the shortest round trip: the same reflected peak, or none for both
    bounded = pulse_features(up, h, noise=noise, rate=RATE, min_tof=0.9e-3)
    assert bounded.times["reflected"] == pytest.approx(
        pick_peaks(y, RATE, noise, RULE, min_tof=0.9e-3).t_reflected, abs=0.01 / RATE)


def test_features_give_no_reflection_where_measure_finds_the_bound_straddled():
    """A broad reflection peaking just before the shortest round trip: ``ssw measure``
    rejects the record (tests/test_signal_bound.py); the features find no reflected peak."""
    from ssw.signal.features import upsample
    from ssw.signal.peaks import UPSAMPLE, PeakError, pick_peaks
    from ssw.signal.rule import RULE

    t = np.arange(int(4e-3 * RATE)) / RATE
    y = 60 / np.cosh((t - 1e-3) / 40e-6) ** 2 + 30 / np.cosh((t - 1.62e-3) / 80e-6) ** 2
    with pytest.raises(PeakError, match="just before the shortest physical round trip"):
        pick_peaks(y, RATE, 0.0, RULE, min_tof=0.64e-3)
    f = pulse_features(upsample(y), 1 / (UPSAMPLE * RATE), rate=RATE, min_tof=0.64e-3)
    assert np.isnan(f.values[0]) and np.isnan(f.times["reflected"])
    assert np.isfinite(pulse_features(upsample(y), 1 / (UPSAMPLE * RATE), rate=RATE).values[0])
