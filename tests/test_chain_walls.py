"""Wall laws: equivalences that hold exactly, the table's interpolation and extension."""

from __future__ import annotations

import numpy as np
import pytest

from ssw.chain.params import ChainParams
from ssw.chain.wall import TABLE_CELLS, compliance_scale
from ssw.curve import ForceCurve, write_curve
from ssw.errors import ConfigError
from ssw.hertz import effective_modulus, hertz_coefficient
from ssw.tof import api
from ssw.walls import build_wall

P = ChainParams(striker_velocity=0.5246)
E = np.array([38e6, 445e6])
NU = np.array([0.34, 0.30])


def _rigid_sphere_hertz_curve(E_s: float, nu_s: float, d_max: float, n: int = 101
                              ) -> ForceCurve:
    """What the FEM gives without a plate: F = 4/3 E/(1-nu^2) sqrt(R) d^1.5 (rigid sphere)."""
    d = np.linspace(0.0, d_max, n)
    F = 4 / 3 * E_s / (1 - nu_s**2) * np.sqrt(P.bead_radius) * d**1.5
    return ForceCurve(delta=d, force=F, contact_radius=np.sqrt(P.bead_radius * d))


def test_fit_wall_with_K_1_is_the_hertz_wall():
    np.testing.assert_allclose(api.tof(E, NU, P, "fit", K=1.0), api.tof(E, NU, P, "hertz"),
                               rtol=1e-12)


def test_power_law_wall_of_the_rigid_sphere_hertz_law_is_the_hertz_wall():
    """C = 4/3 E_s/(1-nu_s^2) sqrt(R), n = 1.5 with the bead's compliance added through
    s = (1 + c_b/c_s)^(2/3) gives exactly A_w = 4/3 sqrt(R) / (c_s + c_b)."""
    C = 4 / 3 * E / (1 - NU**2) * np.sqrt(P.bead_radius)
    w = build_wall("fit", P, E, NU, power=(C, 1.5))
    A_w = hertz_coefficient(effective_modulus(P.bead_E, P.bead_nu, E, NU), P.bead_radius)
    np.testing.assert_allclose(w.coef, A_w, rtol=1e-12)


@pytest.mark.parametrize("d_max", [1.0e-4, 1.0e-3])
def test_table_wall_of_a_hertz_curve_is_the_hertz_wall(tmp_path, d_max):
    """A tabulated Hertz curve reproduces the Hertz wall: inside the table (g = F/d^1.5 is
    constant, so interpolation is exact) and beyond it (the extension's exponent is the
    curve's log-log slope, 1.5). With d_max = 0.1 mm (the thesis's FEM range) the chain's
    peak indentation (0.1-0.3 mm) lies beyond the table."""
    paths = []
    for k, (e, n) in enumerate(zip(E, NU, strict=True)):
        paths.append(tmp_path / f"c{k}.h5")
        write_curve(paths[-1], _rigid_sphere_hertz_curve(e, n, d_max))
    t_tab = api.tof(E, NU, P, "table", curve=[str(p) for p in paths])
    np.testing.assert_allclose(t_tab, api.tof(E, NU, P, "hertz"), rtol=1e-9)


def test_table_interpolates_a_non_hertz_curve_linearly_in_F_over_d15():
    """For F = c d^2 (not Hertz), g = F/d^1.5 = c d^0.5 is interpolated on a grid of
    TABLE_CELLS cells; the force error stays below the interpolation bound of sqrt."""
    d = np.linspace(0, 2e-4, 201)
    curve = ForceCurve(delta=d, force=1e9 * d**2, contact_radius=np.sqrt(P.bead_radius * d))
    w = build_wall("table", P, 1.0, 0.3, curve=curve)  # 1 Pa: bead compliance negligible
    x = np.linspace(1e-6, 2e-4, 37)
    F = np.array([w.force(np.array([xi]))[0] for xi in x])
    exact = 1e9 * x**2
    h = 2e-4 / TABLE_CELLS
    assert np.max(np.abs(F / exact - 1)) < 0.5 * h / x.min() + 1e-6
    # extension: the slope of the last 10 % is 2, so F continues as d^2
    far = w.force(np.array([4e-4]))[0]
    assert far == pytest.approx(1e9 * (4e-4) ** 2, rel=1e-3)
    # statics inverse of the tabulated law
    np.testing.assert_allclose(w.force(w.indentation(np.array([3.0]))), 3.0, rtol=1e-9)


def test_compliance_scale_is_the_hertz_combination():
    s = compliance_scale(P, 38e6, 0.34)
    c_s, c_b = (1 - 0.34**2) / 38e6, P.bead_compliance
    assert s == pytest.approx((1 + c_b / c_s) ** (2 / 3), rel=1e-14)


def test_stiffer_contact_shortens_tof():
    """K > 1 (a plate spreading the load) makes the last contact stiffer: shorter TOF."""
    t1, t2 = api.tof(38e6, 0.34, P, "fit", K=[1.0, 2.0][0]), api.tof(38e6, 0.34, P, "fit", K=2.0)
    assert t2 < t1


def test_wall_errors_name_the_field():
    with pytest.raises(ConfigError, match="wall"):
        build_wall("soft", P, 1e7, 0.3)
    with pytest.raises(ConfigError, match="exactly one"):
        build_wall("fit", P, 1e7, 0.3)
    with pytest.raises(ConfigError, match="soil_nu"):
        build_wall("hertz", P, 1e7, 0.7)
    with pytest.raises(ConfigError, match="k-table"):
        build_wall("fit", P, 1e7, 0.3, k_table="/nonexistent/k_table.h5")


class _HertzKTable:
    """A K table of the bare soil (no plate): K = 1, power law C = 4/3 E/(1-nu^2) sqrt(R)."""

    def K(self, E, nu):
        return np.ones_like(np.asarray(E, float))

    def power(self, E, nu):
        E, nu = np.asarray(E, float), np.asarray(nu, float)
        return 4 / 3 * E / (1 - nu**2) * np.sqrt(P.bead_radius), np.full(E.shape, 1.5)


def test_a_k_table_file_is_read_once_per_version(tmp_path):
    """Building the fit wall again (a calibration's root search, an inverse) does not read
    the K table file again; a rewritten file is read anew and its values are used."""
    import os

    from ssw.fit.table import KTable, write_tables
    from ssw.walls import load_k_table

    def table(K):
        Eg, nug = np.array([30e6, 500e6]), np.array([0.3, 0.35])
        ones = np.ones((2, 2))
        res = {"rms_rel_residual": 0 * ones, "max_rel_residual": 0 * ones}
        return KTable("pla", P.plate_thickness, 9.53e-3, Eg, nug, {"k_hertz": {"K": K * ones}},
                      {"k_hertz": res}, 1e-7 * ones, 1e-4 * ones)

    path = tmp_path / "k_table.h5"
    write_tables([table(1.5)], path, None, {})
    first = load_k_table(str(path), P)
    assert load_k_table(str(path), P) is first
    write_tables([table(2.0)], path, None, {})
    os.utime(path, ns=(1, 1))  # a new version even within the clock's resolution
    again = load_k_table(str(path), P)
    assert again is not first
    assert again.K(100e6, 0.32) == pytest.approx(2.0)
    w = build_wall("fit", P, 100e6, 0.32, k_table=str(path))
    w1 = build_wall("fit", P, 100e6, 0.32, K=2.0)
    np.testing.assert_allclose(w.force(np.array([[5e-5]])), w1.force(np.array([[5e-5]])))


def test_the_fused_tangent_of_a_piecewise_law_is_its_three_methods_to_the_bit():
    """The integrator's step with sensitivities reads the fem wall's force, stiffness and
    dF/dE from one search of its pieces (``force_and_tangent``): the same numbers as the
    three methods, at indentations inside pieces, on breakpoints, beyond the exact law and
    at and below zero; a power law (no fused method) gives its three methods."""
    from ssw.chain.wall import PowerWall, force_and_tangent
    from ssw.walls.fem import PiecewiseLinearWall

    rng = np.random.default_rng(11)
    n, K = 4, 9
    d = np.concatenate([np.zeros((n, 1)), np.cumsum(rng.uniform(1e-6, 3e-6, (n, K)), 1)], 1)
    b = np.cumsum(rng.uniform(1e5, 5e5, (n, K + 1)), 1)  # stiffening pieces
    F = np.concatenate([np.zeros((n, 1)), np.cumsum(b[:, :-1] * np.diff(d, axis=1), 1)], 1)
    a = F - b * d
    wall = PiecewiseLinearWall(d, a, b, np.zeros_like(d), d[:, -1],
                               da_dE=rng.normal(size=(n, K + 1)) * 1e-9,
                               db_dE=rng.normal(size=(n, K + 1)) * 1e-3)
    for at in (np.array([-1e-6, 0.0, 1.3e-6, 5e-5]), d[:, 3].copy(), 0.999 * d[:, -1],
               rng.uniform(0, 1.2, n) * d[:, -1]):
        f, kd, kE = force_and_tangent(wall, at, True)
        assert np.array_equal(f, wall.force(at)) and np.array_equal(kd, wall.dforce_dd(at))
        assert np.array_equal(kE, wall.dforce_dE(at))
        f2, kd2, none = force_and_tangent(wall, at, False)
        assert none is None and np.array_equal(f2, f) and np.array_equal(kd2, kd)
    # the law is continuous: the force at a breakpoint is both pieces' value
    at = d[:, 4]
    assert np.allclose(wall.force(at), F[:, 4], rtol=1e-12)
    power = PowerWall(np.full(n, 2e9), np.full(n, 1.5), dcoef_dE=np.full(n, 10.0))
    at = np.array([-1e-6, 0.0, 2e-6, 4e-5])
    f, kd, kE = force_and_tangent(power, at, True)
    assert np.array_equal(f, power.force(at)) and np.array_equal(kd, power.dforce_dd(at))
    assert np.array_equal(kE, power.dforce_dE(at))
