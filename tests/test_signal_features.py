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
