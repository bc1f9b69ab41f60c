"""The model's discrepancy at the features level (:mod:`ssw.calibration.discrepancy`):
the line of each feature's relative residuals in ``ln E``, checked against residuals made
with a known line (recovered exactly, the hits' delays taken out), its JSON form, and the
corrected model's derivative in E against central differences of the corrected model. What
it does on a device outside every law ssw offers is the honesty study's
(tests/test_honesty.py)."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.calibration.discrepancy import POWER, Discrepancy, estimate
from ssw.signal.features import DELAYED, NAMES

E_REF = np.array([38e6, 123e6, 445e6])


def _records(rng, coef, hits=4):
    """Hits of three references: the model's features (smooth in E, each hit its own
    speed's scatter), its delays, and records that depart from it by the line ``coef``."""
    sample = np.repeat(np.arange(E_REF.size), hits)
    E = E_REF[sample]
    base = np.array([1.5e-3, 0.6, 2.0e-3, 0.3, 7.5e-5, 8.5e-5, 230.0])
    model = base[None, :] * (E[:, None] / 1e8) ** np.array([-0.2, 0.05, -0.2, 0.02, 0, 0.03, 0])
    model *= 1.0 + 0.01 * rng.normal(size=model.shape)  # each hit's own speed
    x = (E / np.exp(np.mean(np.log(E_REF)))) ** POWER - 1.0
    data = model * (1.0 + coef[:, 0][None, :] + coef[:, 1][None, :] * x[:, None])
    delay = 1.5e-5 * rng.normal(size=E.size)
    shown = model.copy()
    for k in DELAYED:  # the model as a fit shows it: its DELAYED features carry the delays
        shown[:, NAMES.index(k)] += delay
    return shown, data, delay, sample


def test_the_line_is_recovered_from_residuals_made_with_it():
    """Records that depart from the model by a known line in ``(E / E_0)^(-2/5)`` per
    feature give that
    line back to rounding, the hits' delays (which a fit puts into the DELAYED features)
    taken out first."""
    rng = np.random.default_rng(1)
    coef = np.c_[rng.uniform(-0.1, 0.1, len(NAMES)), rng.uniform(-0.01, 0.01, len(NAMES))]
    d = estimate(*_records(rng, coef), E_REF)
    assert d.references == 3
    assert d.ln_E0 == pytest.approx(np.mean(np.log(E_REF)), rel=1e-15)
    np.testing.assert_allclose(d.coef, coef, rtol=0, atol=1e-12)


def test_a_single_reference_gives_a_constant_and_the_json_form_round_trips():
    """One reference identifies no slope: the correction is its mean residual; the JSON form
    (a calibration's provenance) gives the same correction back."""
    rng = np.random.default_rng(2)
    coef = np.c_[np.full(len(NAMES), 0.05), np.full(len(NAMES), 0.02)]
    model, data, delay, sample = _records(rng, coef)
    one = sample == 1
    d = estimate(model[one], data[one], delay[one], np.zeros(one.sum(), int), E_REF[1:2])
    x = (E_REF[1] / np.exp(np.mean(np.log(E_REF)))) ** POWER - 1.0
    np.testing.assert_allclose(d.coef[:, 0], 0.05 + 0.02 * x, atol=1e-12)
    np.testing.assert_array_equal(d.coef[:, 1], 0.0)
    back = Discrepancy.from_dict(d.to_dict())
    np.testing.assert_array_equal(back.coef, d.coef)
    assert Discrepancy.from_dict(None) is None


def test_the_corrected_model_s_derivative_in_e_is_exact():
    """``d/dE [m (1 + delta(E))]`` from :func:`ssw.calibration.waveform._corrected` against
    central differences of the corrected model (a model ``m ~ E^p`` per feature)."""
    from ssw.calibration.waveform import _corrected

    class _Setup:  # what _corrected reads of a Setup
        discrepancy = Discrepancy(np.c_[np.linspace(-0.1, 0.1, len(NAMES)),
                                        np.linspace(0.02, -0.03, len(NAMES))], 18.6, 3)

    p = np.linspace(-0.25, 0.1, len(NAMES))

    def m(E):
        return 1.7 * (E / 1e8) ** p

    E0 = 2.3e8
    J = np.zeros((len(NAMES), 2))
    J[:, 1] = p * m(E0) / E0  # column 1 is E's
    val, Jc = _corrected(_Setup(), m(E0), J, E0, 1, True)
    h = 1e-6 * E0

    def corrected(E):
        return _corrected(_Setup(), m(E), np.zeros_like(J), E, 1, False)[0]

    np.testing.assert_allclose(val, corrected(E0), rtol=1e-15)
    fd = (corrected(E0 + h) - corrected(E0 - h)) / (2 * h)
    np.testing.assert_allclose(Jc[:, 1], fd, rtol=1e-8)


def test_a_feature_the_line_cannot_follow_loses_its_weight():
    """The cross-validated floor: a feature whose departure is the line keeps a floor near
    the hits' own scatter of it (here 0: none); one whose departure jumps from reference to
    reference by +-8 % about any line gets a floor that covers those jumps."""
    rng = np.random.default_rng(5)
    coef = np.c_[np.full(len(NAMES), 0.03), np.full(len(NAMES), 0.01)]
    model, data, delay, sample = _records(rng, coef)
    k = NAMES.index("amplitude_ratio")
    data[:, k] *= (1.0 + np.array([0.08, -0.08, 0.08]))[sample]
    d = estimate(model, data, delay, sample, E_REF)
    others = [i for i in range(len(NAMES)) if i != k]
    assert np.all(d.sigma[others] < 1e-9)
    assert d.sigma[k] > 0.08
