"""Fit laws against data made from known laws, the exact sphere and bare-soil Hertz."""

import numpy as np
import pytest

from ssw import hertz
from ssw.curve import ForceCurve
from ssw.errors import ConfigError, OutOfRangeError
from ssw.fit.fitting import fit_curve, scene_inputs
from ssw.fit.laws import LAWS

R = 9.53e-3  # m, the thesis's indenter
E_SOIL, NU_SOIL = 50e6, 0.3
A_H = float(hertz.hertz_coefficient(hertz.effective_modulus(E_SOIL, NU_SOIL), R))
# 1000 increments of 0.1 um, as the thesis's FEM (delta = 0 included, as a real curve has)
DELTA = np.linspace(0.0, 1e-4, 1001)
INPUTS = {"soil_E": E_SOIL, "soil_nu": NU_SOIL, "indenter_radius": R}

# Known parameters with "infinite decimal representations" (meshio's precision advice).
TRUE = {
    "k_hertz": {"K": 1.0 + np.pi / 7.0},
    "power": {"C": 2.0e7 / 3.0, "n": 1.0 + 1.0 / 3.0},
    "two_term": {"k1": 1.0e4 * np.sqrt(2.0), "k2": 6.0e8 / 7.0},
}


def curve_of(F, delta=DELTA, **inputs):
    return ForceCurve(delta, F, np.sqrt(R * delta), inputs={**INPUTS, **inputs})


@pytest.mark.parametrize("weighting", ["absolute", "relative"])
@pytest.mark.parametrize("law", list(LAWS))
def test_fits_recover_known_parameters(law, weighting):
    F = LAWS[law].evaluate(TRUE[law], DELTA, A_H)
    res = fit_curve(curve_of(F), law, weighting=weighting)
    for name, value in TRUE[law].items():
        assert res.params[name] == pytest.approx(value, rel=1e-10, abs=0.0)
    assert res.max_rel_residual < 1e-12


@pytest.mark.parametrize("law", list(LAWS))
def test_fit_on_a_subrange_uses_only_that_range(law):
    # the law holds on [0, 2e-5] m only; beyond, the data are garbage (10x)
    F = LAWS[law].evaluate(TRUE[law], DELTA, A_H)
    F = np.where(DELTA > 2e-5, 10.0 * F, F)
    res = fit_curve(curve_of(F), law, (0.0, 2e-5))
    for name, value in TRUE[law].items():
        assert res.params[name] == pytest.approx(value, rel=1e-10, abs=0.0)
    assert res.delta_hi == pytest.approx(2e-5, rel=1e-12)
    assert res.n_points == 200  # delta = 0.1 .. 20 um; delta = 0 is excluded


def test_exact_hertz_gives_K_one_and_hertz_exponent():
    F = hertz.force(DELTA, hertz.effective_modulus(E_SOIL, NU_SOIL), R)
    assert fit_curve(curve_of(F), "k_hertz").params["K"] == pytest.approx(1.0, rel=1e-12)
    p = fit_curve(curve_of(F), "power").params
    assert p["n"] == pytest.approx(1.5, rel=1e-12)
    assert p["C"] == pytest.approx(A_H, rel=1e-10)
    two = fit_curve(curve_of(F), "two_term").params
    # no linear part: its force at 0.1 mm is below 1e-10 of the Hertz term's
    assert abs(two["k1"] * 1e-4) < 1e-10 * two["k2"] * 1e-4**1.5
    assert two["k2"] == pytest.approx(A_H, rel=1e-10)


@pytest.mark.parametrize("nu", [0.1, 0.3, 0.5])
def test_exact_sphere_gives_K_one_within_half_percent(nu):
    """Sneddon's exact rigid sphere stiffens by O(a^2/R^2) over Hertz; up to 0.1 mm
    (a/R ~ 0.1) K stays within 0.5 % of 1, and tends to 1 on small ranges."""
    a = np.linspace(0.0, np.sqrt(R * 1.01e-4), 2001)
    d, F = hertz.sneddon_sphere(a, hertz.effective_modulus(E_SOIL, nu), R)
    c = ForceCurve(d, F, a, inputs={**INPUTS, "soil_nu": nu})
    K_full = fit_curve(c, "k_hertz", (0.0, 1e-4)).params["K"]
    K_small = fit_curve(c, "k_hertz", (0.0, 1e-5)).params["K"]
    assert abs(K_full - 1.0) < 5e-3
    assert abs(K_small - 1.0) < abs(K_full - 1.0) / 5  # error ~ delta/R: 10x smaller range


def test_E_star_is_the_rigid_indenter_plane_strain_modulus():
    F = hertz.force(DELTA, E_SOIL / (1 - NU_SOIL**2), R)
    res = fit_curve(curve_of(F), "k_hertz")
    assert res.E_star == pytest.approx(E_SOIL / (1 - NU_SOIL**2), rel=1e-15)
    assert res.hertz_coefficient == pytest.approx(4 / 3 * res.E_star * np.sqrt(R), rel=1e-15)


def test_residuals_measure_a_known_misfit():
    # data F = A d^1.5 (1 + d/d0) fitted by K: the relative residual r = K/(1 + d/d0) - 1
    d0 = 1e-4
    F = A_H * DELTA**1.5 * (1 + DELTA / d0)
    res = fit_curve(curve_of(F), "k_hertz")
    sel = DELTA > 0
    r = res.params["K"] / (1 + DELTA[sel] / d0) - 1
    assert res.rms_rel_residual == pytest.approx(np.sqrt(np.mean(r**2)), rel=1e-12)
    assert res.max_rel_residual == pytest.approx(np.max(np.abs(r)), rel=1e-12)


def test_predict_reproduces_the_law():
    F = LAWS["power"].evaluate(TRUE["power"], DELTA, A_H)
    res = fit_curve(curve_of(F), "power")
    assert np.allclose(res.predict(DELTA), F, rtol=1e-10, atol=0)


def test_bad_inputs_raise_named_errors():
    F = hertz.force(DELTA, hertz.effective_modulus(E_SOIL, NU_SOIL), R)
    c = curve_of(F)
    with pytest.raises(ConfigError, match=r"fit\.law"):
        fit_curve(c, "cubic")
    with pytest.raises(OutOfRangeError, match="beyond the curve"):
        fit_curve(c, "k_hertz", (0.0, 2e-4))
    with pytest.raises(OutOfRangeError, match="needs at least"):
        fit_curve(c, "power", (0.0, 1.5e-7))
    with pytest.raises(ConfigError, match="soil_E"):
        fit_curve(ForceCurve(DELTA, F, DELTA, inputs={}), "k_hertz")
    # inputs may be given explicitly, overriding the file's
    assert scene_inputs(c, soil_E=1.0)["soil_E"] == 1.0


def test_power_fit_reaches_the_optimum_where_undamped_gauss_newton_oscillates():
    """A force far from a power law (one that stiffens exponentially, as a soft layer
    bottoming out on a rigid base), fitted with absolute weights over three decades of
    indentation: undamped Gauss-Newton steps from the log-log line overshoot and oscillate
    (60 steps without converging); the damped fit reaches the least-squares optimum. The
    optimum checked independently: for a fixed exponent the best coefficient is linear
    least squares, so the cost's profile over ``n`` on a fine grid brackets the fitted
    ``n``, and the fitted cost is the profile's minimum."""
    d = np.geomspace(1e-6, 1e-3, 60)
    F = np.exp(d / 1e-4)
    p = LAWS["power"].fit(d, F, 1.0, "absolute")

    def profile(n):
        g = d[:, None] ** n[None, :]
        c = (F @ g) / np.sum(g * g, axis=0)
        return np.sum((c * g - F[:, None]) ** 2, axis=0), c

    n = np.linspace(p["n"] - 0.05, p["n"] + 0.05, 20_001)
    cost, _ = profile(n)
    best = n[np.argmin(cost)]
    assert abs(best - p["n"]) <= 2 * (n[1] - n[0])
    fitted = float(np.sum((p["C"] * d ** p["n"] - F) ** 2))
    assert fitted <= cost.min() * (1 + 1e-12)
