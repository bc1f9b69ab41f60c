"""Stress grid of the modified-Hertz fits: soils of 1 MPa..10 GPa, nu 0.49-0.5,
indentations from 1e-9 m, degenerate curves.

Truth: a synthetic curve built from a law is recovered exactly by a fit of that law (to
rounding: 1e-10 relative over five decades of indentation); a curve with nothing to fit
(no positive force) stops with an ssw error that says so (checked); a law that does not fit
says so through its residual instead of returning a plausible-looking number.
"""

from __future__ import annotations

import numpy as np
import pytest

from ssw import hertz
from ssw.curve import ForceCurve
from ssw.errors import OutOfRangeError, SswError
from ssw.fit.fitting import fit_curve

R = 9.53e-3  # m
DELTA = np.geomspace(1.0e-9, 1.0e-4, 200)  # m, five decades down to 1 nm
RTOL = 1e-10


#: Seconds any one case may take before it counts as a hang (the slowest takes ~5 s).
CASE_TIMEOUT_S = 60


pytestmark = pytest.mark.usefixtures("no_hang")  # tests/conftest.py


def _curve(force: np.ndarray, soil_E: float = 50.0e6, soil_nu: float = 0.3) -> ForceCurve:
    return ForceCurve(DELTA, force, np.sqrt(R * DELTA),
                      inputs={"soil_E": soil_E, "soil_nu": soil_nu, "indenter_radius": R})


@pytest.mark.parametrize("soil_E", [1.0e6, 1.0e10])
@pytest.mark.parametrize("soil_nu", [0.49, 0.5])
def test_exact_modified_hertz_is_recovered(soil_E: float, soil_nu: float) -> None:
    """F = K 4/3 E* sqrt(R) d^1.5 with K = 2.3: k_hertz gives K, power gives (K A, 1.5)."""
    A = float(hertz.hertz_coefficient(hertz.effective_modulus(soil_E, soil_nu), R))
    c = _curve(2.3 * A * DELTA**1.5, soil_E, soil_nu)
    k = fit_curve(c, "k_hertz")
    assert k.params["K"] == pytest.approx(2.3, rel=RTOL)
    assert k.max_rel_residual < RTOL
    p = fit_curve(c, "power")
    assert p.params["n"] == pytest.approx(1.5, rel=RTOL)
    assert p.params["C"] == pytest.approx(2.3 * A, rel=1e-8)
    assert np.all(np.isfinite(p.predict(DELTA)))


def test_exact_power_law_is_recovered() -> None:
    """F = 3 d^1.2 (N, m): the power fit returns C = 3, n = 1.2."""
    p = fit_curve(_curve(3.0 * DELTA**1.2), "power")
    assert (p.params["C"], p.params["n"]) == (pytest.approx(3.0, rel=1e-8),
                                              pytest.approx(1.2, rel=RTOL))


def test_a_law_that_does_not_fit_says_so() -> None:
    """k_hertz on a d^1.2 curve cannot fit: its largest relative residual is large (> 50 %),
    so the misfit is visible in the result, not hidden behind a finite K."""
    k = fit_curve(_curve(3.0 * DELTA**1.2), "k_hertz")
    assert np.isfinite(k.params["K"])
    assert k.max_rel_residual > 0.5


@pytest.mark.parametrize("force", [np.zeros(DELTA.size), -DELTA**1.5],
                         ids=["no-force", "tension"])
@pytest.mark.parametrize("law", ["k_hertz", "power"])
def test_curves_without_contact_are_refused(force: np.ndarray, law: str) -> None:
    """No positive force anywhere: nothing to fit, an ssw error saying so (not K = 0 or
    NaN): no point with d > 0 and F > 0 in the fit range."""
    with pytest.raises(OutOfRangeError, match=r"only 0 points with delta > 0 and F > 0"):
        fit_curve(_curve(force), law)


def test_nan_force_is_refused_when_the_curve_is_built() -> None:
    """A NaN in a curve never reaches a fit: ForceCurve refuses it."""
    f = DELTA**1.5
    f[10] = np.nan
    with pytest.raises(SswError, match="finite"):
        _curve(f)
