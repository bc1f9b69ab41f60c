"""Constitutive models: the consistent tangent (Taylor test, second-order remainder), the
backward-Euler equations of each return, the Drucker-Prager regions (cone, cutoff, apex),
the foam's plastic Poisson's ratio, Hill's thick sphere (first yield, the elastic-plastic
front, collapse) and the registry."""

from __future__ import annotations

import numpy as np
import pytest
from taylor import STEPS, rates, remainders

from ssw.constitutive import (
    CrushableFoam,
    DruckerPrager,
    LinearElastic,
    VonMises,
    model_from,
    model_of_strength,
)
from ssw.constitutive.base import initial_state
from ssw.constitutive.tensors import ONE, P_DEV, bulk_shear, deviator, invariants
from ssw.constitutive.thick_sphere import hill_pressure, solve_sphere
from ssw.errors import ConfigError
from ssw.materials import Strength

E, NU = 50e6, 0.3
MODELS = {
    "von-mises": VonMises(1e6),
    "von-mises-hardening": VonMises(1e6, hardening=5e6),
    "drucker-prager": DruckerPrager(50e3, 30.0, dilatancy_angle=10.0, tension_cutoff=20e3),
    "drucker-prager-apex": DruckerPrager(50e3, 30.0),
    "crushable-foam": CrushableFoam(1e6),
    "crushable-foam-hardening": CrushableFoam(1e6, hardening=3e6, plastic_poisson=0.1),
}


def _points(model, n: int = 4000, seed: int = 1):
    """Strains spread over elastic, plastic and (Drucker-Prager) cutoff and apex states,
    from a random plastic history."""
    rng = np.random.default_rng(seed)
    scale = 4.0 * model.strength / E if np.isfinite(model.strength) else 1e-2
    strain = rng.normal(size=(n, 4)) * scale
    strain[: n // 4] += rng.uniform(-1, 3, size=(n // 4, 1)) * scale * ONE  # hydrostatic
    # near the tension cutoff: a mean stress up to a few strengths, a small deviator
    m = n // 8
    strain[-m:] = (rng.uniform(0, 3, size=(m, 1)) * ONE * scale / 10
                   + 0.05 * scale * rng.normal(size=(m, 4)))
    state = initial_state(n)
    state[:, :4] = 0.3 * scale * rng.normal(size=(n, 4)) @ P_DEV
    state[:, 4] = rng.uniform(0, 0.05, n)
    return strain, state, rng.normal(size=(n, 4)) * scale


@pytest.mark.parametrize("name", list(MODELS))
def test_taylor_remainder_is_second_order(name):
    """|sigma(e + h d) - sigma(e) - h D d| falls 4x per halving of h (the tangent is the
    derivative of the return), where the plain difference falls only 2x; points whose
    region changes within the step (a kink of the return) are left out."""
    model = MODELS[name]
    strain, state, d = _points(model)
    base, r1, r2, same = remainders(model, E, NU, strain, state, d)
    sel = same & base.plastic & (r2[-1] > 1e-6 * r1[-1]) & (r1[-1] > 1e-9 * model.strength)
    assert sel.sum() > 200
    rate1, rate2 = rates(r1, r2, sel)
    assert np.median(rate2) == pytest.approx(2.0, abs=0.05)
    assert np.percentile(rate2, 1) > 1.8
    assert np.median(rate1) == pytest.approx(1.0, abs=0.05)
    # the elastic tangent in place of the consistent one is first order: the test can fail
    K, G = bulk_shear(E, NU)
    Ce = K * np.outer(ONE, ONE) + 2 * G * P_DEV
    wrong = np.linalg.norm(model.update(E, NU, strain + STEPS[-1] * d, state).stress
                           - base.stress - STEPS[-1] * d @ Ce, axis=1)[sel]
    assert np.median(wrong / r2[-1, sel]) > 10


def _flow_direction(model, stress):
    """The normal of the flow potential at the returned stress (an independent formula)."""
    p, _ = invariants(stress)
    _, n = deviator(stress @ P_DEV)
    s = stress @ P_DEV
    if isinstance(model, VonMises):
        return s
    if isinstance(model, DruckerPrager):
        eta_b = model.constants[2]
        return n / np.sqrt(2.0) + eta_b / 3.0 * ONE
    a2 = model.alpha ** 2
    return 3.0 * s + (2.0 * a2 / 3.0) * p[:, None] * ONE


@pytest.mark.parametrize("name", ["von-mises", "von-mises-hardening", "drucker-prager",
                                  "crushable-foam", "crushable-foam-hardening"])
def test_return_solves_backward_euler(name):
    """The returned stress is C (eps - eps_p), on the (hardened) yield surface, and the
    plastic strain increment points along the flow potential's normal there."""
    model = MODELS[name]
    strain, state, _ = _points(model, seed=2)
    up = model.update(E, NU, strain, state)
    K, G = bulk_shear(E, NU)
    Ce = K * np.outer(ONE, ONE) + 2 * G * P_DEV
    np.testing.assert_allclose(up.stress, (strain - up.state[:, :4]) @ Ce,
                               atol=1e-9 * model.strength)
    sel = up.region == 1
    assert sel.sum() > 500
    np.testing.assert_allclose(model.yield_ratio(up.stress, up.state)[sel], 1.0, rtol=1e-9)
    dep = (up.state[:, :4] - state[:, :4])[sel]
    m = _flow_direction(model, up.stress[sel])
    cos = np.einsum("ni,ni->n", dep, m) / np.linalg.norm(dep, axis=1) / np.linalg.norm(m,
                                                                                        axis=1)
    np.testing.assert_allclose(cos, 1.0, atol=1e-9)
    elastic = ~up.plastic
    np.testing.assert_array_equal(up.state[elastic], state[elastic])
    assert np.all(model.yield_ratio(up.stress, up.state)[elastic] <= 1.0 + 1e-12)


def test_drucker_prager_regions():
    """Cone, cutoff and apex each served; a hydrostatic tension beyond the apex returns to
    the apex stress ``p = xi c / eta``, beyond the cutoff to ``p = t`` with the deviator
    kept while inside the cone."""
    apex = MODELS["drucker-prager-apex"]
    eta, xi, _, t = apex.constants
    assert t == pytest.approx(xi * apex.cohesion / eta)
    K, _ = bulk_shear(E, NU)
    strain = np.array([[1.0, 1.0, 1.0, 0.0]]) * 3 * t / (3 * K)  # p_tr = 3 t
    strain = strain + np.array([[1e-5, -1e-5, 0, 0]])
    up = apex.update(E, NU, strain, initial_state(1))
    assert up.region[0] == 3
    np.testing.assert_allclose(up.stress, t * ONE[None], rtol=1e-12)
    np.testing.assert_allclose(up.tangent, 0.0, atol=1e-12 * E)
    cut = MODELS["drucker-prager"]
    _, _, _, tc = cut.constants
    strain = np.array([[1.0, 1.0, 1.0, 0.0]]) * 2 * tc / (3 * K) + np.array([[1e-6, 0, 0, 0]])
    up = cut.update(E, NU, strain, initial_state(1))
    p, q = invariants(up.stress)
    assert up.region[0] == 2 and p[0] == pytest.approx(tc)
    assert q[0] == pytest.approx(invariants(strain @ (K * np.outer(ONE, ONE) + E / (1 + NU)
                                                      * P_DEV))[1][0])
    strain, state, _ = _points(cut, seed=3)
    assert set(np.unique(cut.update(E, NU, strain, state).region)) == {0, 1, 2, 3}


@pytest.mark.parametrize("match", ["outer", "inner"])
def test_drucker_prager_cones_pass_through_mohr_coulomb_meridians(match):
    """Mohr-Coulomb in principal stresses (tension positive, ``s1 >= s2 >= s3``; de Souza
    Neto, Peric & Owen 2008, ch. 6): ``(s1 - s3) + (s1 + s3) sin(phi) = 2 c cos(phi)``. Under
    a confining pressure ``s`` the deviator at failure is then

        ``q = 2 (c cos(phi) + s sin(phi)) / (1 - sin(phi))``

    on both meridians: triaxial compression (``s1 = s2 = -s``, ``s3 = -s - q``; the stress
    under an indenter's axis) and triaxial extension (``s1 = -s``, ``s2 = s3 = -s - q``).
    The outer cone passes through the first, the inner through the second: the model's
    yield ratio is 1 at these stresses, computed here from Mohr-Coulomb alone, over
    confinements from 0 to 30 cohesions; at ``s = 0`` the compressive one is the unconfined
    compressive strength the model reports."""
    c, phi = 30e3, 35.0
    dp = DruckerPrager(c, phi, match=match)
    sin_p, cos_p = np.sin(np.radians(phi)), np.cos(np.radians(phi))
    s = np.array([0.0, 0.3, 3.0, 30.0]) * c
    q = 2.0 * (c * cos_p + s * sin_p) / (1.0 - sin_p)
    if match == "outer":  # (rr, zz, tt, sqrt2 rz): the axis of z the most compressive
        stress = np.column_stack([-s, -s - q, -s, np.zeros_like(s)])
    else:  # r and t the most compressive
        stress = np.column_stack([-s - q, -s, -s - q, np.zeros_like(s)])
    np.testing.assert_allclose(dp.yield_ratio(stress, initial_state(s.size)), 1.0,
                               rtol=1e-12)
    if match == "outer":
        assert dp.strength == pytest.approx(q[0], rel=1e-14)


@pytest.mark.parametrize("nu_p", [0.0, 0.2])
def test_foam_uniaxial_crushing(nu_p):
    """A uniaxial-stress compression (the lateral stresses held at zero by Newton's method
    on the lateral strains with the consistent tangent) plateaus at ``-Y`` and crushes with
    the plastic Poisson's ratio ``nu_p`` (Deshpande & Fleck 2000, eq. 2.7)."""
    foam = CrushableFoam(1e6, plastic_poisson=nu_p)
    state = initial_state(1)
    lateral = 0.0
    for ez in np.linspace(0, -0.1, 41)[1:]:
        for _ in range(30):
            eps = np.array([[lateral, ez, lateral, 0.0]])
            up = foam.update(E, NU, eps, state)
            res = up.stress[0, 0] + up.stress[0, 2]
            if abs(res) < 1e-9 * foam.strength:
                break
            D = up.tangent[0]
            lateral -= res / (D[0, 0] + D[0, 2] + D[2, 0] + D[2, 2])
        state = up.state
    assert up.stress[0, 1] == pytest.approx(-foam.strength, rel=1e-9)
    ep = state[0, :4]
    assert -ep[0] / ep[1] == pytest.approx(nu_p, abs=1e-9)


def test_hill_thick_sphere():
    """Hill (1950): inner pressure at first yield (2Y/3)(1 - a^3/b^3), the elastic-plastic
    front's pressure 2Y ln(c/a) + (2Y/3)(1 - c^3/b^3), collapse 2Y ln(b/a)."""
    Y, a, b = 1e6, 1.0, 2.0
    model = VonMises(Y)
    path = solve_sphere(model, 100e6, 0.3, a, b, np.linspace(0, 0.05, 101)[1:],
                        elements=100)
    py, pc = hill_pressure(a, a, b, Y), 2 * Y * np.log(b / a)
    k = int(np.argmax(path.plastic.any(axis=1)))
    assert path.p[k - 1] < py <= path.p[k]
    # last elastic increment scaled to the yield surface (the sphere is linear until then)
    assert path.p[k - 1] / path.yield_ratio[k - 1] == pytest.approx(py, rel=5e-3)
    hs = path.r_gauss[1] - path.r_gauss[0]
    for j in range(k + 1, len(path.p)):
        pl = path.plastic[j]
        i = int(np.flatnonzero(~pl)[0]) if not pl.all() else pl.size
        assert pl[:i].all()  # one plastic zone from the inner face
        if i == pl.size:
            continue
        c = 0.5 * (path.r_gauss[i - 1] + path.r_gauss[i])
        bound = abs(hill_pressure(c + hs, a, b, Y) - hill_pressure(c, a, b, Y))
        assert abs(path.p[j] - hill_pressure(c, a, b, Y)) <= bound + 2e-3 * pc
    assert np.all(np.diff(path.p) > 0)
    assert path.p[-1] == pytest.approx(pc, rel=1e-4)
    assert path.p.max() <= pc * (1 + 1e-9)


def test_registry():
    assert model_from(None) is None
    assert model_from({"model": "linear-elastic"}) is None
    vm = model_from({"model": "von-mises", "yield_stress": 2e6})
    assert vm == VonMises(2e6) and vm.key == "vm-Y2MPa"
    assert hash(vm) == hash(VonMises(2.0e6))
    assert model_from({"model": "drucker-prager", "cohesion": 20e3, "friction_angle": 30}
                      ).key == "dp-c20kPa-phi30"
    with pytest.raises(ConfigError, match=r"soil_model\.model"):
        model_from({"model": "cam-clay"})
    with pytest.raises(ConfigError, match=r"soil_model\.friction"):
        model_from({"model": "von-mises", "yield_stress": 1e6, "friction": 3})
    with pytest.raises(ConfigError, match="yield_stress"):
        VonMises(-1.0)
    st = Strength(compressive=2.2e6, source="catalogue")
    assert model_of_strength("crushable-foam", st) == CrushableFoam(2.2e6)
    with pytest.raises(ConfigError, match="cohesion"):
        model_of_strength("drucker-prager", st, "materials.pcf08")
    el = LinearElastic().update(E, NU, np.ones((3, 4)), initial_state(3))
    assert not el.plastic.any()


def test_library_strengths():
    """Every foam grade has a sourced compressive strength rising with density (the
    Gibson-Ashby scaling of a cellular solid's plateau stress, roughly rho^1.5-2); the
    compacted soils have Mohr-Coulomb strengths inside the typical ranges, and each builds
    its model from the library (not fitted)."""
    from ssw.materials import material_set

    lib = material_set("realistic")
    foams = sorted((m.density, m.strength.compressive, k) for k, m in lib.items()
                   if k.startswith("pcf"))
    assert len(foams) == 8 and all(s is not None for _, s, _ in foams)
    rho, sig = np.array([f[0] for f in foams]), np.array([f[1] for f in foams])
    assert np.all(np.diff(sig) > 0)
    slope = np.polyfit(np.log(rho), np.log(sig), 1)[0]
    assert 1.3 < slope < 2.2
    for _, _, k in foams:
        assert "F1839" in lib[k].strength.source
        assert model_of_strength("crushable-foam", lib[k].strength).strength \
            == lib[k].strength.compressive
    clay, sand = lib["compacted_clay"].strength, lib["compacted_sand"].strength
    assert 10e3 <= clay.cohesion <= 100e3 and 20 <= clay.friction_angle <= 30
    assert sand.cohesion <= 10e3 and 35 <= sand.friction_angle <= 42
    assert model_of_strength("drucker-prager", clay).key == "dp-c50kPa-phi25-psi0"


def test_yield_index():
    """Hertz's p0 of a force and back (F = 2/3 pi a^2 p0, a = pi p0 R / (2 E*)), and the
    first-yield flag at Johnson's p0 = 1.61 Y (nu 0.3)."""
    from ssw.constitutive.yield_index import first_yield_ratio, yield_index

    E_, nu, R_, Y_ = 38e6, 0.3, 4.75e-3, 1.4e6
    assert first_yield_ratio(0.3) == pytest.approx(1.61, abs=0.005)
    assert first_yield_ratio(0.45) == pytest.approx(1.81, abs=0.01)
    F = np.array([0.1, 1.0, 10.0])
    out = yield_index(F, E_, nu, R_, Y_)
    a = np.pi * out["p0"] * R_ / (2 * E_ / (1 - nu * nu))
    np.testing.assert_allclose(2 / 3 * np.pi * a * a * out["p0"], F, rtol=1e-12)
    np.testing.assert_array_equal(out["first_yield"], out["index"] > first_yield_ratio(nu))


def test_plate_strengths_and_hardening():
    """The plate materials carry a sourced yield stress and linear hardening modulus (the
    uncertain ones marked [U]); the secant hardening from yield to the tensile strength over
    the elongation lies between 0 and (UTS - Y) / 0.1 (a plastic strain of at least 10 %
    for the metals); the von Mises model takes them; a negative hardening is refused naming
    the field."""
    from ssw.errors import ConfigError
    from ssw.materials import Strength, material_set

    lib = material_set("realistic")
    for key, Y in (("pla", 50e6), ("al6061", 276e6), ("a36", 250e6)):
        st = lib[key].strength
        assert st.yield_stress == Y and st.hardening is not None and "[U" in st.source
        m = model_of_strength("von-mises", st)
        assert (m.yield_stress, m.hardening) == (st.yield_stress, st.hardening)
        if key != "pla":
            assert 0 < st.hardening <= (st.tensile - st.yield_stress) / 0.1 * 1.01
    assert model_of_strength("von-mises", lib["al6061"].strength).key == "vm-Y276MPa-H290MPa"
    with pytest.raises(ConfigError, match=r"materials\.x\.strength\.hardening"):
        Strength(yield_stress=1e6, hardening=-1.0, source="s").check("x")
