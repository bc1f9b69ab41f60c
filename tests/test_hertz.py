"""Hertz laws against textbook identities and an independent ODE integration."""

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from ssw import hertz
from ssw.errors import ConfigError

R = 9.53e-3  # m, the thesis's indenter


def test_rigid_indenter_modulus_is_plane_strain_modulus():
    # Johnson (1985) eq. 4.22 with E2 -> inf: E* = E/(1 - nu^2)
    assert hertz.effective_modulus(100e6, 0.3) == pytest.approx(100e6 / 0.91, rel=1e-15)


def test_identical_spheres_coefficient_matches_reference_formula():
    # REFERENCE.md: A = E sqrt(2R) / (3 (1 - nu^2)) for two identical spheres
    E, nu = 200e9, 0.28
    expected = E * np.sqrt(2 * R) / (3 * (1 - nu**2))
    assert hertz.sphere_sphere_coefficient(E, nu, R) == pytest.approx(expected, rel=1e-14)


def test_pressure_integrates_to_force():
    # p(r) = p0 sqrt(1 - r^2/a^2) must carry the Hertz force: 2 pi int p r dr = F
    Es, d = hertz.effective_modulus(50e6, 0.3), 3e-5
    a = hertz.contact_radius(d, R)
    total, _ = quad(lambda r: 2 * np.pi * r * hertz.pressure_profile(r, d, Es, R), 0, a)
    assert total == pytest.approx(hertz.force(d, Es, R), rel=1e-8)
    # and p0 = 3F / (2 pi a^2)
    p0 = 3 * hertz.force(d, Es, R) / (2 * np.pi * a**2)
    assert hertz.peak_pressure(d, Es, R) == pytest.approx(p0, rel=1e-12)


def test_indentation_inverts_force_and_no_tension():
    Es = hertz.effective_modulus(200e9, 0.28, 200e9, 0.28)
    d = np.array([1e-9, 1e-6, 1e-4])
    assert np.allclose(hertz.indentation(hertz.force(d, Es, R), Es, R), d, rtol=1e-12)
    assert hertz.force(-1e-6, Es, R) == 0.0


@pytest.mark.parametrize("x", [1e-3, 1e-2, 0.05])
def test_sneddon_sphere_reduces_to_hertz(x):
    # Exact sphere vs paraboloid: F/F_H = 1 - x^2/10 + O(x^4), x = a/R (series of Sneddon 1965)
    Es = 1e8
    delta, F = hertz.sneddon_sphere(x * R, Es, R)
    ratio = F / hertz.force(delta, Es, R)
    assert ratio == pytest.approx(1 - x**2 / 10, abs=2 * x**4)


def test_contact_time_constant_and_ode():
    # The Johnson constant: 2 * int_0^1 (1 - s^(5/2))^(-1/2) ds
    integral, _ = quad(lambda s: (1 - s**2.5) ** -0.5, 0, 1)
    assert hertz.HERTZ_TC == pytest.approx(2 * integral, rel=1e-6)
    # and an independent integration of m x'' = -A x^1.5 from x=0, x'=v
    m, A, v = 0.028, 1.2e10, 0.5

    def rhs(t, y):
        return [y[1], -A * max(y[0], 0.0) ** 1.5 / m]

    def leave(t, y):
        return y[0]

    leave.terminal, leave.direction = True, -1
    sol = solve_ivp(rhs, [1e-12, 1e-2], [v * 1e-12, v], events=leave, rtol=1e-11, atol=1e-16)
    assert hertz.contact_time(m, A, v) == pytest.approx(sol.t_events[0][0], rel=1e-6)


def test_bad_input_names_the_field():
    with pytest.raises(ConfigError, match="nu1"):
        hertz.effective_modulus(1e6, 0.7)
    with pytest.raises(ConfigError, match="E1"):
        hertz.effective_modulus(-1e6, 0.3)


def test_energy_indentation_closed_forms_and_upper_end():
    """``(2/5) A d^2.5 - P d = W``: without a load ``(5 W / 2 A)^(2/5)``, without an energy
    the static ``(5 P / 2 A)^(2/3)`` (where the stored energy equals the load's work), and
    with both the root scipy's brentq finds (another method), returned as the upper end of
    its bracket: the contact stores at least ``W + P d`` there."""
    from scipy.optimize import brentq

    A = np.array([3e8, 5e9, 2e10])
    W = np.array([1e-3, 4e-3, 2e-2])
    assert np.allclose(hertz.energy_indentation(A, W), (2.5 * W / A) ** 0.4, rtol=1e-15)
    P = np.array([0.5, 3.0, 40.0])
    assert np.allclose(hertz.energy_indentation(A, 0.0, P), (2.5 * P / A) ** (2 / 3),
                       rtol=1e-14)
    d = hertz.energy_indentation(A, W, P)
    for a, w, p, x in zip(A, W, P, d, strict=True):
        ref = brentq(lambda t, a=a, w=w, p=p: 0.4 * a * t**2.5 - p * t - w, 1e-12, 1.0,
                     xtol=1e-20, rtol=1e-15)
        assert x == pytest.approx(ref, rel=1e-14)
        assert 0.4 * a * x**2.5 - p * x - w >= 0
    with pytest.raises(ConfigError, match="energy"):
        hertz.energy_indentation(A, -1.0)
