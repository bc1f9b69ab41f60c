"""The model-error term's estimator (:mod:`ssw.calibration.model_error`) against statistics'
own truth: the upper confidence bound covers the true model error at its confidence when the
residuals are a least-squares fit's (``n - p`` degrees of freedom), and the rejection gate is
the chi^2 law's quantile."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.calibration.model_error import (
    FLOOR_CONFIDENCE,
    REJECT_QUANTILE,
    chi2_cdf,
    floor_bound,
    rejects,
)


def _fitted(rng: np.random.Generator, A: np.ndarray, sigma: np.ndarray, scale: np.ndarray,
            phi: float) -> np.ndarray:
    """Residuals of a weighted linear least squares (weights the true total variances) of
    data ``A theta + e``, ``e_i ~ N(0, sigma_i^2 + phi^2 scale_i^2)``."""
    var = sigma**2 + (phi * scale) ** 2
    y = A @ np.array([1.0, -0.5][: A.shape[1]]) + rng.normal(size=A.shape[0]) * np.sqrt(var)
    w = 1.0 / np.sqrt(var)
    theta = np.linalg.lstsq(A * w[:, None], y * w, rcond=None)[0]
    return y - A @ theta


@pytest.mark.parametrize(("n", "p"), [(3, 1), (3, 2), (6, 2)])
def test_the_bound_covers_the_model_error_of_a_fit_at_its_confidence(n, p):
    """Equal variances: ``sum r^2 / (sigma^2 + phi^2 s^2)`` of a fit's residuals is chi^2 with
    ``n - p`` degrees of freedom (Cochran's theorem), so the bound at ``n - p`` covers the
    true ``phi`` with probability FLOOR_CONFIDENCE exactly: 2000 draws, within 4 binomial
    standard deviations. With one or two degrees of freedom (a TOF calibration's three
    references, one or two parameters) the bound is several times the point estimate."""
    rng = np.random.default_rng(20 + n + p)
    A = np.column_stack([np.ones(n), np.linspace(-1.0, 1.0, n)])[:, :p]
    sigma, scale, phi = np.full(n, 1e-3), np.full(n, 1.0), 0.01
    draws = 2000
    hits = sum(floor_bound(_fitted(rng, A, sigma, scale, phi), sigma, scale, n - p) >= phi
               for _ in range(draws))
    band = 4.0 * np.sqrt(FLOOR_CONFIDENCE * (1 - FLOOR_CONFIDENCE) / draws)
    assert hits / draws == pytest.approx(FLOOR_CONFIDENCE, abs=band)


def test_the_bound_is_conservative_with_unequal_noise_and_scales():
    """TOF-like data: the references' TOFs (scales 1.2-1.8 ms) with noise of 0.1-0.3 % and a
    1 % model error, a straight line fitted: the bound still covers at least at its
    confidence, within the Monte Carlo's band (the pivot is then only near chi^2)."""
    rng = np.random.default_rng(7)
    T = np.array([1.8e-3, 1.45e-3, 1.2e-3])
    sigma = np.array([3e-3, 1e-3, 2e-3]) * T
    A = np.column_stack([np.ones(3), np.log([38.0, 123.0, 445.0])])[:, :1]
    draws = 2000
    hits = sum(floor_bound(_fitted(rng, A * T[:, None], sigma, T, 0.01), sigma, T, 2) >= 0.01
               for _ in range(draws))
    band = 4.0 * np.sqrt(FLOOR_CONFIDENCE * (1 - FLOOR_CONFIDENCE) / draws)
    assert hits / draws >= FLOOR_CONFIDENCE - band


def test_the_gate_is_the_chi2_laws_quantile():
    """3.84 and 5.99 are chi^2's 95 % quantiles for 1 and 2 degrees of freedom (tables):
    the references reject the model just above them, not just below; without a degree of
    freedom nothing is rejected."""
    assert REJECT_QUANTILE == 0.95
    assert chi2_cdf(3.8415, 1) == pytest.approx(0.95, abs=1e-4)
    assert chi2_cdf(5.9915, 2) == pytest.approx(0.95, abs=1e-4)
    assert rejects(3.90, 1) and not rejects(3.80, 1)
    assert rejects(6.05, 2) and not rejects(5.95, 2)
    assert not rejects(1e6, 0)
    # the study's calibration: chi^2 1.23 on 1 degree of freedom is not rejected
    assert not rejects(1.2309, 1)
