"""The model-error floor of a fit of records (:func:`ssw.calibration.waveform.floor_bound`):
an upper confidence bound of the relative standard deviation a model's error adds to the
noise's, checked against residuals drawn with a known floor (its coverage, its limit)."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.calibration.waveform import floor_bound


def _residuals(rng, n, phi, sigma=1.0):
    scale = rng.uniform(50.0, 200.0, n)
    return rng.normal(0.0, np.sqrt(sigma**2 + (phi * scale) ** 2)), np.full(n, sigma), scale


def test_the_floor_bound_covers_the_true_floor_at_its_confidence():
    """Ten observations a kind (a calibration's handful of hits): over 1000 draws the 95 %
    bound lies at or above the true floor in 95 % of them (binomial sd 0.7 %)."""
    rng = np.random.default_rng(3)
    phi = 0.02
    hits = [floor_bound(*_residuals(rng, 10, phi), dof=10.0) >= phi for _ in range(1000)]
    assert np.mean(hits) == pytest.approx(0.95, abs=0.02)


def test_the_floor_bound_tends_to_the_true_floor_and_to_zero_without_one():
    """With many observations the bound approaches the floor from above (its relative
    standard error ~ 1/sqrt(2n)); residuals of the noise alone give a floor below the
    noise's own relative size (sigma / scale, 0.5-2 %)."""
    rng = np.random.default_rng(4)
    got = floor_bound(*_residuals(rng, 20000, 0.02), dof=20000.0)
    assert 0.02 <= got < 0.02 * 1.02
    r, sigma, scale = _residuals(rng, 200, 0.0)
    assert floor_bound(r, sigma, scale, dof=200.0) < 5e-3
